// reloc: the robot's pose from one scan and the map, by two-point alignment, with or without a pose
// prior (the filter's estimate; none after a reset that says nothing about the pose).
// In: observations z_i = (range, bearing) with R_i; the map's landmark means m_j with covariances
// P_j (AlignWorkspace::push_landmark). Out: the pose world_T_robot, its covariance from the fit, the
// inlier pairings, and whether the pose is unique (AlignResult).
//   base pairs   the longest observed pairs (a, b), |q_a - q_b| >= min_base_m, at most base_pairs
//   matches      every map pair (j, k) with (|q_a - q_b| - |m_j - m_k|)^2 <= chi2(1) s2: two poses
//                each (a->j, b->k and a->k, b->j), rotation only (det R = +1: no mirror image)
//   prior        with a prior, a hypothesis outside its gate (prior_gate_d2, 3 dof) is not scored
//   score        inliers: observations whose world point R q_i + t lies within the 2-dof gate of a
//                landmark, S = R Sigma_i R^T + P_j (a window of the map sorted by x); the kTopPoses
//                best distinct poses are kept
//   rank         each kept pose, refined, by its log posterior [nats]: the set likelihood of the scan
//                there (set_log_likelihood) + the log prior (-d2/2; 0 without a prior)
//   accept       the best plausible pose (>= min_inliers, inlier ratio) when it leads the best
//                plausible distinct pose by margin_nats (or has none); else the scan is ambiguous
//   refine       weighted 2-D Procrustes on the exclusive inliers (2 rounds); covariance
//                (sum J^T S^-1 J)^-1 with J = [I, dR/dtheta q_i]
// Bounds: m^2 base-pair choice; base_pairs * n (n - 1) / 2 map pairs; kMaxAlignHypotheses scored
// hypotheses, each m (log n + window) inlier tests. No pair table: the map pairs are enumerated per
// base pair (no RAM; docs/relocalisation.md compares the cost). References: the 2-point RANSAC of
// scan-to-map localisation; Arun, Huang, Blostein (1987) for the closed-form rigid fit.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include <Eigen/Cholesky>

#include "geojcbb/consistency/pairwise.hpp"
#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/fmath.hpp"
#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/gate/validate.hpp"
#include "geojcbb/reloc/align_options.hpp"

namespace geojcbb::reloc {

template <typename T, class B>
struct AlignResult {
  bool accepted = false;          ///< unique and supported: pose and cov are the answer
  Pose2<T> pose{};                ///< world_T_robot (refined when accepted; else the best hypothesis)
  Mat3<T> cov = Mat3<T>::Zero();  ///< of (x, y, theta) from the fit (accepted only)
  int inliers = 0;                ///< of the best pose (after refinement when accepted)
  int misses = 0;                 ///< of the best pose: landmarks in view there, not observed
  int rival_inliers = 0;          ///< of the best plausible pose distinct from it (0: none)
  T score = T(0);                 ///< the best plausible pose's log posterior [nats] (-inf: none)
  T rival_score = T(0);           ///< its rival's (-inf: none)
  bool ambiguous = false;         ///< a plausible rival within margin_nats: nothing accepted
  bool unmapped = false;          ///< test_unmapped: "not of the map" within margin_nats: nothing accepted
  int hypotheses = 0;             ///< poses scored
  bool truncated = false;         ///< kMaxAlignHypotheses reached before every match was scored
  /// Per observation: the map index (push order) it pairs with at the answer, or -1.
  std::array<std::int16_t, B::kMaxObservations> landmark{};
};

namespace align_detail {
template <typename T>
struct Candidate {
  Pose2<T> pose{};
  int inliers = 0;
  T cost = T(0);  ///< sum of the inliers' d2 (ties)
};
}  // namespace align_detail

/// The map and the scratch of one align() call; fill the map with clear_map / push_landmark.
template <typename T, class B>
struct AlignWorkspace {
  int n = 0;
  std::array<Vec2<T>, B::kMaxLandmarks> m;             ///< landmark means, sorted by x after align()
  std::array<Mat2<T>, B::kMaxLandmarks> P;             ///< their covariances
  std::array<std::int16_t, B::kMaxLandmarks> index;    ///< sorted position -> push order
  std::array<Vec2<T>, B::kMaxObservations> q;          ///< observed points, robot frame [m]
  std::array<Mat2<T>, B::kMaxObservations> S;          ///< their covariances J R J^T
  std::array<T, B::kMaxObservations> radius;           ///< per observation: inlier search radius [m]
  std::array<std::int16_t, B::kMaxObservations> pick;  ///< per observation: sorted landmark or -1
  std::array<T, B::kMaxObservations> pick_d2;
  std::array<std::uint8_t, 2 * kMaxBasePairs> base;  ///< observation pairs (a, b), longest first
  std::array<align_detail::Candidate<T>, kTopPoses> top;
  std::array<Mat3<T>, kTopPoses> top_cov;  ///< the refined poses' fit covariances
  std::array<int, kTopPoses> top_misses;
  std::array<bool, kTopPoses> top_plausible;
  std::array<T, kTopPoses> top_score;  ///< the refined poses' log posteriors [nats]
  std::array<T, kMaxBasePairs> base_len;

