// ekf: the filter's prediction, ekf::Slam's predict (odometry, or a pose increment), apply_motion
// and predict_local; declared and documented in ekf/slam.hpp, defined here. In: the motion, or the
// local radius r + d (eq. 5); out: the pose moved with its covariance rows, or the prediction (ids,
// h_j, C = H P H^T). Bounds: predict O(n); predict_local O(n kMaxCandidates + kMaxCandidates^2).
// Definitions are `inline` where the in-class ones were implicitly so (not the gnu::noinline ones).
#pragma once

#include <cmath>
#include <cstdint>

#include "geojcbb/core/fmath.hpp"
#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/ekf/motion.hpp"
#include "geojcbb/ekf/slam.hpp"

namespace geojcbb::ekf {

template <typename T, class B>
Status Slam<T, B>::predict(const Odometry<T>& u) {
  if (!std::isfinite(u.v_mps) || !std::isfinite(u.w_radps) || !std::isfinite(u.dt_s) || !std::isfinite(u.sigma_v_mps) ||
      !std::isfinite(u.sigma_w_radps)) {
    return Status::kNonFinite;
  }
  if (u.dt_s < T(0) || u.sigma_v_mps < T(0) || u.sigma_w_radps < T(0)) return Status::kInvalidInput;
  Mat3<T> F;
  Mat32<T> G;
  const Pose2<T> next = move(pose(), u, &F, &G);
  const Mat2<T> Q = Vec2<T>(u.sigma_v_mps * u.sigma_v_mps, u.sigma_w_radps * u.sigma_w_radps).asDiagonal();
  return apply_motion(next, F, G * Q * G.transpose());
}

template <typename T, class B>
inline Status Slam<T, B>::predict(const PoseIncrement<T>& u) {
  if (!std::isfinite(u.dx_m) || !std::isfinite(u.dy_m) || !std::isfinite(u.dtheta_rad) || !u.cov.allFinite()) {
    return Status::kNonFinite;
  }
  if (!is_psd3(u.cov)) return Status::kNotPositiveDefinite;
  Mat3<T> F, J;
  const Pose2<T> next = compose(pose(), u, &F, &J);
  return apply_motion(next, F, J * symmetric_part(u.cov) * J.transpose());
}

template <typename T, class B>
Status Slam<T, B>::apply_motion(const Pose2<T>& next, Mat3<T> F, const Mat3<T>& Qx) {
  if (options_.first_estimates_jacobians && updated_) {
    // FEJ: the displacement from the pose before the last update, not from the updated pose.
    F(0, 2) -= x_[1] - prior_[1];
    F(1, 2) += x_[0] - prior_[0];
  }
  const Mat3<T> Prr = F * P_.template block<3, 3>(0, 0) * F.transpose() + Qx;
  // Finite inputs can still overflow (speeds or sigmas near the scalar's max): check the new
  // pose and covariance before writing any of them.
  if (!std::isfinite(next.x) || !std::isfinite(next.y) || !std::isfinite(next.theta) || !Prr.allFinite()) {
    return Status::kNonFinite;
  }
  // Finite but singular by rounding (a sigma near 1e19 in float: the motion noise swamps the
  // pose's own covariance, and the correlation of x and y, both driven by one sigma_v, rounds to
  // 1): refused, nothing changed (fuzz_associate's finding).
  const Mat3<T> Prr_sym = symmetric_part(Prr);
  if (!is_spd_scaled<T>(Prr_sym)) return Status::kNotPositiveDefinite;
  for (int j = 0; j < landmarks(); ++j) {  // <= kMaxLandmarks
    if (!(F * P_.template block<3, 2>(0, Layout::landmark(j))).allFinite()) return Status::kNonFinite;
  }
  P_.template set_sym<3>(0, Prr_sym);
  for (int j = 0; j < landmarks(); ++j) {  // <= kMaxLandmarks: only the pose rows change, O(n)
    const int l = Layout::landmark(j);
    P_.template set_block<3, 2>(0, l, F * P_.template block<3, 2>(0, l));
  }
  x_[0] = next.x;
  x_[1] = next.y;
  x_[2] = next.theta;
  updated_ = false;
  return Status::kOk;
}

template <typename T, class B>
inline Status Slam<T, B>::predict_local(T radius_m, SlamWorkspace<T, B>& ws, Prediction<T, B>& out,
                                        LocalMapStats& stats, bool confirmed_first, T half_fov_rad) const {
  if (!(std::isfinite(radius_m) && radius_m > T(0))) return Status::kInvalidInput;
  if (!(half_fov_rad > T(0) && half_fov_rad <= kPi<T>)) return Status::kInvalidInput;
  auto& idx = ws.cand;
  auto& rng = ws.cand_range;
  auto& Hp = ws.cand_Hp;
  auto& Hl = ws.cand_Hl;
  int n = 0;
  stats = LocalMapStats{};
  const Pose2<T> xr = pose();
  // Behind: cos(bearing) < cos((half_fov + pi) / 2) = -sin(half_fov / 2); ranked after every
  // landmark in view (its range + radius_m).
  const T back_cos = -fmath::sin(half_fov_rad / T(2));
  const Vec2<T> ahead(fmath::cos(xr.theta), fmath::sin(xr.theta));
  for (int j = 0; j < landmarks(); ++j) {  // <= kMaxLandmarks; insertion keeps the nearest kMaxCandidates
    const Vec2<T> d = landmark(j) - Vec2<T>(xr.x, xr.y);
    const T dist = d.norm();
    if (!(dist < radius_m) || !(dist > T(0))) continue;
    const T r = d.dot(ahead) < back_cos * dist ? dist + radius_m : dist;
    ++stats.in_region;
    int k = n;
    if (n < B::kMaxCandidates) {
      ++n;
    } else {
      stats.truncated = true;
      if (!(r < rng[n - 1])) continue;  // farther than every kept candidate
      k = n - 1;                        // the farthest kept candidate makes room
    }
    for (; k > 0 && rng[k - 1] > r; --k) {  // <= kMaxCandidates
      rng[k] = rng[k - 1];
      idx[k] = idx[k - 1];
    }
    rng[k] = r;
    idx[k] = static_cast<std::uint16_t>(j);
  }
  for (int a = 0; a < n; ++a) {  // <= kMaxCandidates: the kept ones by range (behind ones in place)
    if (rng[a] >= radius_m) rng[a] -= radius_m;
  }
  for (int a = 1; a < n; ++a) {  // <= kMaxCandidates, insertion sort: O(kMaxCandidates^2)
    const T r = rng[a];
    const std::uint16_t i = idx[a];
    int k = a;
    for (; k > 0 && rng[k - 1] > r; --k) {  // <= kMaxCandidates
      rng[k] = rng[k - 1];
      idx[k] = idx[k - 1];
    }
    rng[k] = r;
    idx[k] = i;
  }
  stats.confirmed = n;
  if (confirmed_first) {  // stable partition, the confirmed first
    std::uint16_t tentative[B::kMaxCandidates];
    int c = 0, t = 0;
    for (int a = 0; a < n; ++a) {  // <= kMaxCandidates
      if (book_.confirmed(idx[a])) {
        idx[c++] = idx[a];
      } else {
        tentative[t++] = idx[a];
      }
    }
    for (int a = 0; a < t; ++a) idx[c + a] = tentative[a];  // <= kMaxCandidates
    stats.confirmed = c;
  }
  const Status sized = out.C.resize(n);  // n <= kMaxCandidates by the insertion above
  if (sized != Status::kOk) return sized;
  out.count = n;
  for (int a = 0; a < n; ++a) {  // <= kMaxCandidates
    out.id[a] = id(idx[a]);
    out.h[a] = observe(xr, mount_, landmark(idx[a]));
    observe(xr, mount_, linearisation_point(idx[a]), &Hp[a], &Hl[a]);
  }
  const Mat3<T> Prr = P_.template block<3, 3>(0, 0);
  for (int a = 0; a < n; ++a) {  // <= kMaxCandidates
    const int la = Layout::landmark(idx[a]);
    // Row a of H P: the 2 x 3 pose part and, per b, the 2 x 2 landmark part.
    const Mat23<T> HPr = Hp[a] * Prr + Hl[a] * P_.template block<3, 2>(0, la).transpose();  // P_lr = P_rl^T
    for (int b = 0; b <= a; ++b) {                                                          // <= kMaxCandidates
      const int lb = Layout::landmark(idx[b]);
      const Mat2<T> HPl = Hp[a] * P_.template block<3, 2>(0, lb) + Hl[a] * P_.template block<2, 2>(la, lb);
      Mat2<T> Cab = HPr * Hp[b].transpose() + HPl * Hl[b].transpose();
      if (a == b) Cab = symmetric_part(Cab);
      out.C.set_block(a, b, Cab);  // block (b, a) = Cab^T: C is stored as its lower block triangle
    }
  }
  return Status::kOk;
}

}  // namespace geojcbb::ekf
