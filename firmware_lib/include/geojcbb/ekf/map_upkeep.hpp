// ekf: the map's upkeep, the operations of ekf::Slam that decide which landmarks stay (declared and
// documented in ekf/slam.hpp, defined here):
//   review         a scan's evidence counted (hits, misses, the log-odds of existence, the static
//                  gate) and the landmarks the policy rejects removed, marginalised
//                  (count_evidence, LandmarkBook::choose_kept, move_kept)
//   duplicate_d2   how far apart two landmarks are in their own uncertainty
//   merge          a duplicate fused into the landmark it copies, then removed
//   evict          the least-seen landmark beyond r + d removed to make room
//   remove, moved  one landmark removed; the static gate on one landmark
// Definitions are `inline` where the in-class ones were implicitly so (the `gnu::noinline` ones
// are not), so the compiler inlines as before the split.
// Bounds: O(n^2) per removal (the covariance compacted), O(n_c) evidence per scan.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "geojcbb/core/fmath.hpp"
#include "geojcbb/ekf/slam.hpp"

namespace geojcbb::ekf {

template <typename T, class B>
Status Slam<T, B>::review(const Observations<T, B>& obs, const Prediction<T, B>& pred, const Association<T, B>& assoc,
                          const Visibility<T>& view, const LandmarkPolicy& policy, ReviewStats& stats,
                          std::uint32_t (*clock)(), std::uint32_t* counted) {
  if (!policy.valid() || !(view.min_range_m >= T(0)) || !(view.max_range_m > view.min_range_m) ||
      !(view.half_fov_rad > T(0)) || !std::isfinite(view.max_range_m) || !std::isfinite(view.half_fov_rad) ||
      !(view.occlusion_rad >= T(0)) || !std::isfinite(view.occlusion_rad)) {
    return Status::kInvalidInput;
  }
  if (pred.count < 0 || pred.count > B::kMaxCandidates || assoc.count < 0 || assoc.count > B::kMaxObservations ||
      obs.count != assoc.count) {
    return Status::kInvalidInput;
  }
  const std::uint32_t t0 = clock ? clock() : 0;
  count_evidence(obs, pred, assoc, view, policy, stats);
  std::int16_t keep[B::kMaxLandmarks];
  const int kept = book_.choose_kept(policy, keep, stats);
  if (counted != nullptr) *counted = clock ? clock() - t0 : 0;
  if (kept == landmarks()) return Status::kOk;
  move_kept(keep, kept);
  book_.retain(keep, kept);
  return Status::kOk;
}

template <typename T, class B>
T Slam<T, B>::duplicate_d2(int a, int b) const {
  if (a < 0 || b < 0 || a >= landmarks() || b >= landmarks() || a == b) return std::numeric_limits<T>::infinity();
  const int la = Layout::landmark(a), lb = Layout::landmark(b);
  const T s00 = cov(la, la) + cov(lb, lb) - T(2) * cov(la, lb);
  const T s01 = cov(la, la + 1) + cov(lb, lb + 1) - cov(la, lb + 1) - cov(la + 1, lb);
  const T s11 = cov(la + 1, la + 1) + cov(lb + 1, lb + 1) - T(2) * cov(la + 1, lb + 1);
  const T det = s00 * s11 - s01 * s01;
  if (!(s00 > T(0)) || !(det > T(0)) || !std::isfinite(det)) return std::numeric_limits<T>::infinity();
  const T dx = x_[la] - x_[lb], dy = x_[la + 1] - x_[lb + 1];
  const T d2 = (s11 * dx * dx - T(2) * s01 * dx * dy + s00 * dy * dy) / det;
  return std::isfinite(d2) ? d2 : std::numeric_limits<T>::infinity();
}

template <typename T, class B>
inline Status Slam<T, B>::merge(int keep, int drop, SlamWorkspace<T, B>& ws) {
  if (keep < 0 || drop < 0 || keep >= landmarks() || drop >= landmarks() || keep == drop) {
    return Status::kInvalidInput;
  }
  const int n = dim();
  constexpr int K = kUpdateBlockCols;
  auto V = [&](int r, int c) -> T& { return ws.V[static_cast<std::size_t>(r) * K + c]; };
  const int lk = Layout::landmark(keep), ld = Layout::landmark(drop);
  for (int r = 0; r < n; ++r) {  // A = P H^T, two columns;  <= kMaxState
    V(r, 0) = cov(r, lk) - cov(r, ld);
    V(r, 1) = cov(r, lk + 1) - cov(r, ld + 1);
    for (int c = 2; c < K; ++c) V(r, c) = T(0);  // <= K
  }
  // S = H A + R = L L^T (2x2), then V <- A L^-T.
  const T s00 = V(lk, 0) - V(ld, 0) + kMergeNoise_m2, s10 = V(lk + 1, 0) - V(ld + 1, 0);
  const T s11 = V(lk + 1, 1) - V(ld + 1, 1) + kMergeNoise_m2;
  if (!(s00 > T(0)) || !std::isfinite(s00)) return Status::kNotPositiveDefinite;
  const T l00 = std::sqrt(s00), l10 = s10 / l00, d11 = s11 - l10 * l10;
  if (!(d11 > T(0)) || !std::isfinite(d11)) return Status::kNotPositiveDefinite;
  const T l11 = std::sqrt(d11);
  for (int r = 0; r < n; ++r) {  // <= kMaxState
    V(r, 0) = V(r, 0) / l00;
    V(r, 1) = (V(r, 1) - l10 * V(r, 0)) / l11;
  }
  if (!downdate_keeps_blocks_definite(n, ws)) return Status::kNotPositiveDefinite;
  // The innovation 0 - (l_keep - l_drop), whitened: w = L^-1 nu.
  const T w0 = -(x_[lk] - x_[ld]) / l00;
  const T w1 = (-(x_[lk + 1] - x_[ld + 1]) - l10 * w0) / l11;
  for (int r = 0; r < n; ++r) {  // <= kMaxState
    if (!std::isfinite(x_[r] + V(r, 0) * w0 + V(r, 1) * w1)) return Status::kNonFinite;
  }
  if (!updated_) {  // the pose the next prediction linearises at (FEJ), as update() records it
    prior_[0] = x_[0];
    prior_[1] = x_[1];
    updated_ = true;
  }
  for (int r = 0; r < n; ++r) x_[r] += V(r, 0) * w0 + V(r, 1) * w1;  // <= kMaxState
  x_[2] = wrap_angle(x_[2]);
  P_.template downdate<K>(n, ws.V.data(), ws.floored_variances);
  book_.absorb(keep, drop);
  remove(drop);
  return Status::kOk;
}

template <typename T, class B>
inline Status Slam<T, B>::evict(T radius_m, FeatureId& evicted) {
  evicted = -1;
  int best = -1;
  T best_d = T(0);
  const Vec2<T> r(x_[0], x_[1]);
  for (int j = 0; j < landmarks(); ++j) {  // <= kMaxLandmarks
    const T d = (landmark(j) - r).norm();
    if (!(d > radius_m)) continue;
    if (best < 0 || hits(j) < hits(best) || (hits(j) == hits(best) && d > best_d)) {
      best = j;
      best_d = d;
    }
  }
  if (best < 0) return Status::kCapacityExceeded;
  evicted = id(best);
  remove(best);
  return Status::kOk;
}

template <typename T, class B>
void Slam<T, B>::remove(int j) {
  std::int16_t keep[B::kMaxLandmarks];
  int kept = 0;
  for (int k = 0; k < landmarks(); ++k) {  // <= kMaxLandmarks
    if (k != j) keep[kept++] = static_cast<std::int16_t>(k);
  }
  move_kept(keep, kept);
  book_.retain(keep, kept);
}

template <typename T, class B>
inline bool Slam<T, B>::moved(int j, T gate_d2) const {
  const auto& r = book_[j];
  const int l = Layout::landmark(j);
  const T a0 = r.P0[0] - cov(l, l) + kStaticFloor_m2, b0 = r.P0[1] - cov(l, l + 1),
          c0 = r.P0[2] - cov(l + 1, l + 1) + kStaticFloor_m2;
  const T det = a0 * c0 - b0 * b0;
  const T dx = x_[l] - r.l0[0], dy = x_[l + 1] - r.l0[1];
  const T d2 = (c0 * dx * dx - T(2) * b0 * dx * dy + a0 * dy * dy) / det;
  return det > T(0) && d2 > gate_d2;
}

template <typename T, class B>
void Slam<T, B>::count_evidence(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                const Association<T, B>& assoc, const Visibility<T>& view, const LandmarkPolicy& policy,
                                ReviewStats& stats) {
  stats = ReviewStats{};
  book_.start_review();
  constexpr bool kModel = OptionalStages<B>::kWorldModel;  // compiled out: configure() refused learning
  const bool learn_pd = kModel && policy.learn_detection, learn_clutter = kModel && policy.learn_clutter;
  if ((learn_pd || learn_clutter) && !detect_ready_) {
    detect_.reset(T(policy.p_detect), T(policy.clutter_density), view.max_range_m);
    detect_ready_ = true;
  }
  const ExistenceEvidence<T> ev =
      learn_clutter ? ExistenceEvidence<T>(policy, detect_.density()) : ExistenceEvidence<T>(policy);
  const Mat2<T> R_miss = obs.count > 0 ? obs.R[0] : Mat2<T>::Zero();
  for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates
    const int j = index_of(pred.id[a]);
    if (j < 0) continue;  // not in this map
    int i = 0;
    while (i < assoc.count && assoc.feature[i] != pred.id[a]) ++i;  // <= kMaxObservations
    const bool paired = i < assoc.count;
    const T r = pred.h[a].x();
    const bool seen = ekf::in_view(pred, a, view);
    const T pd = learn_pd ? detect_.pd(r) : T(policy.p_detect);
    if (learn_pd && seen && book_.confirmed(j)) detect_.sighting(r, paired);
    const bool informative = seen && !(pd < T(policy.detection_floor));  // a miss below the floor: nothing
    stats.expected += informative;
    stats.paired += paired;
    T e = T(0);
    if (paired || informative) {
      const Mat2<T> S = pred.C.block(a, a) + (paired ? obs.R[i] : R_miss);
      const T pfa = ev.pfa(r * r * (S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0)));
      if (learn_pd) {
        e = paired ? ExistenceEvidence<T>::hit_pd(pd, pfa) : ExistenceEvidence<T>::miss_pd(pd, pfa);
      } else {
        e = paired ? ev.hit(pfa) : ev.miss(pfa);
      }
    }
    stats.confirmed += book_.count(j, informative, paired, e, policy);
    if (paired && policy.static_gate_d2 > 0.0f && moved(j, T(policy.static_gate_d2))) book_[j].drop = Drop::kMoved;
  }
  if (learn_clutter) {  // the scan's observations nothing explains, over the area in view
    int unexplained = 0;
    for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
      unexplained += assoc.feature[i] == kNewFeature || assoc.feature[i] == kUnmatched;
    }
    const T r0 = view.min_range_m, r1 = view.max_range_m;
    detect_.scan(unexplained, view.half_fov_rad * (r1 * r1 - r0 * r0));
  }
}