  /// Per observation: left out of the alignment (no base pair, never an inlier, no term of the set
  /// likelihood); the caller's, reset by clear_map().
  std::array<bool, B::kMaxObservations> skip{};
  /// Where the sensor sits on the robot (the filter's; kept by clear_map()).
  Mount<T> mount{};
  /// A free-running counter (nullptr: none) and what set_log_likelihood spent by it since the caller
  /// zeroed count (the posterior scoring's row of the step's counts; kept by clear_map()). 16 bytes
  /// on 32- and 64-bit targets alike: the C API's storage sizes are one number for both.
  struct alignas(16) ScoreClock {
    std::uint32_t (*fn)() = nullptr;
    std::uint32_t count = 0;
  };
  mutable ScoreClock score;
  void clear_map() {
    n = 0;
    skip.fill(false);
  }
  /// @return kOk; kCapacityExceeded when MaxLandmarks are in; kNonFinite; kNotPositiveDefinite
  ///         for a P that is not a covariance. Nothing is added unless kOk.
  [[nodiscard]] Status push_landmark(const Vec2<T>& mean, const Mat2<T>& cov) {
    if (n >= B::kMaxLandmarks) return Status::kCapacityExceeded;
    if (!all_finite(mean) || !all_finite(cov)) return Status::kNonFinite;
    if (!(cov(0, 0) >= T(0) && cov(1, 1) >= T(0) && cov(0, 0) * cov(1, 1) >= cov(0, 1) * cov(1, 0))) {
      return Status::kNotPositiveDefinite;
    }
    m[n] = mean;
    P[n] = cov;
    index[n] = static_cast<std::int16_t>(n);
    ++n;
    return Status::kOk;
  }
};

namespace align_detail {

template <typename T>
Vec2<T> transform(const Pose2<T>& x, const Vec2<T>& q) {
  const T c = fmath::cos(x.theta), s = fmath::sin(x.theta);
  return Vec2<T>(x.x + c * q.x() - s * q.y(), x.y + s * q.x() + c * q.y());
}

/// Map index (sorted) of the landmark nearest (in d2) to observation i at pose x within the gate,
/// or -1; its d2 in `d2`. Bound: log2(n) + the landmarks in the x window.
template <typename T, class B>
int nearest(const AlignWorkspace<T, B>& ws, int i, const Pose2<T>& x, const Mat2<T>& Rot, T gate_d2, T& d2) {
  const Vec2<T> w = transform(x, ws.q[i]);
  const T lo_x = w.x() - ws.radius[i];
  int lo = 0, hi = ws.n;  // first landmark with x >= lo_x; <= log2(kMaxLandmarks) + 1 steps
  while (lo < hi) {
    const int mid = lo + (hi - lo) / 2;
    if (ws.m[mid].x() < lo_x)
      lo = mid + 1;
    else
      hi = mid;
  }
  const Mat2<T> Sw = Rot * ws.S[i] * Rot.transpose();
  int best = -1;
  d2 = std::numeric_limits<T>::infinity();
  for (int j = lo; j < ws.n && ws.m[j].x() <= w.x() + ws.radius[i]; ++j) {  // <= kMaxLandmarks
    const Vec2<T> e = w - ws.m[j];
    if (std::abs(e.y()) > ws.radius[i]) continue;
    const Mat2<T> S = Sw + ws.P[j];
    const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    if (!(det > T(0))) continue;
    const T q = (S(1, 1) * e.x() * e.x() - (S(0, 1) + S(1, 0)) * e.x() * e.y() + S(0, 0) * e.y() * e.y()) / det;
    if (q <= gate_d2 && q < d2) {
      d2 = q;
      best = j;
    }
  }
  return best;
}

template <typename T>
Mat2<T> rotation(T theta) {
  const T c = fmath::cos(theta), s = fmath::sin(theta);
  Mat2<T> r;
  r << c, -s, s, c;
  return r;
}

/// Inliers of pose x (a landmark may count twice here: scoring only). Stops early once even every
/// remaining observation could not reach `need`. Bound: m nearest() calls.
template <typename T, class B>
Candidate<T> score(const AlignWorkspace<T, B>& ws, int m, const Pose2<T>& x, T gate_d2, int need) {
  Candidate<T> c;
  c.pose = x;
  const Mat2<T> Rot = rotation(x.theta);
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (c.inliers + (m - i) < need) break;
    T d2 = T(0);
    if (!ws.skip[i] && nearest(ws, i, x, Rot, gate_d2, d2) >= 0) {
      ++c.inliers;
      c.cost += d2;
    }
  }
  return c;
}

template <typename T>
bool better(const Candidate<T>& a, const Candidate<T>& b) {
  return a.inliers > b.inliers || (a.inliers == b.inliers && a.cost < b.cost);
}

/// Keeps the kTopPoses best distinct poses, best first: a pose close to a kept one replaces it
/// when better, else it is dropped. Bound: kTopPoses.
template <typename T>
void offer(std::array<Candidate<T>, kTopPoses>& top, int& kept, const Candidate<T>& c, const AlignOptions<T>& opt) {
  for (int k = 0; k < kept; ++k) {  // <= kTopPoses
    if (distinct(top[k].pose, c.pose, opt)) continue;
    if (!better(c, top[k])) return;
    for (int q = k; q + 1 < kept; ++q) top[q] = top[q + 1];  // <= kTopPoses: take it out
    --kept;
    break;
  }
  int at = kept;                                  // where c goes
  while (at > 0 && better(c, top[at - 1])) --at;  // <= kTopPoses
  if (at >= kTopPoses) return;
  const int last = kept < kTopPoses ? kept : kTopPoses - 1;
  for (int q = last; q > at; --q) top[q] = top[q - 1];  // <= kTopPoses
  top[at] = c;
  if (kept < kTopPoses) ++kept;
}

/// Weighted 2-D Procrustes (rotation only) of the picked pairs: the pose minimising
/// sum w_i |R q_i + t - m_i|^2, w_i = 1 / tr(S_i + P_i). Needs >= 2 pairs.
template <typename T, class B>
[[gnu::cold]] Pose2<T> procrustes(const AlignWorkspace<T, B>& ws, int m) {
  T sw = T(0);
  Vec2<T> qc = Vec2<T>::Zero(), mc = Vec2<T>::Zero();
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (ws.pick[i] < 0) continue;
    const int j = ws.pick[i];
    const T w = T(1) / (ws.S[i].trace() + ws.P[j].trace());
    sw += w;
    qc += w * ws.q[i];
    mc += w * ws.m[j];
  }
  qc /= sw;
  mc /= sw;
  T sin_sum = T(0), cos_sum = T(0);
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (ws.pick[i] < 0) continue;
    const int j = ws.pick[i];
    const T w = T(1) / (ws.S[i].trace() + ws.P[j].trace());
    const Vec2<T> a = ws.q[i] - qc, b = ws.m[j] - mc;
    cos_sum += w * (a.x() * b.x() + a.y() * b.y());
    sin_sum += w * (a.x() * b.y() - a.y() * b.x());
  }
  Pose2<T> x;
  x.theta = fmath::atan2(sin_sum, cos_sum);
  const Mat2<T> Rot = rotation(x.theta);
  const Vec2<T> t = mc - Rot * qc;
  x.x = t.x();
  x.y = t.y();
  return x;
}

