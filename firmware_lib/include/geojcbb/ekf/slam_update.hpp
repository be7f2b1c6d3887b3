// ekf: the filter's correction, ekf::Slam's update (the paired observations fused kUpdateBlockPairs
// at a time, linearised once), update_alone (a Schmidt update of one landmark) and the downdate's
// definiteness check; declared and documented in ekf/slam.hpp, defined here. In: observations, their
// association (landmark ids), scratch; out: x and P corrected. Bounds: update O(n^2 p), O(n) scratch;
// update_alone O(n). Definitions `inline` as the in-class ones were (not the gnu::noinline one).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/ekf/slam.hpp"

namespace geojcbb::ekf {

template <typename T, class B>
inline Status Slam<T, B>::update(const Observations<T, B>& obs, const Association<T, B>& assoc, SlamWorkspace<T, B>& ws,
                                 const Pose2<T>* at, const std::uint8_t* rounds, int this_round) {
  if (assoc.count != obs.count || obs.count < 0 || obs.count > B::kMaxObservations) {
    return Status::kInvalidInput;
  }
  if (at != nullptr && !(std::isfinite(at->x) && std::isfinite(at->y) && std::isfinite(at->theta))) {
    return Status::kNonFinite;
  }
  int p = 0;
  const Pose2<T> xr = at != nullptr ? Pose2<T>{at->x, at->y, wrap_angle(at->theta)} : pose();
  for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
    const FeatureId f = assoc.feature[i];
    if (f < 0 || (rounds != nullptr && rounds[i] != this_round)) continue;
    const int j = index_of(f);
    if (j < 0) return Status::kInvalidInput;
    if (!obs.z[i].allFinite() || !obs.R[i].allFinite()) return Status::kNonFinite;
    if (!is_spd(obs.R[i])) return Status::kNotPositiveDefinite;
    const Vec2<T> h = observe(xr, mount_, landmark(j));
    observe(xr, mount_, linearisation_point(j), &ws.Hp[p], &ws.Hl[p]);
    const Vec2<T> nu = innovation(obs.z[i], h);
    ws.nu[2 * p] = nu.x();
    ws.nu[2 * p + 1] = nu.y();
    ws.obs[p] = static_cast<std::int16_t>(i);
    ws.lm[p] = static_cast<std::int16_t>(j);
    ws.l0[p] = landmark(j);
    ++p;
  }
  ws.rejected_blocks = 0;
  ws.floored_variances = 0;
  if (p == 0) return Status::kOk;
  const int n = dim();
  const T pose0[3] = {xr.x, xr.y, xr.theta};  // the linearisation pose
  constexpr int G = kUpdateBlockPairs;
  constexpr int K = kUpdateBlockCols;
  auto V = [&](int r, int c) -> T& { return ws.V[static_cast<std::size_t>(r) * K + c]; };
  // Sequential blocks of G pairs, every one linearised where the batch is (design.md, "Covariance
  // engine"): with S = L L^T of the whole batch, the block's Schur complement is its diagonal
  // block of L, which the block's S from the already-updated P equals; so the blocks together are
  // the batch update x <- x + W L^-1 nu, P <- P - W W^T, W = P H^T L^-T, and need O(n) scratch.
  for (int b0 = 0; b0 < p; b0 += G) {       // <= ceil(kMaxObservations / G) blocks
    const int q = p - b0 < G ? p - b0 : G;  // pairs in this block
    const int k = 2 * q;                    // rows of H_b
    // A = P H_b^T, K columns (the unused ones of a short block zero).  O(n)
    for (int r = 0; r < n; ++r) {  // <= kMaxState
      const T pr0 = cov(r, 0), pr1 = cov(r, 1), pr2 = cov(r, 2);
      for (int a = 0; a < G; ++a) {
        if (a >= q) {
          V(r, 2 * a) = T(0);
          V(r, 2 * a + 1) = T(0);
          continue;
        }
        const int l = Layout::landmark(ws.lm[b0 + a]);
        const T pl0 = cov(r, l), pl1 = cov(r, l + 1);
        const Mat23<T>& Hp = ws.Hp[b0 + a];
        const Mat2<T>& Hl = ws.Hl[b0 + a];
        for (int u = 0; u < 2; ++u) {
          V(r, 2 * a + u) = Hp(u, 0) * pr0 + Hp(u, 1) * pr1 + Hp(u, 2) * pr2 + Hl(u, 0) * pl0 + Hl(u, 1) * pl1;
        }
      }
    }
    // S_b = H_b A + R_b (lower triangle) and the block's innovation at the linearisation point:
    // nu - H (x - x0), x0 the state before the first block (H touches the pose and one landmark).
    T L[K][K] = {};
    T w[K] = {};
    for (int a = 0; a < q; ++a) {
      const int pa = b0 + a;
      const int la = Layout::landmark(ws.lm[pa]);
      const Vec2<T> dl = landmark(ws.lm[pa]) - ws.l0[pa];
      const T dp[3] = {x_[0] - pose0[0], x_[1] - pose0[1], wrap_angle(x_[2] - pose0[2])};
      for (int u = 0; u < 2; ++u) {
        const int row = 2 * a + u;
        for (int col = 0; col <= row; ++col) {  // <= K
          T s = T(0);
          for (int t = 0; t < 3; ++t) s += ws.Hp[pa](u, t) * V(t, col);
          for (int t = 0; t < 2; ++t) s += ws.Hl[pa](u, t) * V(la + t, col);
          if (col / 2 == a) s += obs.R[ws.obs[pa]](u, col % 2);
          L[row][col] = s;
        }
        T h = T(0);
        for (int t = 0; t < 3; ++t) h += ws.Hp[pa](u, t) * dp[t];
        for (int t = 0; t < 2; ++t) h += ws.Hl[pa](u, t) * dl(t);
        w[row] = ws.nu[2 * pa + u] - h;
      }
    }
    bool spd = true;
    for (int j = 0; j < k && spd; ++j) {  // <= K: in-place Cholesky
      T d = L[j][j];
      for (int t = 0; t < j; ++t) d -= L[j][t] * L[j][t];
      spd = d > T(0) && std::isfinite(d);
      if (!spd) break;
      L[j][j] = std::sqrt(d);
      for (int i = j + 1; i < k; ++i) {  // <= K
        T s = L[i][j];
        for (int t = 0; t < j; ++t) s -= L[i][t] * L[j][t];
        L[i][j] = s / L[j][j];
      }
    }
    for (int r = 0; r < n && spd; ++r) {  // V <- A L^-T (per row);  <= kMaxState
      for (int i = 0; i < k; ++i) {       // <= K
        T v = V(r, i);
        for (int t = 0; t < i; ++t) v -= L[i][t] * V(r, t);
        V(r, i) = v / L[i][i];
      }
    }
    // S positive definite is not enough in floating point: a pose variance many orders above the
    // landmark's (float, 1e6 against 1e-2) loses every digit in P - V V^T, and the result can be
    // indefinite (fuzz_node's finding). The entries that define the filter's guarantees, the pose
    // block and each landmark's 2x2 block, are computed as the downdate will write them and checked
    // first.  O(n K)
    if (spd) spd = downdate_keeps_blocks_definite(n, ws);
    for (int i = 0; i < k && spd; ++i) {  // w <- L^-1 nu_b;  <= K
      for (int t = 0; t < i; ++t) w[i] -= L[i][t] * w[t];
      w[i] /= L[i][i];
    }
    // The new mean must be finite too: a finite innovation over a tiny S can overflow x + V w
    // (fuzz_associate's finding). Checked with the arithmetic that writes it, before any write.
    bool finite = true;
    for (int r = 0; r < n && spd && finite; ++r) {  // <= kMaxState
      T dx = T(0);
      for (int i = 0; i < k; ++i) dx += V(r, i) * w[i];  // <= K
      finite = std::isfinite(x_[r] + dx);
    }
    if (!spd || !finite) {
      // The first block runs before any change: a refusal there changes nothing (the caller's S,
      // or a P that cannot take the update in T). Later blocks are skipped, PX4-style.
      if (b0 == 0) return spd ? Status::kNonFinite : Status::kNotPositiveDefinite;
      ++ws.rejected_blocks;
      continue;
    }
    if (b0 == 0 && !updated_) {  // nothing below can fail; the pose the next prediction linearises at (FEJ)
      prior_[0] = x_[0];
      prior_[1] = x_[1];
      updated_ = true;
    }
    for (int r = 0; r < n; ++r) {  // x <- x + V w;  <= kMaxState
      T dx = T(0);
      for (int i = 0; i < k; ++i) dx += V(r, i) * w[i];  // <= K
      x_[r] += dx;
    }
    x_[2] = wrap_angle(x_[2]);
    P_.template downdate<K>(n, ws.V.data(), ws.floored_variances);
  }
  return Status::kOk;
}

