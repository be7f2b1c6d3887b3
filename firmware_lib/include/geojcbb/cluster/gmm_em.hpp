// cluster: Gaussian-mixture clustering by EM (2019 paper, eqs. 6-13; GEMJCBB and GEOJCBB).
//   E-step (eq. 8): gamma_jk = pi_k N(z_j; mu_k, Sigma_k) / sum_l pi_l N(z_j; mu_l, Sigma_l), in logs
//                  with log-sum-exp (the paper warns of underflow).
//   M-step (eqs. 11-13): N_k = sum_j gamma_jk, mu_k = sum_j gamma_jk z_j / N_k, pi_k = N_k / m, and
//                  Sigma_k = (S_k + eps I) / N_k with S_k = sum_j gamma_jk (z_j - mu_k)(z_j - mu_k)^T.
// The floor eps (m^2) is the MAP estimate under the penalty -eps/2 tr(Sigma_k^-1). It keeps a
// component on one point, or on collinear points, positive definite. EM then never decreases
// Q = LL - eps/2 sum_k tr(Sigma_k^-1) (LL of eq. 10). A component whose N_k falls below
// kMinComponentWeight is dropped.
// Labels by arg max gamma (eq. 9). K is fixed, or chosen in [1, min(MaxGroups, m)] by BIC.
// Everything in the Scalar T, the BIC included (float on the controller: no soft-float double).
// Start (EmOptions::start): hard responsibilities to the nearest farthest-first seed, or (default,
// packed covariance) to the k-means groups from those seeds. Stop (EmOptions::stop): the
// papers' objective tolerance, or (default, packed covariance) also once the groups are
// stable (core/grouping_options.hpp).
// Bounds: max_iterations <= kMaxEmIterations per fit (and kMaxKMeansIterations for the k-means
// start); K fits when choosing by BIC.
#pragma once

#include "geojcbb/cluster/groups.hpp"
#include "geojcbb/cluster/kmeans.hpp"
#include "geojcbb/core/grouping_options.hpp"

