// consistency: the pairwise consistency graph (Bailey's CCDA 2002; Mangelson et al.'s PCM 2018).
// In: observations z_i (R_i) and the prediction (h, C = H P H^T). Out: graph nodes = pairings (i, a)
// from a wide gate (<= MaxNodes, the best by individual d2 kept), edges = pairs of pairings whose
// observed and predicted point distances agree (chi-square, 1 dof). Pose-free: docs/consistency.md.
// Bounds: m n gate tests; <= MaxNodes (MaxNodes - 1) / 2 pair tests, each O(1) on 2x2 blocks.
//
//   p_i = r_i (cos b_i, sin b_i)          observed point (sensor frame),   J_i = dp/dz at z_i
//   q_a = r_a (cos b_a, sin b_a)          predicted point from h_a,        J_a = dp/dz at h_a
//   u = p_i - p_k,  Sigma_u = J_i R_i J_i^T + J_k R_k J_k^T
//   v = q_a - q_b,  Sigma_v = J_a C_aa J_a^T + J_b C_bb J_b^T - J_a C_ab J_b^T - (J_a C_ab J_b^T)^T
//   e = |u| - |v|,  s2 = g_u^T Sigma_u g_u + g_v^T Sigma_v g_v  (g = unit direction of u, v)
//   consistent:  e^2 <= pair_d2 s2,  i != k,  a != b
// |v| = |l_a - l_b| whatever the pose estimate; the pose's part of Sigma_v cancels (translation) or is
// orthogonal to g_v (rotation), so s2 holds the map's and the sensor's uncertainty only.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include "geojcbb/consistency/bitset_graph.hpp"
#include "geojcbb/core/consistency_options.hpp"
#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/gate/compatibility.hpp"

namespace geojcbb {

/// One node of the consistency graph: observation i takes candidate a.
template <typename T>
struct Pairing {
  std::int8_t obs = 0;
  std::int16_t cand = 0;
  T d2 = T(0);  ///< individual d2 of (i, a): nu^T (C_aa + R_i)^-1 nu
};

template <typename T, int MaxNodes>
struct PairingList {
  int count = 0;
  int offered = 0;         ///< pairings that passed the wide gate (may exceed MaxNodes)
  bool truncated = false;  ///< more than MaxNodes passed: the MaxNodes smallest d2 were kept
  std::array<Pairing<T>, MaxNodes> node;
};

/// The distance test of two pairings, with its parts (for tests and diagnostics).
template <typename T>
struct PairStatistic {
  T observed_m = T(0);     ///< |p_i - p_k|
  T predicted_m = T(0);    ///< |q_a - q_b|
  T var_observed = T(0);   ///< first-order variance of observed_m [m^2]
  T var_predicted = T(0);  ///< first-order variance of predicted_m [m^2] (pose-free)
  /// (observed - predicted)^2 / (var_observed + var_predicted); 0 or infinity when the variance is 0.
  T d2() const {
    const T e = observed_m - predicted_m;
    const T s2 = var_observed + var_predicted;
    if (s2 > T(0)) return e * e / s2;
    return e == T(0) ? T(0) : std::numeric_limits<T>::infinity();
  }
};

/// Cartesian points of the observations and candidates in the sensor frame, computed once per call.
template <typename T, class B>
struct PairwiseGeometry {
  std::array<Vec2<T>, B::kMaxObservations> obs_point;  ///< p_i [m]
  std::array<Mat2<T>, B::kMaxObservations> obs_cov;    ///< J_i R_i J_i^T [m^2]
  std::array<Vec2<T>, B::kMaxCandidates> cand_point;   ///< q_a [m]
  std::array<Mat2<T>, B::kMaxCandidates> cand_J;       ///< J_a = dq/dh at h_a

  void prepare(const Observations<T, B>& obs, const Prediction<T, B>& pred) {
    const Pose2<T> sensor{};  // the sensor frame: polar to Cartesian is inverse_observe at identity
    Mat23<T>* const no_pose_jacobian = nullptr;
    Mat2<T> J;
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      obs_point[i] = inverse_observe(sensor, obs.z[i], no_pose_jacobian, &J);
      obs_cov[i] = J * obs.R[i] * J.transpose();
    }
    for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates
      cand_point[a] = inverse_observe(sensor, pred.h[a], no_pose_jacobian, &cand_J[a]);
    }
  }
};

namespace pairwise_detail {

/// First-order variance of |d| for d with covariance S: g^T S g along g = d / |d|. Where |d| is
/// numerically zero the direction is undefined and the largest eigenvalue of S (an upper bound over
/// every direction) is used.
template <typename T>
T norm_variance(const Vec2<T>& d, const Mat2<T>& S, T norm) {
  const T tr = S(0, 0) + S(1, 1);
  if (norm * norm > kCovarianceTolerance<T> * tr) {
    const Vec2<T> g = d / norm;
    return g.dot(S * g);
  }
  const T half_gap = (S(0, 0) - S(1, 1)) / T(2);
  return tr / T(2) + std::sqrt(half_gap * half_gap + S(0, 1) * S(1, 0));
}

}  // namespace pairwise_detail