/// One Gauss-Newton step of the weighted fit over the picked pairs, from pose x: minimises
/// sum r_i^T S_i^-1 r_i, r_i = R q_i + t - m_i, S_i = R Sigma_i R^T + P_i, J_i = dr_i/d(x, y, theta)
/// = [I, dR/dtheta q_i]; `cov` gets (sum J_i^T S_i^-1 J_i)^-1 at x (the fit's covariance).
/// @return false when an S_i or the information is not positive definite (x, cov untouched).
template <typename T, class B>
bool gauss_newton_step(const AlignWorkspace<T, B>& ws, int m, Pose2<T>& x, Mat3<T>& cov) {
  const Mat2<T> Rot = rotation(x.theta);
  Mat2<T> dRot;
  dRot << -Rot(1, 0), -Rot(0, 0), Rot(0, 0), -Rot(1, 0);  // dR/dtheta
  Mat3<T> info = Mat3<T>::Zero();
  Vec3<T> grad = Vec3<T>::Zero();
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (ws.pick[i] < 0) continue;
    Mat23<T> J;
    J.template leftCols<2>() = Mat2<T>::Identity();
    J.col(2) = dRot * ws.q[i];
    const Vec2<T> r = Rot * ws.q[i] + Vec2<T>(x.x, x.y) - ws.m[ws.pick[i]];
    const Mat2<T> S = Rot * ws.S[i] * Rot.transpose() + ws.P[ws.pick[i]];
    const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    if (!(S(0, 0) > T(0) && det > T(0))) return false;
    Mat2<T> W;  // S^-1 in closed form (a matrix right-hand side would take Eigen's blocked solver)
    W << S(1, 1) / det, -S(0, 1) / det, -S(1, 0) / det, S(0, 0) / det;
    info += J.transpose() * W * J;
    grad += J.transpose() * (W * r);
  }
  const Eigen::LLT<Mat3<T>> llt(info);
  if (llt.info() != Eigen::Success) return false;
  Mat3<T> inv;
  for (int k = 0; k < 3; ++k) inv.col(k) = llt.solve(Vec3<T>::Unit(k));  // <= 3: vector solves
  const Mat3<T> c = symmetric_part(inv);
  const Vec3<T> dx = -(c * grad);
  if (!all_finite(c) || !all_finite(dx)) return false;
  x = Pose2<T>{x.x + dx(0), x.y + dx(1), wrap_angle(x.theta + dx(2))};
  cov = c;
  return true;
}

