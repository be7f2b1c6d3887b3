// reloc: a few pose hypotheses kept while a scan is ambiguous, until one wins (the hypothesis
// window). A hypothesis is a pose-only EKF (3 states) against the frozen map: the confirmed
// landmarks of the local region, each with its own 2x2 covariance and no correlations. On a scan
// it pairs the observations one after another (the nearest free landmark within the individual
// gate, at the pose its earlier pairs this scan have updated) and scores what it did with the set
// likelihood of reloc/loop.hpp, the pairs' terms being the sequential (marginal) likelihood
// log p_D + log N(nu; 0, S), S = Jx P Jx^T + Jl P_l Jl^T + R, so the pose prior is in the score:
//   sum over pairs (log p_D - d2 / 2 - log|2 pi S| / 2)
//   + (landmarks in view at the pose, not paired) log(1 - p_D) + (unpaired observations) log(density)
// node::HypothesisWindow (node/stages/hypothesis_window.hpp) runs it (docs/hypotheses.md): a scan whose seeds (the
// association's pairs, and one seed per compatible landmark of up to kMaxAnchors ambiguous
// observations) include two conflicting ones within the margin, or a seed that conflicts with the
// association's and beats it, opens the window with at most kMaxHypotheses conflicting seeds (the
// association's among them); each later scan adds each hypothesis's score; one that leads every
// other by the margin closes the window, and is committed as a correction of the pose unless it is
// the association's; at the end of the window, nothing is. Meanwhile the association's pairs stand,
// or (hypothesis_hold) the observations the hypotheses pair differently are held.
// Bounds: a seed or a hypothesis's scan is O(m n) (m observations, n frozen landmarks).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/fmath.hpp"
#include "geojcbb/reloc/align.hpp"
#include "geojcbb/reloc/loop.hpp"

