// ekf: the filter's covariance P (symmetric, K x K at most), stored packed: its upper triangle
// column by column, entry (r, c), r <= c, at c (c + 1) / 2 + r (packed_index), in a fixed array of
// K (K + 1) / 2 scalars. The layout does not depend on the dimension n in use, which the caller
// keeps and passes: growing appends columns and moves nothing, removal compacts in place.
//   entries and fixed-size blocks (cov, at, block, set_block, set_sym)                     O(1) each
//   append_correlated / append_uncorrelated: two rows and columns at n                        O(n)
//   keep_pairs: keeps some of the pairs of rows and columns after a fixed head, in order     O(n^2)
//   downdate: P <- P - V V^T for V n x Kv, fused multiply-adds and a variance floor         O(n^2 Kv)
// design.md, "Covariance engine". No heap; the object is the array, nothing else.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "geojcbb/core/math.hpp"

namespace geojcbb::ekf {

/// The downdate's machine code on an x86-64 host built without FMA (the default -march): a second
/// copy for processors with the FMA instruction, chosen when the program loads (GCC's
/// target_clones). std::fma is correctly rounded in both, so the results are the same bit for bit;
/// without it every fused multiply-add is a call into libm, which made the downdate of a
/// 1,000-landmark map several times slower. Nothing on the device.
#if defined(__x86_64__) && !defined(__FMA__) && defined(__GNUC__) && !defined(__clang__)
#define GEOJCBB_FMA_CLONES __attribute__((target_clones("fma", "default")))
#else
#define GEOJCBB_FMA_CLONES
#endif

/// Columns of P the downdate updates per pass (PackedCovariance::downdate): with 4 columns of V
/// that is 24 + 4 single-precision registers of the M4F's 32 for V's entries, so nothing spills;
/// the arithmetic per entry does not depend on it.
constexpr int kDowndateCols = 6;

/// @tparam T       scalar (float on the device)
/// @tparam MaxDim  K, the largest dimension (rows = columns)
template <typename T, int MaxDim>
class PackedCovariance {
 public:
  static constexpr int kMaxDim = MaxDim;
  /// Scalars stored: the upper triangle of a kMaxDim x kMaxDim matrix.
  static constexpr std::size_t kPackedSize = static_cast<std::size_t>(kMaxDim) * (kMaxDim + 1) / 2;
  /// Variance floor of the downdate: no downdate may shrink a variance below this fraction of its
  /// value before it (one scan's information gain is orders of magnitude smaller here).
  static constexpr T kMinVarianceRatio = T(1e-6);

  /// Where entry (r, c) lives in the packed upper triangle (column by column).
  static constexpr std::size_t packed_index(int r, int c) {
    return r <= c ? static_cast<std::size_t>(c) * (c + 1) / 2 + r : static_cast<std::size_t>(r) * (r + 1) / 2 + c;
  }

  /// Entry (r, c) (symmetric: cov(r, c) == cov(c, r), one stored scalar).
  T cov(int r, int c) const { return p_[packed_index(r, c)]; }
  T& at(int r, int c) { return p_[packed_index(r, c)]; }

  template <int R, int C>
  Eigen::Matrix<T, R, C> block(int r0, int c0) const {
    Eigen::Matrix<T, R, C> b;
    for (int r = 0; r < R; ++r)
      for (int c = 0; c < C; ++c) b(r, c) = cov(r0 + r, c0 + c);
    return b;
  }
  /// Writes an R x C block at (r0, c0) that lies in the upper triangle or below it, not across
  /// the diagonal (use set_sym for a diagonal block).
  template <int R, int C>
  void set_block(int r0, int c0, const Eigen::Matrix<T, R, C>& b) {
    for (int r = 0; r < R; ++r)
      for (int c = 0; c < C; ++c) at(r0 + r, c0 + c) = b(r, c);
  }
  /// Writes a symmetric N x N diagonal block at (r0, r0): its upper triangle.
  template <int N>
  void set_sym(int r0, const Eigen::Matrix<T, N, N>& b) {
    for (int c = 0; c < N; ++c)
      for (int r = 0; r <= c; ++r) at(r0 + r, r0 + c) = b(r, c);
  }

