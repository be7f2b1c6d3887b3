// core: compile-time bounds. Every array in firmware_lib is sized from one of these; algorithms are
// templates over a Bounds type. The defaults are a controller-class configuration (Cortex-M4F, about
// 128 KiB RAM); the host instantiates larger ones for benchmarks.
#pragma once

#include <cstdint>

namespace geojcbb {

/// The one type of every JCBB node count and budget: CONFIG's node_budget on the wire, the
/// strategy's and the association's options, the search's counter and the diagnostics.
using NodeCount = std::uint32_t;

/// @tparam MaxObservations  observations in one scan (M)
/// @tparam MaxCandidates    map features offered to one association call (n, after the local region)
/// @tparam MaxGroups        observation groups (clustering, grouped association)
/// @tparam MaxJcbbNodes     JCBB interpretation-tree nodes per scan (the worst-case cost of a scan)
/// @tparam MaxLandmarks     landmarks in the EKF map
template <int MaxObservations, int MaxCandidates, int MaxGroups, NodeCount MaxJcbbNodes, int MaxLandmarks>
struct Bounds {
  static constexpr int kMaxObservations = MaxObservations;
  static constexpr int kMaxCandidates = MaxCandidates;
  static constexpr int kMaxGroups = MaxGroups;
  static constexpr NodeCount kMaxJcbbNodes = MaxJcbbNodes;
  static constexpr int kMaxLandmarks = MaxLandmarks;
  /// Rows of a joint innovation: two per pairing, at most one pairing per observation.
  static constexpr int kMaxJointRows = 2 * MaxObservations;

  static_assert(MaxObservations >= 1 && MaxObservations <= 127, "observation index must fit int8");
  static_assert(MaxCandidates >= 1 && MaxCandidates <= 32767, "candidate index must fit int16");
  static_assert(MaxCandidates <= MaxLandmarks, "candidates are a subset of the map");
  static_assert(MaxGroups >= 1 && MaxGroups <= MaxObservations, "a group holds at least one observation");
  static_assert(MaxJcbbNodes >= 1, "JCBB needs a node budget");
};

/// Controller-class default: 24 observations per scan, 32 candidates in the local region, 5 groups,
/// 4000 JCBB nodes per scan, 96 landmarks in the map. The float device loop at these bounds
/// (node::Node, all memory static) needs about 119 KB of RAM and fits, with a 4 KiB stack, in
/// 128 KiB (packed covariance: packed covariance P, packed C in the Prediction, O(n)
/// update scratch; the covariance still grows as (3 + 2N)(4 + 2N)/2 floats, and at most 100
/// landmarks fit).
/// See docs/firmware.md, "Configurations".
using DefaultBounds = Bounds<24, 32, 5, 4000, 96>;

/// The Cortex-M4F firmware's other configurations (firmware_lib/port/mps2_an386, docs/firmware.md):
/// a smaller part, and a large one with the desktop device's capacity (a whole env1 lap fits).
using SmallControllerBounds = Bounds<16, 24, 4, 2000, 32>;
using LargeControllerBounds = Bounds<24, 64, 5, 20000, 200>;

/// An image may leave the hypothesis window and clusters first out at every bounds: the 128 KiB
/// default Cortex-M4F image does (its port defines GEOJCBB_WITHOUT_HYPOTHESES), to make room for the
/// local map's hand-over (docs/firmware.md, "Configurations").
#ifdef GEOJCBB_WITHOUT_HYPOTHESES
inline constexpr bool kImageHypotheses = false;
#else
inline constexpr bool kImageHypotheses = true;
#endif
/// And the duplicate merge (StepSettings::duplicate_merge_d2: off by default, and measured to merge
/// no true duplicate that the existence rule leaves, only false ones: docs/results/existence.md): the
/// default image leaves it out (GEOJCBB_WITHOUT_DUPLICATE_MERGE) to make room for the local map's
/// seed (SUBMAP_SEED).
#ifdef GEOJCBB_WITHOUT_DUPLICATE_MERGE
inline constexpr bool kImageDuplicateMerge = false;
#else
inline constexpr bool kImageDuplicateMerge = true;
#endif

/// And the world model (docs/design.md, "The world model": the motion test, the movers, the learned
/// detection and clutter; all off by default): the 128 KiB images leave it out
/// (GEOJCBB_WITHOUT_WORLD_MODEL) until room is made for its 20 bytes a landmark and 6 KB of code.
#ifdef GEOJCBB_WITHOUT_WORLD_MODEL
inline constexpr bool kImageWorldModel = false;
#else
inline constexpr bool kImageWorldModel = true;
#endif

/// The optional stages a configuration compiles in. The hypothesis window and clusters first
/// (StepSettings::hypothesis_rivals, cluster_first: about 7 KB of Cortex-M4 code) and the local
/// map's hand-over (StepSettings::submap_*, node::Node's SUBMAP frames, ekf::Slam::restart: about
/// 10 KB) are left out of the small controller's image, which cannot hold them and the rest in
/// 128 KiB of flash; there node::SlamStep::configure refuses their options (kInvalidInput), on the
/// device and on the host.
template <class B>
struct OptionalStages {
  static constexpr bool kHypotheses = kImageHypotheses;          ///< the hypothesis window and clusters first
  static constexpr bool kHandOver = true;                        ///< local maps closed, handed over, seeded
  static constexpr bool kDuplicateMerge = kImageDuplicateMerge;  ///< duplicate_merge_d2
  /// motion_false_alarm, learn_detection, learn_clutter, detection_floor
  static constexpr bool kWorldModel = kImageWorldModel;
};
template <>
struct OptionalStages<SmallControllerBounds> {
  static constexpr bool kHypotheses = false;
  static constexpr bool kHandOver = false;
  static constexpr bool kDuplicateMerge = kImageDuplicateMerge;
  static constexpr bool kWorldModel = false;
};

}  // namespace geojcbb