template <typename T, class B>
Status Slam<T, B>::update_alone(int j, const Vec2<T>& z, const Mat2<T>& R, SlamWorkspace<T, B>& ws, T& d2) {
  if (j < 0 || j >= landmarks()) return Status::kInvalidInput;
  if (!z.allFinite() || !R.allFinite()) return Status::kNonFinite;
  if (!is_spd(R)) return Status::kNotPositiveDefinite;
  const int n = dim(), l = Layout::landmark(j);
  Mat23<T> Hp;
  Mat2<T> Hl;
  const Pose2<T> xr = pose();
  const Vec2<T> nu = innovation(z, observe(xr, mount_, landmark(j)));
  observe(xr, mount_, linearisation_point(j), &Hp, &Hl);
  // A = P H^T (n x 2), in the update's scratch (its first two columns).
  constexpr int K = kUpdateBlockCols;
  auto V = [&](int r, int c) -> T& { return ws.V[static_cast<std::size_t>(r) * K + c]; };
  for (int r = 0; r < n; ++r) {  // <= kMaxState
    for (int u = 0; u < 2; ++u) {
      V(r, u) = Hp(u, 0) * cov(r, 0) + Hp(u, 1) * cov(r, 1) + Hp(u, 2) * cov(r, 2) + Hl(u, 0) * cov(r, l) +
                Hl(u, 1) * cov(r, l + 1);
    }
  }
  Mat2<T> S;
  for (int u = 0; u < 2; ++u) {
    for (int v = 0; v < 2; ++v) {
      S(u, v) = Hp(u, 0) * V(0, v) + Hp(u, 1) * V(1, v) + Hp(u, 2) * V(2, v) + Hl(u, 0) * V(l, v) +
                Hl(u, 1) * V(l + 1, v) + R(u, v);
    }
  }
  S = symmetric_part(S);
  const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
  if (!(S(0, 0) > T(0)) || !(det > T(0)) || !std::isfinite(det)) return Status::kNotPositiveDefinite;
  Mat2<T> Si;
  Si << S(1, 1) / det, -S(0, 1) / det, -S(1, 0) / det, S(0, 0) / det;
  // K_l = (A's rows l, l + 1) S^-1; K_l S K_l^T = A_l S^-1 A_l^T.
  Mat2<T> Al;
  Al << V(l, 0), V(l, 1), V(l + 1, 0), V(l + 1, 1);
  const Mat2<T> Kl = Al * Si;
  const Mat2<T> Pll = symmetric_part(Mat2<T>(P_.template block<2, 2>(l, l) - Kl * Al.transpose()));
  const Vec2<T> xl = landmark(j) + Kl * nu;
  if (!xl.allFinite() || !Pll.allFinite()) return Status::kNonFinite;
  if (!spd_block(Pll)) return Status::kNotPositiveDefinite;
  d2 = nu.dot(Si * nu);
  // P_lo -= K_l (H P)_o = K_l A_o^T for every other row o (A_o: row o of P H^T).
  for (int o = 0; o < n; ++o) {  // <= kMaxState
    if (o == l || o == l + 1) continue;
    for (int u = 0; u < 2; ++u) P_.at(l + u, o) -= Kl(u, 0) * V(o, 0) + Kl(u, 1) * V(o, 1);
  }
  P_.set_sym(l, Pll);
  x_[l] = xl.x();
  x_[l + 1] = xl.y();
  return Status::kOk;
}

template <typename T, class B>
inline bool Slam<T, B>::downdate_keeps_blocks_definite(int n, const SlamWorkspace<T, B>& ws) const {
  constexpr int K = kUpdateBlockCols;
  const T* v = ws.V.data();
  Mat3<T> Prr;
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r <= c; ++r) {
      Prr(r, c) = P_.template downdated<K>(r, c, v);
      Prr(c, r) = Prr(r, c);
    }
  }
  if (!is_spd_scaled<T>(Prr)) return false;
  for (int l = Layout::landmark(0); l + 1 < n; l += 2) {  // <= kMaxLandmarks
    if (!is_spd_scaled<T>(P_.template downdated<K>(l, l, v), P_.template downdated<K>(l, l + 1, v),
                          P_.template downdated<K>(l + 1, l + 1, v)))
      return false;
  }
  return true;
}

}  // namespace geojcbb::ekf