  /// Whether every cross term of append_correlated(n, J, .) is finite. Reads only.  O(n)
  template <int R>
  bool correlated_finite(int n, const Eigen::Matrix<T, 2, R>& J) const {
    for (int c = 0; c < n; ++c) {  // <= kMaxDim
      for (int u = 0; u < 2; ++u) {
        if (!std::isfinite(cross_term(J, u, c))) return false;
      }
    }
    return true;
  }
  /// Grows P from n to n + 2 (n + 2 <= kMaxDim) with two variables that depend on the first R:
  /// the new columns hold (J P(0:R, c))_u for c < n, and Pnn (symmetric) is their own block.
  /// Nothing moves: columns n and n + 1 are written in place.  O(n)
  template <int R>
  void append_correlated(int n, const Eigen::Matrix<T, 2, R>& J, const Mat2<T>& Pnn) {
    for (int c = 0; c < n; ++c) {  // <= kMaxDim
      for (int u = 0; u < 2; ++u) at(c, n + u) = cross_term(J, u, c);
    }
    set_sym<2>(n, Pnn);
  }
  /// Grows P from n to n + 2 with two variables uncorrelated with the others (covariance Pnn).  O(n)
  void append_uncorrelated(int n, const Mat2<T>& Pnn) {
    for (int c = 0; c < n; ++c) {  // <= kMaxDim
      for (int u = 0; u < 2; ++u) at(c, n + u) = T(0);
    }
    set_sym<2>(n, Pnn);
  }

  /// Removes pairs of rows and columns: the first Head rows and columns stay; after them, pair
  /// keep[k] (increasing, k < kept <= N) becomes pair k, so P shrinks to Head + 2 kept. Out of line
  /// so a caller's frame that holds keep stays small.  O(n^2)
  template <int Head, std::size_t N>
  [[gnu::noinline]] void keep_pairs(const std::int16_t (&keep)[N], int kept) {
    static_assert(Head + 2 * static_cast<long>(N) <= kMaxDim, "the pairs must fit in P");
    constexpr int head = Head;
    auto old_row = [&](int r) { return r < head ? r : head + 2 * keep[(r - head) / 2] + (r - head) % 2; };
    const int n = head + 2 * kept;
    // The pairs before the first removed one keep their index, so the leading rows and columns
    // stay where they are: only the columns from there on move.
    int first = 0;
    while (first < kept && keep[first] == first) ++first;  // <= kMaxDim / 2
    const int r_first = head + 2 * first;
    // old_row is increasing, so the source of (r, c), r <= c, lies at or after it in the
    // column-by-column order; copying in that order reads every source before it is overwritten.
    for (int c = r_first; c < n; ++c) {  // <= kMaxDim
      T* dst = &p_[packed_index(0, c)];
      const T* src = &p_[packed_index(0, old_row(c))];
      for (int r = 0; r < r_first; ++r) dst[r] = src[r];  // <= kMaxDim: rows that keep their index
      for (int k = first; head + 2 * k <= c; ++k) {       // <= kMaxDim / 2: two rows per pair
        const int r = head + 2 * k, o = head + 2 * keep[k];
        dst[r] = src[o];
        if (r + 1 <= c) dst[r + 1] = src[o + 1];
      }
    }
  }

