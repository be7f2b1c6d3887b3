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
// Bounds: max_iterations <= kMaxEmIterations per fit; K fits when choosing by BIC.
#pragma once

#include "geojcbb/cluster/groups.hpp"

namespace geojcbb {

constexpr int kMaxEmIterations = 50;

struct EmStats {
  int components = 0;     ///< components of the chosen fit
  int iterations = 0;     ///< EM iterations of the chosen fit
  int total_iterations = 0;  ///< over every fit (BIC tries several K)
  bool converged = false; ///< the chosen fit met its tolerance before the iteration bound
  double objective = 0;   ///< Q of the chosen fit
  double log_likelihood = 0;  ///< LL (eq. 10) of the chosen fit
};

template <typename T>
struct EmOptions {
  int max_iterations = kMaxEmIterations;
  T tolerance = T(1e-4);          ///< stop when Q gains less than tolerance * (1 + |Q|)
  T covariance_floor_m2 = T(0.04);  ///< eps: a lone point is a Gaussian of 0.2 m standard deviation
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
  T ll = T(0);  ///< LL (eq. 10) at the last E-step
};

namespace em_detail {

constexpr double kLog2Pi = 1.8378770664093454836;
constexpr double kMinComponentWeight = 1e-3;

/// E-step: responsibilities and Q. Bound: m * k.
template <typename T, class B>
T e_step(const Points<T, B>& pts, int m, T floor, EmWorkspace<T, B>& ws) {
  std::array<T, B::kMaxGroups> log_norm;
  std::array<Mat2<T>, B::kMaxGroups> inv;
  T penalty = T(0);
  for (int q = 0; q < ws.k; ++q) {  // <= kMaxGroups
    const Mat2<T>& S = ws.sigma[q];
    const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    inv[q] << S(1, 1) / det, -S(0, 1) / det, -S(1, 0) / det, S(0, 0) / det;
    log_norm[q] = ws.log_pi[q] - T(kLog2Pi) - T(0.5) * fmath::log(det);
    penalty += T(0.5) * floor * (inv[q](0, 0) + inv[q](1, 1));
  }
  T ll = T(0);
  for (int j = 0; j < m; ++j) {  // <= kMaxObservations
    T mx = -std::numeric_limits<T>::infinity();
    for (int q = 0; q < ws.k; ++q) {  // <= kMaxGroups
      const Vec2<T> d = pts[j] - ws.mu[q];
      const T lp = log_norm[q] - T(0.5) * d.dot(inv[q] * d);
      ws.gamma[j][q] = lp;
      if (lp > mx) mx = lp;
    }
    T sum = T(0);
    for (int q = 0; q < ws.k; ++q) sum += fmath::exp(ws.gamma[j][q] - mx);  // <= kMaxGroups
    const T lse = mx + fmath::log(sum);
    for (int q = 0; q < ws.k; ++q) ws.gamma[j][q] = fmath::exp(ws.gamma[j][q] - lse);  // <= kMaxGroups
    ll += lse;
  }
  ws.ll = ll;
  return ll - penalty;
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
    if (!(n >= T(kMinComponentWeight))) continue;
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

/// One EM fit with k components from farthest-first seeds (hard nearest-seed start).
template <typename T, class B>
EmStats fit(const Points<T, B>& pts, int m, int k, const EmOptions<T>& opt, EmWorkspace<T, B>& ws) {
  EmStats st;
  std::array<Vec2<T>, B::kMaxGroups> seeds;
  ws.k = farthest_first<T, B>(pts, m, k, seeds);
  for (int j = 0; j < m; ++j) {  // <= kMaxObservations: hard responsibilities to the nearest seed
    int arg = 0;
    for (int q = 1; q < ws.k; ++q) {  // <= kMaxGroups
      if ((pts[j] - seeds[q]).squaredNorm() < (pts[j] - seeds[arg]).squaredNorm()) arg = q;
    }
    for (int q = 0; q < ws.k; ++q) ws.gamma[j][q] = q == arg ? T(1) : T(0);  // <= kMaxGroups
  }
  m_step(pts, m, opt.covariance_floor_m2, ws);
  ws.trace_length = 0;
  T q_old = e_step(pts, m, opt.covariance_floor_m2, ws);
  ws.trace[ws.trace_length++] = q_old;
  for (int it = 0; it < opt.max_iterations; ++it) {  // <= kMaxEmIterations
    m_step(pts, m, opt.covariance_floor_m2, ws);
    const T q_new = e_step(pts, m, opt.covariance_floor_m2, ws);
    ws.trace[ws.trace_length++] = q_new;
    st.iterations = it + 1;
    if (q_new - q_old <= opt.tolerance * (T(1) + std::abs(q_old))) {
      st.converged = true;
      q_old = q_new;
      break;
    }
    q_old = q_new;
  }
  st.components = ws.k;
  st.total_iterations = st.iterations;
  st.objective = static_cast<double>(q_old);
  st.log_likelihood = static_cast<double>(ws.ll);
  return st;
}

}  // namespace em_detail

/// Groups the points by a Gaussian mixture fitted with EM.
/// @param k  components, 1 .. MaxGroups (clamped to m); 0 chooses K in [1, min(MaxGroups, m)] by BIC
/// @return statistics of the chosen fit; `out` holds the groups (labels by arg max gamma, eq. 9).
/// Iterations are clamped to [1, kMaxEmIterations].
template <typename T, class B>
EmStats gmm_em(const Points<T, B>& pts, int m, int k, EmOptions<T> opt, EmWorkspace<T, B>& ws, Groups<B>& out) {
  EmStats best;
  if (m == 0) {
    out.count = 0;
    return best;
  }
  opt.max_iterations = opt.max_iterations < 1 ? 1 : (opt.max_iterations > kMaxEmIterations ? kMaxEmIterations : opt.max_iterations);
  const int k_cap = m < B::kMaxGroups ? m : B::kMaxGroups;
  const bool by_bic = k <= 0;
  const int k_lo = by_bic ? 1 : (k < k_cap ? k : k_cap);
  const int k_hi = by_bic ? k_cap : k_lo;
  double best_bic = std::numeric_limits<double>::infinity();
  int total = 0;
  for (int kk = k_lo; kk <= k_hi; ++kk) {  // <= kMaxGroups fits
    const EmStats st = em_detail::fit(pts, m, kk, opt, ws);
    total += st.iterations;
    // BIC = -2 LL + p ln m with p = 6K - 1 free parameters (2 mean + 3 covariance + 1 weight each).
    const double bic = -2.0 * st.log_likelihood + (6.0 * st.components - 1.0) * std::log(static_cast<double>(m));
    if (!by_bic || bic < best_bic) {
      best_bic = bic;
      best = st;
      for (int j = 0; j < m; ++j) {  // <= kMaxObservations: eq. 9, ties to the lower index
        int arg = 0;
        for (int q = 1; q < ws.k; ++q) {  // <= kMaxGroups
          if (ws.gamma[j][q] > ws.gamma[j][arg]) arg = q;
        }
        out.label[j] = static_cast<std::int8_t>(arg);
      }
    }
  }
  best.total_iterations = total;
  compact_labels(m, out);
  return best;
}

}  // namespace geojcbb