template <typename T, class B>
bool Slam<T, B>::motion_pair(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                             const Association<T, B>& assoc, int i, int& j, T (&delta)[2], T (&Sigma)[3],
                             T (&info)[3]) const {
  const FeatureId f = assoc.feature[i];
  if (f < 0) return false;
  int a = assoc.candidate[i];
  if (a < 0 || a >= pred.count || pred.id[a] != f) {
    a = -1;
    for (int b = 0; b < pred.count && a < 0; ++b) a = pred.id[b] == f ? b : -1;  // <= kMaxCandidates
  }
  j = index_of(f);
  if (a < 0 || j < 0) return false;
  Vec2<T> nu = obs.z[i] - pred.h[a];
  nu.y() = wrap_angle(nu.y());
  const Mat2<T> S = pred.C.block(a, a) + obs.R[i];
  const T alpha = x_[2] + mount_.theta + pred.h[a].y();  // the line of sight in the world
  if (!world_innovation(nu, S, pred.h[a].x(), alpha, delta, Sigma)) return false;
  const T det = Sigma[0] * Sigma[2] - Sigma[1] * Sigma[1];
  if (!(det > T(0))) return false;
  info[0] = Sigma[2] / det;
  info[1] = -Sigma[1] / det;
  info[2] = Sigma[0] / det;
  return true;
}