  /// P <- P - V V^T over the first n rows and columns, V n x Kv row-major (v); a variance that
  /// rounding would take below kMinVarianceRatio of its value before is floored there and counted
  /// in `floored` (raising a diagonal entry adds a positive semidefinite matrix, so P stays positive
  /// definite).  O(n^2 Kv)
  /// Every entry gets the same arithmetic whichever loop below computes it: starting from P(r, c),
  /// Kv fused multiply-adds in the order t = 0 .. Kv-1, each correctly rounded,
  ///   P(r, c) <- fma(V(r, t), -V(c, t), P(r, c))
  /// (fmadd, std::fma: one VFMA.F32 on the M4F, fmaf on the host, so the two agree bit for bit; negating
  /// V(c, t) first is exact). The column blocking only shares the loads: kDowndateCols columns per
  /// pass, so each row of V is loaded once for them and each entry of P once per block.
  template <int Kv>
  GEOJCBB_FMA_CLONES void downdate(int n, const T* v, int& floored) {
    constexpr int K = Kv;
    constexpr int C = kDowndateCols;
    int c0 = 0;
    for (; c0 + C <= n; c0 += C) {  // <= kMaxDim / C column groups
      T vc[C][K];                   // -V(c0 + j, t): in registers for the whole pass
      T* pc[C];                     // column c0 + j of the packed triangle, row 0
      for (int j = 0; j < C; ++j) {
        pc[j] = &p_[static_cast<std::size_t>(c0 + j) * (c0 + j + 1) / 2];
        for (int t = 0; t < K; ++t) vc[j][t] = -v[static_cast<std::size_t>(c0 + j) * K + t];
      }
      // Rows above the group: every column of the group, one load of V's row for all of them.
      const T* vr = v;
      const T* const vend = v + static_cast<std::size_t>(c0) * K;
      while (vr != vend) {  // <= kMaxDim rows
        T a[K];
        for (int t = 0; t < K; ++t) a[t] = vr[t];
        vr += K;
        for (int j = 0; j < C; ++j) {
          T* q = pc[j];
          T s = *q;
          for (int t = 0; t < K; ++t) s = fmadd(a[t], vc[j][t], s);
          *q = s;
          pc[j] = q + 1;
        }
      }
      // The group's own triangle: rows c0 .. c0 + j of column c0 + j (pc[j] points at row c0).
      for (int j = 0; j < C; ++j) {
        for (int i = 0; i < j; ++i) {
          T s = pc[j][i];
          for (int t = 0; t < K; ++t) s = fmadd(v[static_cast<std::size_t>(c0 + i) * K + t], vc[j][t], s);
          pc[j][i] = s;
        }
        downdate_variance<K>(pc[j][j], vc[j], floored);
      }
    }
    for (int c = c0; c < n; ++c) {  // < C columns left
      T vc[K];
      for (int t = 0; t < K; ++t) vc[t] = -v[static_cast<std::size_t>(c) * K + t];
      T* pc = &p_[static_cast<std::size_t>(c) * (c + 1) / 2];
      for (int r = 0; r < c; ++r) {  // <= kMaxDim rows above the diagonal
        T s = pc[r];
        for (int t = 0; t < K; ++t) s = fmadd(v[static_cast<std::size_t>(r) * K + t], vc[t], s);
        pc[r] = s;
      }
      downdate_variance<K>(pc[c], vc, floored);
    }
  }
  /// Entry (r, c), r <= c, of P - V V^T as downdate() computes it: the same fused chain, and for
  /// a variance the same floor (without counting it). Reads only.
  template <int Kv>
  T downdated(int r, int c, const T* v) const {
    const T* vr = &v[static_cast<std::size_t>(r) * Kv];
    const T* vc = &v[static_cast<std::size_t>(c) * Kv];
    T s = cov(r, c);
    for (int t = 0; t < Kv; ++t) s = fmadd(vr[t], -vc[t], s);  // <= Kv
    if (r == c && !(s >= cov(r, c) * kMinVarianceRatio)) s = cov(r, c) * kMinVarianceRatio;
    return s;
  }

 private:
  /// a * b + c rounded once: std::fma, which GCC lowers to VFMA.F32 on the M4F (checked in the
  /// cross build's disassembly: no libcall) and the host's fmaf; both correctly rounded.
  static T fmadd(T a, T b, T c) { return std::fma(a, b, c); }
  /// The diagonal entry of a column whose -V row is nvc: the same fused chain, then the floor.
  template <int Kv>
  static void downdate_variance(T& pcc, const T (&nvc)[Kv], int& floored) {
    T nv = pcc;
    for (int t = 0; t < Kv; ++t) nv = fmadd(-nvc[t], nvc[t], nv);
    const T floor = pcc * kMinVarianceRatio;
    if (!(nv >= floor)) {
      nv = floor;
      ++floored;
    }
    pcc = nv;
  }
  /// (J P(0:R, c))_u, summed in the order t = 0 .. R-1.
  template <int R>
  T cross_term(const Eigen::Matrix<T, 2, R>& J, int u, int c) const {
    T s = T(0);
    for (int t = 0; t < R; ++t) s += J(u, t) * cov(t, c);
    return s;
  }

  std::array<T, kPackedSize> p_{};
};

}  // namespace geojcbb::ekf