namespace geojcbb {

template <typename T>
struct EmStats {
  int components = 0;        ///< components of the chosen fit
  int iterations = 0;        ///< EM iterations of the chosen fit
  int total_iterations = 0;  ///< over every fit (BIC tries several K)
  bool converged = false;    ///< the chosen fit met its stop rule before the iteration bound
  T objective = T(0);        ///< Q of the chosen fit
  T log_likelihood = T(0);   ///< LL (eq. 10) of the chosen fit
};

/// The EM state, exposed for tests (objective trace) and reuse across BIC fits.
template <typename T, class B>
struct EmWorkspace {
  static constexpr int K = B::kMaxGroups;
  int k = 0;
  std::array<T, K> log_pi;
  std::array<Vec2<T>, K> mu;
  std::array<Mat2<T>, K> sigma;
  std::array<std::array<T, K>, B::kMaxObservations> gamma;
  std::array<T, kMaxEmIterations + 1> trace;  ///< Q after each E-step
  int trace_length = 0;
  T ll = T(0);                                         ///< LL (eq. 10) at the last E-step
  std::array<std::int8_t, B::kMaxObservations> label;  ///< arg max gamma at the last E-step
  bool hard = false;  ///< at the last E-step every point's largest gamma was >= 1 - hard_margin
  // E-step scratch, here rather than in e_step's frame: on the Cortex-M4F the chain associate ->
  // group -> gmm_em -> e_step was 1080 B with them on the stack (the call-chain limit is 1024 B).
  std::array<T, K> e_log_norm;
  std::array<Mat2<T>, K> e_inv;
};

namespace em_detail {

template <typename T>
constexpr T kLog2Pi = T(1.8378770664093454836);
template <typename T>
constexpr T kMinComponentWeight = T(1e-3);

/// E-step: responsibilities, their arg max (eq. 9) and Q; returns how many labels changed.
/// Bound: m * k.
template <typename T, class B>
int e_step(const Points<T, B>& pts, int m, T floor, T hard_margin, EmWorkspace<T, B>& ws, T& q_out) {
  std::array<T, B::kMaxGroups>& log_norm = ws.e_log_norm;
  std::array<Mat2<T>, B::kMaxGroups>& inv = ws.e_inv;
  T penalty = T(0);
  for (int q = 0; q < ws.k; ++q) {  // <= kMaxGroups
    const Mat2<T>& S = ws.sigma[q];
    const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    const T r = T(1) / det;
    inv[q] << S(1, 1) * r, -S(0, 1) * r, -S(1, 0) * r, S(0, 0) * r;
    log_norm[q] = ws.log_pi[q] - kLog2Pi<T> - T(0.5) * fmath::log(det);
    penalty += T(0.5) * floor * (inv[q](0, 0) + inv[q](1, 1));
  }
  T ll = T(0);
  int changed = 0;
  bool hard = true;
  for (int j = 0; j < m; ++j) {  // <= kMaxObservations
    T mx = -std::numeric_limits<T>::infinity();
    int arg = 0;
    for (int q = 0; q < ws.k; ++q) {  // <= kMaxGroups
      const Vec2<T> d = pts[j] - ws.mu[q];
      const T lp = log_norm[q] - T(0.5) * d.dot(inv[q] * d);
      ws.gamma[j][q] = lp;
      if (lp > mx) {
        mx = lp;
        arg = q;
      }
    }
    // exp(lp - mx) once per component; gamma is its share of the sum (no second exp).
    T sum = T(0);
    for (int q = 0; q < ws.k; ++q) {  // <= kMaxGroups
      ws.gamma[j][q] = fmath::exp(ws.gamma[j][q] - mx);
      sum += ws.gamma[j][q];
    }
    const T r = T(1) / sum;
    for (int q = 0; q < ws.k; ++q) ws.gamma[j][q] *= r;  // <= kMaxGroups
    ll += mx + fmath::log(sum);
    hard = hard && r >= T(1) - hard_margin;  // gamma_j,arg = 1 / sum
    changed += ws.label[j] != arg;
    ws.label[j] = static_cast<std::int8_t>(arg);
  }
  ws.ll = ll;
  ws.hard = hard;
  q_out = ll - penalty;
  return changed;
}

/// M-step; drops components whose weight vanished. Bound: m * k.
template <typename T, class B>
void m_step(const Points<T, B>& pts, int m, T floor, EmWorkspace<T, B>& ws) {
  int kept = 0;
  for (int q = 0; q < ws.k; ++q) {  // <= kMaxGroups
    T n = T(0);
    Vec2<T> s = Vec2<T>::Zero();
    for (int j = 0; j < m; ++j) {  // <= kMaxObservations
      n += ws.gamma[j][q];
      s += ws.gamma[j][q] * pts[j];
    }
    if (!(n >= kMinComponentWeight<T>)) continue;
    const Vec2<T> mu = s / n;
    Mat2<T> S = Mat2<T>::Identity() * floor;
    for (int j = 0; j < m; ++j) {  // <= kMaxObservations
      const Vec2<T> d = pts[j] - mu;
      S += ws.gamma[j][q] * (d * d.transpose());
    }
    ws.mu[kept] = mu;
    ws.sigma[kept] = S / n;
    ws.log_pi[kept] = fmath::log(n / static_cast<T>(m));
    for (int j = 0; j < m; ++j) ws.gamma[j][kept] = ws.gamma[j][q];  // <= kMaxObservations
    ++kept;
  }
  ws.k = kept;
}

/// One EM fit with k components from hard responsibilities: to the groups `start` (the k-means
/// start, computed by the caller so that k-means and this fit do not stack their frames) or, when
/// null, to the nearest farthest-first seed.
template <typename T, class B>
EmStats<T> fit(const Points<T, B>& pts, int m, int k, const EmOptions<T>& opt, const Groups<B>* start,
               EmWorkspace<T, B>& ws) {
  EmStats<T> st;
  if (start != nullptr) {
    ws.k = start->count;
    for (int j = 0; j < m; ++j) ws.label[j] = start->label[j];  // <= kMaxObservations
  } else {
    std::array<Vec2<T>, B::kMaxGroups> seeds;
    ws.k = farthest_first<T, B>(pts, m, k, seeds);
    for (int j = 0; j < m; ++j) {  // <= kMaxObservations: the nearest seed
      int arg = 0;
      for (int q = 1; q < ws.k; ++q) {  // <= kMaxGroups
        if ((pts[j] - seeds[q]).squaredNorm() < (pts[j] - seeds[arg]).squaredNorm()) arg = q;
      }
      ws.label[j] = static_cast<std::int8_t>(arg);
    }
  }
  for (int j = 0; j < m; ++j) {  // <= kMaxObservations: hard responsibilities
    for (int q = 0; q < ws.k; ++q) ws.gamma[j][q] = q == ws.label[j] ? T(1) : T(0);  // <= kMaxGroups
  }
  const T floor = opt.covariance_floor_m2;
  const bool by_groups = opt.stop == EmStop::kGroupsStable;
  int k_before = ws.k;
  m_step(pts, m, floor, ws);
  ws.trace_length = 0;
  T q_old = T(0);
  // Labels are compared with the previous labels (the start's, then each E-step's), under the same
  // numbering only: not after the M-step dropped a component.
  int changed = e_step(pts, m, floor, opt.hard_margin, ws, q_old);
  ws.trace[ws.trace_length++] = q_old;
  int stable = changed == 0 && ws.k == k_before && ws.hard ? 1 : 0;
  for (int it = 0; it < opt.max_iterations; ++it) {      // <= kMaxEmIterations
    if (by_groups && stable >= opt.stable_iterations) {  // the start's groups came out unchanged
      st.converged = true;
      break;
    }
    k_before = ws.k;
    m_step(pts, m, floor, ws);
    T q_new = T(0);
    changed = e_step(pts, m, floor, opt.hard_margin, ws, q_new);
    ws.trace[ws.trace_length++] = q_new;
    st.iterations = it + 1;
    stable = changed == 0 && ws.k == k_before && ws.hard ? stable + 1 : 0;
    const bool flat = q_new - q_old <= opt.tolerance * (T(1) + std::abs(q_old));
    q_old = q_new;
    if (flat || (by_groups && stable >= opt.stable_iterations)) {
      st.converged = true;
      break;
    }
  }
  st.components = ws.k;
  st.total_iterations = st.iterations;
  st.objective = q_old;
  st.log_likelihood = ws.ll;
  return st;
}

}  // namespace em_detail

/// Groups the points by a Gaussian mixture fitted with EM.
/// @param k  components, 1 .. MaxGroups (clamped to m); 0 chooses K in [1, min(MaxGroups, m)] by BIC
/// @return statistics of the chosen fit; `out` holds the groups (labels by arg max gamma, eq. 9).
/// Iterations are clamped to [1, kMaxEmIterations], stable_iterations to [1, max_iterations].
template <typename T, class B>
EmStats<T> gmm_em(const Points<T, B>& pts, int m, int k, EmOptions<T> opt, EmWorkspace<T, B>& ws, Groups<B>& out) {
  EmStats<T> best;
  if (m == 0) {
    out.count = 0;
    return best;
  }
  opt.max_iterations =
      opt.max_iterations < 1 ? 1 : (opt.max_iterations > kMaxEmIterations ? kMaxEmIterations : opt.max_iterations);
  opt.stable_iterations = opt.stable_iterations < 1 ? 1 : opt.stable_iterations;
  const int k_cap = m < B::kMaxGroups ? m : B::kMaxGroups;
  const bool by_bic = k <= 0;
  const int k_lo = by_bic ? 1 : (k < k_cap ? k : k_cap);
  const int k_hi = by_bic ? k_cap : k_lo;
  T best_bic = std::numeric_limits<T>::infinity();
  const T log_m = by_bic ? fmath::log(static_cast<T>(m)) : T(0);
  int total = 0;
  for (int kk = k_lo; kk <= k_hi; ++kk) {  // <= kMaxGroups fits
    Groups<B> start;
    if (opt.start == EmStart::kKMeans) kmeans(pts, m, kk, kMaxKMeansIterations, start);
    const EmStats<T> st = em_detail::fit(pts, m, kk, opt, opt.start == EmStart::kKMeans ? &start : nullptr, ws);
    total += st.iterations;
    // BIC = -2 LL + p ln m with p = 6K - 1 free parameters (2 mean + 3 covariance + 1 weight each).
    const T bic = T(-2) * st.log_likelihood + static_cast<T>(6 * st.components - 1) * log_m;
    if (!by_bic || bic < best_bic) {
      best_bic = bic;
      best = st;
      for (int j = 0; j < m; ++j) out.label[j] = ws.label[j];  // <= kMaxObservations: eq. 9
    }
  }
  best.total_iterations = total;
  compact_labels(m, out);
  return best;
}

}  // namespace geojcbb
