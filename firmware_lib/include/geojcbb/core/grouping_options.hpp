// core: the options of the grouping stage (ARCHITECTURE.md step 3b) as plain data, and its
// iteration bounds. The stage itself lives in cluster/ (cluster/group.hpp dispatches to k-means,
// DBSCAN or GMM-EM); core holds only what AssociationConfig carries, so core includes no stage.
// Bounds: kMaxKMeansIterations, kMaxEmIterations per fit.
#pragma once

#include <cstdint>

namespace geojcbb {

/// How the observations are split before JCBB runs per group (ARCHITECTURE.md, step 3b).
enum class Grouping : std::uint8_t {
  kNone,    ///< one group: plain JCBB
  kKMeans,  ///< k-means (KJCBB)
  kDbscan,  ///< DBSCAN (DFJCBB)
  kGmmEm,   ///< Gaussian mixture by EM (GEMJCBB, GEOJCBB)
};

constexpr int kMaxKMeansIterations = 50;
constexpr int kMaxEmIterations = 50;

/// When an EM fit stops (cluster/gmm_em.hpp).
enum class EmStop : std::uint8_t {
  /// The papers' rule: when the objective Q gains less than tolerance * (1 + |Q|), or at the bound.
  kObjective,
  /// Packed covariance: also when the groups (arg max responsibilities, eq. 9) came out
  /// the same from stable_iterations consecutive iterations (and, with hard_margin < 1, every
  /// point's largest responsibility is at least 1 - hard_margin): EM's remaining iterations then
  /// mostly refine the components' parameters, not the groups this stage returns. Not a proof that
  /// the groups cannot change later; measured against kObjective on the evaluation's seeds
  /// (docs/algorithms.md).
  kGroupsStable,
};

/// Where an EM fit starts (cluster/gmm_em.hpp).
enum class EmStart : std::uint8_t {
  /// Hard responsibilities to the nearest farthest-first seed (cluster/groups.hpp), the start
  /// before packed covariance.
  kFarthestFirst,
  /// Packed covariance: hard responsibilities from k-means (Lloyd's iterations from the
  /// same seeds, no exp or log; the usual EM initialisation): EM starts next to its fixed point.
  kKMeans,
};

template <typename T>
struct EmOptions {
  int max_iterations = kMaxEmIterations;  ///< 1 .. kMaxEmIterations
  T tolerance = T(1e-4);                  ///< stop when Q gains less than tolerance * (1 + |Q|)
  T covariance_floor_m2 = T(0.04);        ///< eps: a lone point is a Gaussian of 0.2 m standard deviation
  EmStop stop = EmStop::kGroupsStable;
  EmStart start = EmStart::kKMeans;
  int stable_iterations = 1;  ///< kGroupsStable: iterations with unchanged groups, 1 .. kMaxEmIterations
  T hard_margin = T(1);       ///< kGroupsStable: 0 .. 1 (1: no hardness required)
};

}  // namespace geojcbb
