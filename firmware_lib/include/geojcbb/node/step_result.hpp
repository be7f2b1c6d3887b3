// node: what one SLAM step reports (StepResult: per observation its outcome, the stages' stats, the
// stage counts) and the host's way into it (AssociationOverride). node/slam_step.hpp fills them.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include "geojcbb/associate.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/stages/map_view.hpp"
#include "geojcbb/node/stages/relocaliser.hpp"
#include "geojcbb/protocol/stage_counts.h"
#include "geojcbb/reloc/loop.hpp"
#include "geojcbb/reloc/window.hpp"

namespace geojcbb::node {

/// Per observation of a scan, what became of it.
enum class Outcome : std::uint8_t {
  kPaired = 0,    ///< feature: the map landmark's id
  kNewLandmark,   ///< no compatible candidate; became the landmark `feature`
  kNewDropped,    ///< no compatible candidate, but inside the augmentation gate (or augmentation off): dropped
  kUnmatched,     ///< compatible candidates, left unpaired by the search (ambiguous)
  kNotAugmented,  ///< would have become a landmark, but the map is full
  kMover,         ///< taken by a mover's track (stages/movers.hpp): neither paired nor mapped
};

/// Instruction or cycle counts of the stages, from the clock the caller supplies (0 without): one
/// counter per row of the stage table (protocol/stage_counts.h), which STATS carries as instr_<name>.
struct StageCounts {
#define GEOJCBB_STAGE_COUNT_MEMBER(name, meaning) std::uint32_t name = 0;
  GEOJCBB_STAGE_COUNTS(GEOJCBB_STAGE_COUNT_MEMBER)
#undef GEOJCBB_STAGE_COUNT_MEMBER
};

template <typename T, class B>
struct StepResult {
  int count = 0;  ///< observations
  std::array<Outcome, B::kMaxObservations> outcome{};
  std::array<FeatureId, B::kMaxObservations> feature{};  ///< see Outcome; -1 when none
  std::array<T, B::kMaxObservations> d2{};               ///< the association's d2 (core semantics)
  AssociationDiagnostics diag;
  ekf::LocalMapStats local;
  ekf::ReviewStats review;
  RelocStats reloc;
  reloc::LoopStats<T> loop;
  reloc::WindowStats<T> window;
  StageCounts counts;
  /// The local map's closing rule fired (submap_landmarks, submap_distance_m, submap_scans): hand
  /// it over, then SlamStep::restart.
  bool submap_due = false;

  /// A scan that is not used (lost, not aligned): every observation kUnmatched, no counts (the
  /// loop check's and the window's stats are left as they were: neither ran).
  void unused(int observations) {
    count = observations;
    diag = AssociationDiagnostics{};
    local = ekf::LocalMapStats{};
    review = ekf::ReviewStats{};
    counts = StageCounts{};
    for (int i = 0; i < count; ++i) {  // <= kMaxObservations
      outcome[static_cast<std::size_t>(i)] = Outcome::kUnmatched;
      feature[static_cast<std::size_t>(i)] = kUnmatched;
      d2[static_cast<std::size_t>(i)] = std::numeric_limits<T>::infinity();
    }
  }
};

/// A free-running counter read before and after each stage (e.g. SysTick or an instruction count);
/// nullptr: no counts.
using CounterFn = std::uint32_t (*)();

/// The host's way into step(): an association made by other means (the evaluation's ground-truth
/// reference) in place of the configured one and of the stages that edit it (tentative pairing,
/// loop check, clusters first, window). It writes every observation's feature and d2 and the count;
/// the step recounts the pairings. A non-kOk status is returned by step() with nothing changed.
template <typename T, class B>
struct AssociationOverride {
  Status (*fn)(void* ctx, const Observations<T, B>& obs, const Prediction<T, B>& pred, const MapView<T, B>& map,
               Association<T, B>& out) = nullptr;
  void* ctx = nullptr;
};

}  // namespace geojcbb::node