namespace geojcbb::reloc {

/// Hypotheses kept in the window, at most.
constexpr int kMaxHypotheses = 3;
/// Ambiguous observations (two or more compatible landmarks) that seed hypotheses, at most, and
/// the compatible landmarks of each that do (the nearest).
constexpr int kMaxAnchors = 3;
constexpr int kMaxAnchorChoices = 3;
/// Seeds of an opening scan: the association's, and one per anchor choice.
constexpr int kMaxSeeds = 1 + kMaxAnchors * kMaxAnchorChoices;
/// Pairs a hypothesis needs on a scan to be a pose in doubt (to open a window, or to be committed):
/// one pair leaves the heading free, and a single observation's doubt is the gate's business.
constexpr int kMinPosePairs = 2;

/// A pose-only filter and what it scored. Left uninitialised (set before it is read): a static
/// step's arrays of them then need no start-up code.
template <typename T>
struct PoseHypothesis {
  Pose2<T> x;
  Mat3<T> P;
  T ll;  ///< set log-likelihood [nats], summed over the window's scans
};

/// What the window did with one scan.
enum class WindowVerdict : std::uint8_t {
  kNone = 0,   ///< off, not tracking, a loop closure's scan, or no ambiguity
  kOpened,     ///< this scan opened the window: the observations the hypotheses pair differently held
  kHeld,       ///< the window is open and no hypothesis leads by the margin: disputed observations held
  kCommitted,  ///< a hypothesis led by the margin: its pairs replace the association's
  kExpired,    ///< the window ended without a leader: disputed observations held, nothing committed
  kMerged,     ///< the hypotheses paired this scan alike: the window closed, the association stands
};

template <typename T>
struct WindowStats {
  WindowVerdict verdict = WindowVerdict::kNone;
  int seeds = 0;       ///< scored on an opening scan
  int hypotheses = 0;  ///< kept in the window after this scan
  int held = 0;        ///< observations held (kOpened, kHeld, kExpired) or re-paired (kCommitted)
  T lead = T(0);       ///< the leader's score over the runner-up's [nats] (window open)
  int regrouped = 0;   ///< observations cluster_first paired anew (before the window's part)
};

/// Range-bearing innovation of observation i against frozen landmark j at (x, P): nu, S, Jx.
/// @return d2 = nu^T S^-1 nu; +inf when S is not positive definite or the landmark is at the
///         sensor (map.mount on the robot at x).
template <typename T, class B>
T pair_d2(const Observations<T, B>& obs, int i, const AlignWorkspace<T, B>& map, int j, const Pose2<T>& x,
          const Mat3<T>& P, Vec2<T>& nu, Mat2<T>& S, Mat23<T>& Jx) {
  const Pose2<T> xs = sensor_pose(x, map.mount);
  const Vec2<T> d = map.m[j] - Vec2<T>(xs.x, xs.y);
  if (!(d.squaredNorm() > T(1e-12))) return std::numeric_limits<T>::infinity();
  Mat2<T> Jl;
  const Vec2<T> h = observe(x, map.mount, map.m[j], &Jx, &Jl);
  nu = innovation(obs.z[i], h);
  S = Jx * P * Jx.transpose() + Jl * map.P[j] * Jl.transpose() + obs.R[i];
  const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
  if (!(det > T(0)) || !(S(0, 0) > T(0))) return std::numeric_limits<T>::infinity();
  return (S(1, 1) * nu.x() * nu.x() - (S(0, 1) + S(1, 0)) * nu.x() * nu.y() + S(0, 0) * nu.y() * nu.y()) / det;
}

namespace window_detail {

/// The EKF update of the pose filter with one pair; @return its log-likelihood term
/// log p_D - d2 / 2 - log|2 pi S| / 2.
template <typename T>
T update(PoseHypothesis<T>& h, const Vec2<T>& nu, const Mat2<T>& S, const Mat23<T>& Jx, T d2, T log_pd) {
  const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
  Mat2<T> Si;
  Si << S(1, 1) / det, -S(0, 1) / det, -S(1, 0) / det, S(0, 0) / det;
  const Eigen::Matrix<T, 3, 2> K = h.P * Jx.transpose() * Si;
  const Vec3<T> dx = K * nu;
  h.x.x += dx.x();
  h.x.y += dx.y();
  h.x.theta = wrap_angle(h.x.theta + dx.z());
  const Mat3<T> IKH = Mat3<T>::Identity() - K * Jx;
  const Mat2<T> R = S - Jx * h.P * Jx.transpose();            // the pair's own part (measurement and landmark)
  h.P = IKH * h.P * IKH.transpose() + K * R * K.transpose();  // Joseph form
  h.P = T(0.5) * (h.P + h.P.transpose());
  return log_pd - T(0.5) * d2 - fmath::log(T(2) * kPi<T>) - T(0.5) * fmath::log(det);
}

}  // namespace window_detail

/// One scan of one hypothesis: the pairs already in map.pick (seeds: the association's pairs or an
/// anchor) applied first in observation order, then, with `grow`, each observation left takes the
/// nearest free landmark within gate_d2 at the pose the pairs before it left; then the unpaired
/// observations and the misses. Pairs whose d2 exceeds gate_d2 (or whose S is not definite) are
/// dropped from map.pick. Observations with map.skip are left out. h is updated in place.
/// @return the scan's set log-likelihood [nats]. Bound: m n + n.
template <typename T, class B>
[[gnu::cold]] T run_hypothesis(const Observations<T, B>& obs, AlignWorkspace<T, B>& map, const SetModel<T>& model,
                               const AlignOptions<T>& view, T gate_d2, bool grow, PoseHypothesis<T>& h) {
  using namespace window_detail;
  const int m = obs.count;
  const T log_pd = fmath::log(model.p_detect);
  std::array<std::uint32_t, (B::kMaxLandmarks + 31) / 32> taken{};
  auto take = [&](int j) { taken[static_cast<std::size_t>(j / 32)] |= std::uint32_t(1) << (j % 32); };
  auto free = [&](int j) { return (taken[static_cast<std::size_t>(j / 32)] & (std::uint32_t(1) << (j % 32))) == 0; };
  T ll = T(0);
  Vec2<T> nu;
  Mat2<T> S;
  Mat23<T> Jx;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations: the given pairs
    const int j = map.pick[i];
    if (j < 0 || map.skip[i]) {
      map.pick[i] = -1;
      continue;
    }
    const T d2 = pair_d2(obs, i, map, j, h.x, h.P, nu, S, Jx);
    if (!free(j) || !(d2 <= gate_d2)) {
      map.pick[i] = -1;
      continue;
    }
    take(j);
    map.pick_d2[i] = d2;
    ll += update(h, nu, S, Jx, d2, log_pd);
  }
  for (int i = 0; i < m && grow; ++i) {  // <= kMaxObservations: the nearest free landmark
    if (map.pick[i] >= 0 || map.skip[i]) continue;
    int best = -1;
    T best_d2 = gate_d2;
    for (int j = 0; j < map.n; ++j) {  // <= kMaxLandmarks
      if (!free(j)) continue;
      const T d2 = pair_d2(obs, i, map, j, h.x, h.P, nu, S, Jx);
      if (d2 <= best_d2) {
        best_d2 = d2;
        best = j;
      }
    }
    if (best < 0) continue;
    (void)pair_d2(obs, i, map, best, h.x, h.P, nu, S, Jx);
    map.pick[i] = static_cast<std::int16_t>(best);
    take(best);
    map.pick_d2[i] = best_d2;
    ll += update(h, nu, S, Jx, best_d2, log_pd);
  }
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    // The density is per m^2; per (m, rad) of the range-bearing space it is density * range.
    if (map.pick[i] < 0 && !map.skip[i]) ll += fmath::log(model.unexplained_density * std::max(obs.z[i].x(), T(0.1)));
  }
  const int missed = view.max_range_m > T(0) ? align_detail::misses(map, m, h.x, view) : 0;
  return ll + T(missed) * fmath::log(T(1) - model.p_detect);
}

/// The pairs of a pairing (entries >= 0). Bound: m.
inline int pairs(const std::int16_t* pick, int m) {
  int n = 0;
  for (int i = 0; i < m; ++i) n += pick[i] >= 0;  // <= kMaxObservations
  return n;
}

/// Two pairings conflict when an observation is paired with different landmarks, or a landmark
/// with different observations. Bound: m^2.
inline bool conflict(const std::int16_t* a, const std::int16_t* b, int m) {
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (a[i] < 0) continue;
    for (int k = 0; k < m; ++k) {  // <= kMaxObservations
      if (b[k] == a[i] && k != i) return true;
    }
    if (b[i] >= 0 && b[i] != a[i]) return true;
  }
  return false;
}

}  // namespace geojcbb::reloc
