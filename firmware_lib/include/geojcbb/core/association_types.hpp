// core: inputs and outputs of one association call. Inputs are independent of any filter:
// observations z_i = (range, bearing) with noise R_i, and a prediction for n candidate features
// (ids, predicted measurements h_j, and C = H P H^T, the 2n x 2n covariance of the predicted
// measurements with all cross terms). Sizes are bounded by a Bounds type (core/capacity.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include "geojcbb/core/capacity.hpp"
#include "geojcbb/core/math.hpp"
#include "geojcbb/core/status.hpp"

namespace geojcbb {

using FeatureId = std::int32_t;
/// No candidate in the region is individually compatible: a new landmark (or clutter; the filter
/// decides with its own rule).
constexpr FeatureId kNewFeature = -1;
/// Individually compatible with some candidate, but left out of the jointly compatible hypothesis
/// (ambiguous): neither paired nor safe to add as a new landmark.
constexpr FeatureId kUnmatched = -2;

/// Index of a candidate in a Prediction (0 .. MaxCandidates - 1), or -1 for none.
using CandidateIndex = std::int16_t;
/// A hypothesis: per observation, the index of its paired candidate or -1. Every stage (JCBB, ICNN,
/// the merge, the consistency stage) reads and writes hypotheses in this one form.
template <class B>
using Hypothesis = std::array<CandidateIndex, B::kMaxObservations>;

template <typename T, class B>
struct Observations {
  int count = 0;
  std::array<Vec2<T>, B::kMaxObservations> z;  ///< (range [m], bearing [rad]), sensor frame
  std::array<Mat2<T>, B::kMaxObservations> R;  ///< measurement noise covariance [m^2, rad^2]

  void clear() { count = 0; }
  /// @return kOk, or kCapacityExceeded (nothing written) when full. Values are validated by
  ///         associate(), not here.
  [[nodiscard]] Status push(const Vec2<T>& zi, const Mat2<T>& Ri) {
    if (count >= B::kMaxObservations) return Status::kCapacityExceeded;
    z[count] = zi;
    R[count] = Ri;
    ++count;
    return Status::kOk;
  }
};

template <typename T, class B>
using JointCovariance =
    Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * B::kMaxCandidates, 2 * B::kMaxCandidates>;

template <typename T, class B>
struct Prediction {
  int count = 0;                                ///< n candidate features
  std::array<FeatureId, B::kMaxCandidates> id;  ///< map feature ids (>= 0)
  std::array<Vec2<T>, B::kMaxCandidates> h;     ///< predicted (range [m], bearing [rad])
  JointCovariance<T, B> C;                      ///< H P H^T, 2n x 2n, candidate j at rows 2j, 2j+1
};

/// Per-call counters (as MAVLink keeps mavlink_status_t).
struct AssociationDiagnostics {
  NodeCount jcbb_nodes = 0;                ///< interpretation-tree nodes expanded
  std::uint16_t candidates_in_region = 0;  ///< candidates left after the local region (eq. 5)
  std::uint16_t compatible_pairs = 0;      ///< (observation, candidate) pairs passing the individual gate
  bool node_budget_hit = false;            ///< JCBB stopped at its node budget: best-so-far returned
  std::uint8_t groups = 0;                 ///< observation groups searched
  std::uint16_t cluster_iterations = 0;    ///< k-means or EM iterations (EM: over every BIC fit)
  /// The clustering stopped at its iteration bound before converging (k-means, EM), or DBSCAN
  /// merged groups beyond MaxGroups.
  bool cluster_bound_hit = false;
  std::uint16_t merge_conflicts = 0;      ///< features claimed by two groups (mutual exclusion)
  bool recheck_failed = false;            ///< the merged union failed the joint test and was repaired
  std::uint16_t recheck_dropped = 0;      ///< pairings the repair removed
  std::uint16_t declined = 0;             ///< pairings left kUnmatched as ambiguous (ambiguity_margin)
  std::uint16_t verify_dropped = 0;       ///< pairings the verification dropped (not pairwise consistent)
  bool seed_tried = false;                ///< the pose was uncertain: the pose-free clique was computed
  bool seed_used = false;                 ///< the clique passed the joint test and seeded the search
  std::uint16_t seed_pairings = 0;        ///< pairings of the clique (when tried)
  std::uint16_t clique_graph_nodes = 0;   ///< graph nodes of the last consistency graph (seed or verify)
  std::uint32_t clique_search_nodes = 0;  ///< max-clique search nodes, seed and verify together
  bool clique_budget_hit = false;         ///< a max-clique search stopped at its budget (best so far used)
  bool clique_nodes_truncated = false;    ///< the seed's wide gate passed more pairings than graph nodes
  bool rjc_used = false;                  ///< the scan was searched by RJC (cfg.rjc and a large scan)
};

template <typename T, class B>
struct Association {
  int count = 0;  ///< equals the number of observations
  /// Per observation: the paired feature's id, kNewFeature or kUnmatched.
  std::array<FeatureId, B::kMaxObservations> feature;
  /// Per observation: index of the paired candidate in the Prediction, or -1.
  std::array<std::int16_t, B::kMaxObservations> candidate;
  /// Per observation: individual d2 of its pair; when unpaired, the smallest d2 to any candidate in
  /// the region (infinity when there is none), which a filter can use as a second gate.
  std::array<T, B::kMaxObservations> d2;
  int pairings = 0;                ///< number of paired observations
  T joint_d2 = T(0);               ///< joint Mahalanobis distance of the hypothesis (eq. 4)
  bool jointly_compatible = true;  ///< the hypothesis passes the joint test at its size
  AssociationDiagnostics diag;
};

}  // namespace geojcbb