template <typename T, class B>
int Slam<T, B>::test_motion(const Observations<T, B>& obs, const Prediction<T, B>& pred, const Association<T, B>& assoc,
                            T threshold, T static_gate_d2, std::array<std::int16_t, B::kMaxObservations>& moved) {
  if constexpr (!OptionalStages<B>::kWorldModel) {  // compiled out: configure() refused the option
    (void)obs;
    (void)pred;
    (void)assoc;
    (void)threshold;
    (void)static_gate_d2;
    (void)moved;
    return 0;
  } else {
    // First pass: the scan's information and information-weighted innovation, summed over its pairs.
    T Y[3] = {T(0), T(0), T(0)}, y[2] = {T(0), T(0)};
    int pairs = 0;
    for (int i = 0; i < assoc.count && i < obs.count; ++i) {  // <= kMaxObservations
      int j = -1;
      T d[2], D[3], I[3];
      if (!motion_pair(obs, pred, assoc, i, j, d, D, I)) continue;
      const T i00 = I[0], i01 = I[1], i11 = I[2];
      Y[0] += i00;
      Y[1] += i01;
      Y[2] += i11;
      y[0] += i00 * d[0] + i01 * d[1];
      y[1] += i01 * d[0] + i11 * d[1];
      ++pairs;
    }
    // One pair: its motion and the pose's error cannot be told apart (only the static gate decides).
    const bool evidence = pairs >= 2;
    // Second pass: each pair against the others' mean (their sums less its own).
    int n = 0;
    for (int i = 0; i < assoc.count && i < obs.count; ++i) {  // <= kMaxObservations
      int j = -1;
      T d[2], D[3], I[3];
      if (!motion_pair(obs, pred, assoc, i, j, d, D, I)) continue;
      const T i00 = I[0], i01 = I[1], i11 = I[2];
      const T o00 = Y[0] - i00, o01 = Y[1] - i01, o11 = Y[2] - i11;  // the others' information
      const T odet = o00 * o11 - o01 * o01;
      bool fails = has_moved(j, static_gate_d2);
      if (evidence && odet > T(0) && (book_[j].flags & kKnownFlag) == 0) {
        const T c00 = o11 / odet, c01 = -o01 / odet, c11 = o00 / odet;  // their mean's covariance
        const T w0 = y[0] - (i00 * d[0] + i01 * d[1]), w1 = y[1] - (i01 * d[0] + i11 * d[1]);
        const T diff[2] = {d[0] - (c00 * w0 + c01 * w1), d[1] - (c01 * w0 + c11 * w1)};
        const T cov[3] = {D[0] + c00, D[1] + c01, D[2] + c11};
        const T t = book_[j].motion.add(diff, cov);
        fails = fails || (threshold > T(0) && t > threshold);
      }
      if (fails) moved[static_cast<std::size_t>(n++)] = static_cast<std::int16_t>(i);
    }
    return n;
  }
}