/// Map landmarks the sensor would see from pose x (view.max_range_m > 0) that no picked pair
/// holds: the misses of the set likelihood. Bound: n.
template <typename T, class B>
[[gnu::cold]] int misses(const AlignWorkspace<T, B>& ws, int m, const Pose2<T>& x, const AlignOptions<T>& opt) {
  int expected = 0;
  for (int j = 0; j < ws.n; ++j) {  // <= kMaxLandmarks
    const Vec2<T> z = observe(x, ws.mount, ws.m[j]);
    expected += z.x() >= opt.min_range_m && z.x() <= opt.max_range_m && std::abs(z.y()) <= opt.half_fov_rad;
  }
  int paired = 0;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (ws.pick[i] < 0) continue;
    const Vec2<T> z = observe(x, ws.mount, ws.m[ws.pick[i]]);
    paired += z.x() >= opt.min_range_m && z.x() <= opt.max_range_m && std::abs(z.y()) <= opt.half_fov_rad;
  }
  return expected - paired;
}

}  // namespace align_detail

namespace align_detail {
template <typename T, class B>
T set_log_likelihood_at(const AlignWorkspace<T, B>& ws, int m, const Pose2<T>& x, const AlignOptions<T>& view,
                        const SetModel<T>& model) {
  const Mat2<T> Rot = rotation(x.theta);
  const T log_2pi = fmath::log(T(2) * kPi<T>);
  T ll = T(0);
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (ws.skip[i]) continue;
    if (ws.pick[i] < 0) {
      ll += fmath::log(model.unexplained_density);
      continue;
    }
    const int j = ws.pick[i];
    const Vec2<T> e = Rot * ws.q[i] + Vec2<T>(x.x, x.y) - ws.m[j];
    const Mat2<T> S = Rot * ws.S[i] * Rot.transpose() + ws.P[j];
    const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    if (!(det > T(0))) return -std::numeric_limits<T>::infinity();
    const T d2 = (S(1, 1) * e.x() * e.x() - (S(0, 1) + S(1, 0)) * e.x() * e.y() + S(0, 0) * e.y() * e.y()) / det;
    ll += fmath::log(model.p_detect) - T(0.5) * d2 - log_2pi - T(0.5) * fmath::log(det);
  }
  const int missed = view.max_range_m > T(0) ? misses(ws, m, x, view) : 0;
  return ll + T(missed) * fmath::log(T(1) - model.p_detect);
}
}  // namespace align_detail
/// Log-likelihood [nats] of the hypothesis in ws.pick (per observation a sorted map index, or -1)
/// at pose x, over the map in ws and the observations align() prepared (ws.q, ws.S):
///   sum over pairs (log p_D - d2 / 2 - log|2 pi S| / 2)  S = R Sigma R^T + P_j, world frame
///   + (landmarks in view at x, not paired) log(1 - p_D) + (unpaired observations) log(density)
/// Bound: m + n.
/// Counted in ws.score.count when ws.score.fn is set.
template <typename T, class B>
[[gnu::noinline]] T set_log_likelihood(const AlignWorkspace<T, B>& ws, int m, const Pose2<T>& x,
                                       const AlignOptions<T>& view, const SetModel<T>& model) {
  const std::uint32_t t0 = ws.score.fn ? ws.score.fn() : 0;
  const T ll = align_detail::set_log_likelihood_at(ws, m, x, view, model);
  if (ws.score.fn) ws.score.count += ws.score.fn() - t0;
  return ll;
}