/// The distance test of pairings (i, a) and (k, b), a != b. Inputs validated, geometry prepared.
/// @return kOk; kNonFinite for an entry of C's cross block (a, b) that is not finite (C validated
///         where it is read, packed covariance; the packed C's cross blocks are
///         symmetric by storage);
///         kNotPositiveDefinite when C's blocks of a and b make Sigma_v's variance negative beyond
///         rounding (C not PSD).
template <typename T, class B>
[[nodiscard]] Status pair_statistic(const PairwiseGeometry<T, B>& geo, const Prediction<T, B>& pred, int i, int a,
                                    int k, int b, PairStatistic<T>& out) {
  if (!pred.C.block(a, b).allFinite()) return Status::kNonFinite;
  const Vec2<T> u = geo.obs_point[i] - geo.obs_point[k];
  const Mat2<T> Su = geo.obs_cov[i] + geo.obs_cov[k];
  const Vec2<T> v = geo.cand_point[a] - geo.cand_point[b];
  const Mat2<T>& Ja = geo.cand_J[a];
  const Mat2<T>& Jb = geo.cand_J[b];
  const Mat2<T> Saa = Ja * pred.C.block(a, a) * Ja.transpose();
  const Mat2<T> Sbb = Jb * pred.C.block(b, b) * Jb.transpose();
  const Mat2<T> Sab = Ja * pred.C.block(a, b) * Jb.transpose();
  const Mat2<T> Sv = Saa + Sbb - Sab - Sab.transpose();
  PairStatistic<T> st;
  st.observed_m = u.norm();
  st.predicted_m = v.norm();
  st.var_observed = pairwise_detail::norm_variance(u, Su, st.observed_m);
  T var_v = pairwise_detail::norm_variance(v, Sv, st.predicted_m);
  // The pose's share of Saa and Sbb cancels in Sv: rounding of that share may leave var_v slightly
  // negative; beyond rounding of the parts, C is not PSD.
  const T scale = Saa(0, 0) + Saa(1, 1) + Sbb(0, 0) + Sbb(1, 1);
  if (var_v < -kCovarianceTolerance<T> * scale) return Status::kNotPositiveDefinite;
  st.var_predicted = var_v > T(0) ? var_v : T(0);
  out = st;
  return Status::kOk;
}

/// Graph nodes: the pairings (i, a) through the wide gate, every candidate in the region when
/// opt.pairing_gate is kEveryCandidate. When more than MaxNodes pass, the MaxNodes with the smallest
/// (d2, i, a) are kept and `truncated` is set. Nodes are listed by (i, a). Inputs validated.
/// Bounds: m n gate tests; on overflow, an insertion of <= MaxNodes steps per further pairing and a
/// final insertion sort of MaxNodes entries.
template <typename T, class B, int MaxNodes>
void select_pairings(const Observations<T, B>& obs, const Prediction<T, B>& pred, const ConsistencyOptions<T>& opt,
                     PairingList<T, MaxNodes>& list) {
  list.count = 0;
  list.offered = 0;
  list.truncated = false;
  // Sorted by (d2, i, a) once the list overflows; a later pairing has a larger (i, a).
  auto before = [](const Pairing<T>& x, const Pairing<T>& y) { return x.d2 < y.d2; };
  for (int i = 0; i < obs.count; ++i) {     // <= kMaxObservations
    for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates
      if (!opt.in_region(pred.h[a])) continue;
      const Mat2<T> S = pred.C.block(a, a) + obs.R[i];
      Pairing<T> p;
      p.obs = static_cast<std::int8_t>(i);
      p.cand = static_cast<std::int16_t>(a);
      p.d2 = mahalanobis2(innovation(obs.z[i], pred.h[a]), S);
      if (opt.pairing_gate == PairingGate::kWide && !(p.d2 <= opt.wide_d2)) continue;
      ++list.offered;
      if (list.count < MaxNodes) {
        list.node[list.count++] = p;
        continue;
      }
      if (!list.truncated) {  // the first overflow: order the full list by d2 (stable)
        list.truncated = true;
        for (int x = 1; x < MaxNodes; ++x) {  // <= MaxNodes
          const Pairing<T> q = list.node[x];
          int y = x;
          for (; y > 0 && before(q, list.node[y - 1]); --y) list.node[y] = list.node[y - 1];  // <= MaxNodes
          list.node[y] = q;
        }
      }
      if (!before(p, list.node[MaxNodes - 1])) continue;
      int y = MaxNodes - 1;
      for (; y > 0 && before(p, list.node[y - 1]); --y) list.node[y] = list.node[y - 1];  // <= MaxNodes
      list.node[y] = p;
    }
  }
  if (list.truncated) {  // back to (i, a) order
    auto index_before = [](const Pairing<T>& x, const Pairing<T>& y) {
      return x.obs < y.obs || (x.obs == y.obs && x.cand < y.cand);
    };
    for (int x = 1; x < MaxNodes; ++x) {  // <= MaxNodes
      const Pairing<T> q = list.node[x];
      int y = x;
      for (; y > 0 && index_before(q, list.node[y - 1]); --y) list.node[y] = list.node[y - 1];  // <= MaxNodes
      list.node[y] = q;
    }
  }
}

/// Edges between the listed pairings: distinct observations, distinct candidates, and the distance
/// test passed. Inputs validated, geometry prepared.
/// @return kOk; kNotPositiveDefinite from pair_statistic (the graph is then incomplete).
template <typename T, class B, int MaxNodes>
[[nodiscard]] Status build_consistency_graph(const PairwiseGeometry<T, B>& geo, const Prediction<T, B>& pred,
                                             const PairingList<T, MaxNodes>& list, T pair_d2,
                                             BitsetGraph<MaxNodes>& graph) {
  graph.reset(list.count);
  for (int x = 0; x < list.count; ++x) {  // <= MaxNodes
    const Pairing<T>& p = list.node[x];
    for (int y = x + 1; y < list.count; ++y) {  // <= MaxNodes
      const Pairing<T>& q = list.node[y];
      if (p.obs == q.obs || p.cand == q.cand) continue;
      PairStatistic<T> st;
      const Status s = pair_statistic(geo, pred, p.obs, p.cand, q.obs, q.cand, st);
      if (s != Status::kOk) return s;
      if (st.d2() <= pair_d2) graph.add_edge(x, y);
    }
  }
  return Status::kOk;
}

}  // namespace geojcbb