template <typename T, class B>
void Slam<T, B>::move_kept(const std::int16_t (&keep)[B::kMaxLandmarks], int kept) {
  P_.template keep_pairs<Layout::kPoseSize>(keep, kept);
  for (int k = 0; k < kept; ++k) {  // <= kMaxLandmarks
    const int l = Layout::landmark(k), o = Layout::landmark(keep[k]);
    x_[l] = x_[o];
    x_[l + 1] = x_[o + 1];
  }
}

template <typename T, class B>
void Slam<T, B>::reanchor() {
  // fmath: the same bits on the device and on the host (libm's sinf/cosf differ between them).
  const T px = x_[0], py = x_[1], c = fmath::cos(x_[2]), sn = fmath::sin(x_[2]);
  Mat2<T> Rt;  // R(theta)^T
  Rt << c, sn, -sn, c;
  const Mat3<T> Prr = P_.template block<3, 3>(0, 0);
  // d l' / d pose for landmark a: [-R^T, (l'_y, -l'_x)] with l' = R^T (l - p).
  auto jacobian = [&](int a) {
    const int la = Layout::landmark(a);
    const Vec2<T> d = Rt * Vec2<T>(x_[la] - px, x_[la + 1] - py);
    Mat23<T> J;
    J.template block<2, 2>(0, 0) = -Rt;
    J(0, 2) = d.y();
    J(1, 2) = -d.x();
    return J;
  };
  const int n = landmarks();
  for (int a = 0; a < n; ++a) {  // <= kMaxLandmarks
    const int la = Layout::landmark(a);
    const Mat23<T> Ja = jacobian(a);
    const Mat32<T> Pra = P_.template block<3, 2>(0, la);
    for (int b = a; b < n; ++b) {  // <= kMaxLandmarks
      const int lb = Layout::landmark(b);
      const Mat23<T> Jb = jacobian(b);
      const Mat32<T> Prb = P_.template block<3, 2>(0, lb);
      const Mat2<T> Pab = P_.template block<2, 2>(la, lb);
      const Mat2<T> Q = Ja * Prr * Jb.transpose() + Ja * Prb * Rt.transpose() + Rt * Pra.transpose() * Jb.transpose() +
                        Rt * Pab * Rt.transpose();
      if (a == b) {
        P_.template set_sym<2>(la, symmetric_part(Q));
      } else {
        P_.template set_block<2, 2>(la, lb, Q);
      }
    }
  }
  for (int a = 0; a < n; ++a) {  // <= kMaxLandmarks: the means and first estimates, the pose rows
    const int la = Layout::landmark(a);
    const Vec2<T> l = Rt * Vec2<T>(x_[la] - px, x_[la + 1] - py);
    x_[la] = l.x();
    x_[la + 1] = l.y();
    auto& r = book_[a];
    const Vec2<T> l0 = Rt * Vec2<T>(r.l0[0] - px, r.l0[1] - py);
    r.l0[0] = l0.x();
    r.l0[1] = l0.y();
    Mat2<T> P0;
    P0 << r.P0[0], r.P0[1], r.P0[1], r.P0[2];
    P0 = Rt * P0 * Rt.transpose();
    r.P0[0] = P0(0, 0);
    r.P0[1] = P0(0, 1);
    r.P0[2] = P0(1, 1);
    if constexpr (OptionalStages<B>::kWorldModel) r.motion.rotate(c, sn);
    P_.template set_block<3, 2>(0, la, Mat32<T>::Zero());
  }
  x_[0] = x_[1] = x_[2] = T(0);
  updated_ = false;
}

}  // namespace geojcbb::ekf