/// Exclusive inliers of pose x: each observation its nearest landmark in the gate; a landmark
/// taken twice keeps the observation with the smaller d2. Bound: m nearest() calls + m^2.
template <typename T, class B>
int exclusive_inliers(AlignWorkspace<T, B>& ws, int m, const Pose2<T>& x, T gate_d2) {
  const Mat2<T> Rot = align_detail::rotation(x.theta);
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    ws.pick[i] = ws.skip[i] ? std::int16_t(-1)
                            : static_cast<std::int16_t>(align_detail::nearest(ws, i, x, Rot, gate_d2, ws.pick_d2[i]));
  }
  int count = 0;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (ws.pick[i] < 0) continue;
    for (int k = 0; k < m; ++k) {  // <= kMaxObservations
      if (k == i || ws.pick[k] != ws.pick[i]) continue;
      if (ws.pick_d2[k] < ws.pick_d2[i] || (ws.pick_d2[k] == ws.pick_d2[i] && k < i)) {
        ws.pick[i] = -1;
        break;
      }
    }
    count += ws.pick[i] >= 0;
  }
  return count;
}

/// The accepted pose's sensitivity to the landmarks it was fitted to, for a relocalisation that
/// keeps the pose's correlation with the map (ekf::Slam::relocalise_fitted): over the pairs in
/// ws.pick at pose x (after align(), the accepted pose's exclusive inliers), with
/// W_i = (R Sigma_i R^T + P_j)^-1, J_i = [I, dR/dtheta q_i] and C = (sum J_i^T W_i J_i)^-1,
/// A_i = C J_i^T W_i (x moves by A_i when landmark j does); At[k] = A_i^T and map[k] = ws.pick[i]
/// (sorted map index) for the k-th pair; Pobs = sum A_i R Sigma_i R^T A_i^T, the observations'
/// part of the pose's covariance. @return the pairs (0 when the information is not positive
/// definite). Bound: 2 m.
template <typename T, class B>
int fit_sensitivities(const AlignWorkspace<T, B>& ws, int m, const Pose2<T>& x, Mat23<T>* At, std::int16_t* map,
                      Mat3<T>& Pobs) {
  using namespace align_detail;
  const Mat2<T> Rot = rotation(x.theta);
  Mat2<T> dRot;
  dRot << -Rot(1, 0), -Rot(0, 0), Rot(0, 0), -Rot(1, 0);  // dR/dtheta
  Mat3<T> info = Mat3<T>::Zero();
  int pairs = 0;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations: J_i^T W_i in At, for now
    if (ws.pick[i] < 0) continue;
    Mat23<T> J;
    J.template leftCols<2>() = Mat2<T>::Identity();
    J.col(2) = dRot * ws.q[i];
    const Mat2<T> S = Rot * ws.S[i] * Rot.transpose() + ws.P[ws.pick[i]];
    const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    if (!(S(0, 0) > T(0) && det > T(0))) return 0;
    Mat2<T> W;
    W << S(1, 1) / det, -S(0, 1) / det, -S(1, 0) / det, S(0, 0) / det;
    At[pairs] = (J.transpose() * W).transpose();  // W J (2x3)
    info += J.transpose() * W * J;
    map[pairs] = ws.pick[i];
    ++pairs;
  }
  const Eigen::LLT<Mat3<T>> llt(info);
  if (pairs < 2 || llt.info() != Eigen::Success) return 0;
  Mat3<T> C;
  for (int k = 0; k < 3; ++k) C.col(k) = llt.solve(Vec3<T>::Unit(k));  // <= 3: vector solves
  C = symmetric_part(C);
  Pobs = Mat3<T>::Zero();
  int k = 0;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (ws.pick[i] < 0) continue;
    At[k] = At[k] * C;  // (C J^T W)^T = W J C
    const Mat2<T> Sq = Rot * ws.S[i] * Rot.transpose();
    Pobs += At[k].transpose() * Sq * At[k];
    ++k;
  }
  Pobs = symmetric_part(Pobs);
  return all_finite(Pobs) ? pairs : 0;
}

/// The pose of the robot from one scan against the map in ws (see the file's head).
/// @return kOk (out written, accepted or not); kInvalidInput for bad options; the statuses of
///         validate_observations. Nothing is written to `out` unless kOk.
template <typename T, class B>
[[nodiscard, gnu::cold]] Status align(const Observations<T, B>& obs, const AlignOptions<T>& opt,
                                      AlignWorkspace<T, B>& ws, AlignResult<T, B>& out) {
  using namespace align_detail;
  if (!opt.valid()) return Status::kInvalidInput;
  Status st = validate_observations(obs);
  if (st != Status::kOk) return st;
  const int m = obs.count;
  const int n = ws.n;
  // The map sorted by x (insertion sort, stable; <= kMaxLandmarks^2 / 2 moves), the largest
  // landmark variance bound for the search windows.
  T map_tr = T(0);
  for (int j = 1; j < n; ++j) {  // <= kMaxLandmarks
    const Vec2<T> mj = ws.m[j];
    const Mat2<T> Pj = ws.P[j];
    const std::int16_t ij = ws.index[j];
    int k = j;
    while (k > 0 && ws.m[k - 1].x() > mj.x()) {  // <= kMaxLandmarks
      ws.m[k] = ws.m[k - 1];
      ws.P[k] = ws.P[k - 1];
      ws.index[k] = ws.index[k - 1];
      --k;
    }
    ws.m[k] = mj;
    ws.P[k] = Pj;
    ws.index[k] = ij;
  }
  for (int j = 0; j < n; ++j) map_tr = std::max(map_tr, ws.P[j].trace());  // <= kMaxLandmarks
  // Observed points and their covariances in the robot's frame (through the sensor's mount).
  const Pose2<T> origin{};
  Mat23<T>* const no_pose_jacobian = nullptr;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    Mat2<T> J;
    ws.q[i] = inverse_observe(origin, ws.mount, obs.z[i], no_pose_jacobian, &J);
    ws.S[i] = J * obs.R[i] * J.transpose();
    ws.radius[i] = std::sqrt(opt.gate_d2 * (ws.S[i].trace() + map_tr));  // >= the gate's extent
  }
  // Base pairs: the longest observed pairs, longest first (insertion into a short list).
  int bases = 0;
  std::array<T, kMaxBasePairs>& base_len = ws.base_len;
  for (int a = 0; a < m; ++a) {        // <= kMaxObservations
    for (int b = a + 1; b < m; ++b) {  // <= kMaxObservations
      if (ws.skip[a] || ws.skip[b]) continue;
      const T len = (ws.q[a] - ws.q[b]).norm();
      if (!(len >= opt.min_base_m)) continue;
      int at = bases;
      while (at > 0 && base_len[at - 1] < len) --at;  // <= kMaxBasePairs
      if (at >= opt.base_pairs) continue;
      const int last = bases < opt.base_pairs ? bases : opt.base_pairs - 1;
      for (int q = last; q > at; --q) {  // <= kMaxBasePairs
        base_len[q] = base_len[q - 1];
        ws.base[2 * q] = ws.base[2 * q - 2];
        ws.base[2 * q + 1] = ws.base[2 * q - 1];
      }
      base_len[at] = len;
      ws.base[2 * at] = static_cast<std::uint8_t>(a);
      ws.base[2 * at + 1] = static_cast<std::uint8_t>(b);
      if (bases < opt.base_pairs) ++bases;
    }
  }
  // Hypotheses from every map pair of a matching length, scored.
  int kept = 0;
  int scored = 0;
  bool truncated = false;
  for (int p = 0; p < bases && !truncated; ++p) {  // <= kMaxBasePairs
    const int a = ws.base[2 * p], b = ws.base[2 * p + 1];
    const Vec2<T> u = ws.q[b] - ws.q[a];
    const T len = base_len[p];
    const T var_u = pairwise_detail::norm_variance(u, Mat2<T>(ws.S[a] + ws.S[b]), len);
    const T angle_u = fmath::atan2(u.y(), u.x());
    const Vec2<T> mid_q = T(0.5) * (ws.q[a] + ws.q[b]);
    // Widest tolerance over the map (a quick reject before the exact test).
    const T tol_max = std::sqrt(opt.pair_d2 * (var_u + T(2) * map_tr));
    const T lo2 = len > tol_max ? (len - tol_max) * (len - tol_max) : T(0);
    const T hi2 = (len + tol_max) * (len + tol_max);
    for (int j = 0; j < n && !truncated; ++j) {        // <= kMaxLandmarks
      for (int k = j + 1; k < n && !truncated; ++k) {  // <= kMaxLandmarks
        const Vec2<T> v = ws.m[k] - ws.m[j];
        const T v2 = v.squaredNorm();
        if (v2 < lo2 || v2 > hi2) continue;
        const T len_v = std::sqrt(v2);
        const T var_v = pairwise_detail::norm_variance(v, Mat2<T>(ws.P[j] + ws.P[k]), len_v);
        const T e = len - len_v;
        if (e * e > opt.pair_d2 * (var_u + var_v)) continue;
        const T angle_v = fmath::atan2(v.y(), v.x());
        const Vec2<T> mid_m = T(0.5) * (ws.m[j] + ws.m[k]);
        for (int flip = 0; flip < 2; ++flip) {  // a->j, b->k; then a->k, b->j
          if (scored >= kMaxAlignHypotheses) {
            truncated = true;
            break;
          }
          Pose2<T> x;
          x.theta = wrap_angle(angle_v - angle_u + (flip ? kPi<T> : T(0)));
          const Vec2<T> t = mid_m - rotation(x.theta) * mid_q;
          x.x = t.x();
          x.y = t.y();
          if (opt.has_prior && !(prior_d2(opt, x) <= opt.prior_gate_d2)) continue;  // the prior rules it out
          ++scored;
          // A pose below the second kept can change neither the best nor its rival.
          const int need = kept >= 2 && ws.top[1].inliers > opt.min_inliers ? ws.top[1].inliers : opt.min_inliers;
          const Candidate<T> c = score(ws, m, x, opt.gate_d2, need);
          if (c.inliers >= opt.min_inliers) offer(ws.top, kept, c, opt);
        }
      }
    }
  }
  // Each kept pose refined (exclusive inliers, Procrustes, Gauss-Newton), its misses counted and
  // its log posterior scored; the most probable plausible one is the answer, the most probable
  // plausible one distinct from it its rival.
  // (From here on nothing fails: `out` is written in place, a local result would take the frame
  // over the controller's 512 bytes.)
  AlignResult<T, B>& r = out;
  r.accepted = false;
  r.pose = Pose2<T>{};
  r.cov = Mat3<T>::Zero();
  r.inliers = r.misses = r.rival_inliers = 0;
  r.score = r.rival_score = -std::numeric_limits<T>::infinity();
  r.ambiguous = false;
  r.hypotheses = scored;
  r.truncated = truncated;
  for (int i = 0; i < m; ++i) r.landmark[i] = -1;  // <= kMaxObservations
  int best = -1, rival = -1;
  std::array<Mat3<T>, kTopPoses>& cov = ws.top_cov;
  std::array<int, kTopPoses>& miss = ws.top_misses;
  std::array<bool, kTopPoses>& plausible = ws.top_plausible;
  std::array<T, kTopPoses>& post = ws.top_score;
  for (int k = 0; k < kept; ++k) {  // <= kTopPoses
    Candidate<T>& c = ws.top[k];
    bool ok = exclusive_inliers(ws, m, c.pose, opt.gate_d2) >= 3;
    if (ok) c.pose = procrustes(ws, m);
    for (int round = 0; ok && round < kRefineRounds; ++round) {  // <= kRefineRounds
      ok = exclusive_inliers(ws, m, c.pose, opt.gate_d2) >= 3 && gauss_newton_step(ws, m, c.pose, cov[k]);
    }
    c.inliers = exclusive_inliers(ws, m, c.pose, opt.gate_d2);
    miss[k] = opt.max_range_m > T(0) ? misses(ws, m, c.pose, opt) : 0;
    plausible[k] = ok && c.inliers >= opt.min_inliers &&
                   T(c.inliers) >= opt.min_inlier_ratio * T(c.inliers + miss[k]) &&
                   (!opt.has_prior || prior_d2(opt, c.pose) <= opt.prior_gate_d2);
    post[k] = set_log_likelihood(ws, m, c.pose, opt, opt.model) - T(0.5) * prior_d2(opt, c.pose);
    if (plausible[k] && (best < 0 || post[k] > post[best])) best = k;
  }
  for (int k = 0; k < kept; ++k) {  // <= kTopPoses
    if (k == best || !plausible[k] || (best >= 0 && !distinct(ws.top[k].pose, ws.top[best].pose, opt))) continue;
    if (rival < 0 || post[k] > post[rival]) rival = k;
  }
  if (kept > 0) {
    const int show = best >= 0 ? best : 0;
    r.pose = ws.top[show].pose;
    r.inliers = ws.top[show].inliers;
    r.misses = miss[show];
  }
  r.rival_inliers = rival >= 0 ? ws.top[rival].inliers : 0;
  if (best >= 0) r.score = post[best];
  if (rival >= 0) r.rival_score = post[rival];
  r.ambiguous = best >= 0 && rival >= 0 && !(post[best] >= post[rival] + opt.margin_nats);
  r.unmapped = false;
  if (best >= 0 && !r.ambiguous && opt.test_unmapped) {
    T none = T(0);
    for (int i = 0; i < m; ++i) none += ws.skip[i] ? T(0) : fmath::log(opt.model.unexplained_density);  // <= m
    // log sqrt det C of the fit's covariance from its Cholesky factor (C not positive definite: unmapped)
    const Eigen::LLT<Mat3<T>> llt(cov[best]);
    const Vec3<T> l = llt.matrixL().toDenseMatrix().diagonal();
    const T half_logdet = fmath::log(l(0)) + fmath::log(l(1)) + fmath::log(l(2));
    const T occam = opt.has_prior ? -opt.prior_half_logdet : T(1.5) * fmath::log(T(2) * kPi<T>) - opt.free_log_volume;
    r.unmapped = llt.info() != Eigen::Success || !(post[best] + half_logdet + occam >= none + opt.margin_nats);
  }
  if (best >= 0 && !r.ambiguous && !r.unmapped) {
    exclusive_inliers(ws, m, ws.top[best].pose, opt.gate_d2);
    r.accepted = true;
    r.cov = cov[best];
    for (int i = 0; i < m; ++i) r.landmark[i] = ws.pick[i] < 0 ? std::int16_t(-1) : ws.index[ws.pick[i]];
  }
  return Status::kOk;
}

}  // namespace geojcbb::reloc
