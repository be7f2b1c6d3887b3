// jcbb: the joint compatibility test (2019 paper, eqs. 1-4) kept incrementally.
//   S_H = C_H + blockdiag(R_i),  D2_H = nu_H^T S_H^-1 nu_H = |L^-1 nu_H|^2  with  S_H = L L^T.
// Adding a pairing appends two rows to L by forward substitution and a 2x2 Cholesky of the Schur
// complement: O(p^2) for p pairings. Removing the last pairing drops its two rows: O(1). Since C_H
// is PSD and R_i is PD, every new pivot is at least lambda_min(R_i) in exact arithmetic; a
// non-positive pivot therefore means C is not PSD, and is reported as kNotPositiveDefinite. The
// packed covariance: try_push reads C's cross blocks between the new candidate and the held
// ones, and (unless told the caller checked all of C) checks each entry it reads is finite: C is
// validated where the joint test reads it. C is symmetric by storage (BlockCovariance keeps one
// copy of a cross block; a dense C's asymmetry is refused where it comes in,
// BlockCovariance::assign_dense).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "geojcbb/core/math.hpp"
#include "geojcbb/core/status.hpp"

namespace geojcbb {

/// @tparam MaxPairs  most pairings held (the observation capacity)
template <typename T, int MaxPairs>
class IncrementalJoint {
 public:
  static constexpr int kRows = 2 * MaxPairs;

  void clear() { pairs_ = 0; }
  /// Whether try_push checks the cross entries of C it reads (default) or trusts the caller's check
  /// of the whole of C (CovarianceCheck::kFull).
  void check_reads(bool on) { check_reads_ = on; }
  int pairs() const { return pairs_; }
  /// Joint d2 of the pairings held.
  T d2() const { return d2_[pairs_]; }

  /// Computes the joint d2 of the held hypothesis plus one pairing, without keeping it.
  /// @param C     predicted-measurement covariance (2n x 2n, symmetric: C(r, c) is C(c, r); candidate j
  ///              at rows 2j, 2j+1), e.g. a Prediction's BlockCovariance
  /// @param cand  candidate index of the new pairing
  /// @param R     the observation's noise
  /// @param nu    the pair's innovation z_i - h_j (bearing wrapped)
  /// @param[out] d2_out  joint d2 with the new pairing
  /// @return kOk; kCapacityExceeded when MaxPairs are held; kNonFinite for a cross entry of C read
  ///         here that is not finite (when checking reads); kNotPositiveDefinite for a pivot <= 0.
  ///         Nothing held changes unless kOk.
  template <class CMatrix>
  [[nodiscard]] Status try_push(const CMatrix& C, int cand, const Mat2<T>& R, const Vec2<T>& nu, T& d2_out) {
    if (pairs_ >= MaxPairs) return Status::kCapacityExceeded;
    const int n = 2 * pairs_;  // rows held
    T* row0 = &L_[row_start(n)];
    T* row1 = row0 + n + 1;  // row n holds n + 1 entries
    const int r0 = 2 * cand;
    if (check_reads_) {
      for (int p = 0; p < pairs_; ++p) {  // <= MaxPairs: the cross block of each held candidate
        const int c0 = 2 * cand_[p];
        for (int a = 0; a < 2; ++a) {
          for (int b = 0; b < 2; ++b) {
            if (!std::isfinite(C(r0 + a, c0 + b))) return Status::kNonFinite;
          }
        }
      }
    }
    // X = B L^-T, B = cross covariance of the new rows with the held ones (R has no cross terms).
    for (int c = 0; c < n; ++c) {  // <= 2 MaxPairs
      const T* lc = &L_[row_start(c)];
      const int cc = 2 * cand_[c / 2] + (c % 2);
      T s0 = C(r0, cc);
      T s1 = C(r0 + 1, cc);
      for (int t = 0; t < c; ++t) {  // <= 2 MaxPairs
        s0 -= row0[t] * lc[t];
        s1 -= row1[t] * lc[t];
      }
      row0[c] = s0 / lc[c];
      row1[c] = s1 / lc[c];
    }
    // Schur complement D - X X^T, then its 2x2 Cholesky factor.
    T a = C(r0, r0) + R(0, 0);
    T b = C(r0 + 1, r0) + R(1, 0);
    T d = C(r0 + 1, r0 + 1) + R(1, 1);
    T e0 = nu.x();
    T e1 = nu.y();
    for (int t = 0; t < n; ++t) {  // <= 2 MaxPairs
      a -= row0[t] * row0[t];
      b -= row1[t] * row0[t];
      d -= row1[t] * row1[t];
      e0 -= row0[t] * y_[t];
      e1 -= row1[t] * y_[t];
    }
    if (!(a > T(0))) return Status::kNotPositiveDefinite;
    const T l00 = std::sqrt(a);
    const T l10 = b / l00;
    const T piv = d - l10 * l10;
    if (!(piv > T(0))) return Status::kNotPositiveDefinite;
    const T l11 = std::sqrt(piv);
    row0[n] = l00;
    row1[n] = l10;
    row1[n + 1] = l11;
    const T y0 = e0 / l00;
    const T y1 = (e1 - l10 * y0) / l11;
    y_[n] = y0;
    y_[n + 1] = y1;
    cand_[pairs_] = static_cast<std::int16_t>(cand);
    d2_[pairs_ + 1] = d2_[pairs_] + y0 * y0 + y1 * y1;
    d2_out = d2_[pairs_ + 1];
    return Status::kOk;
  }

  /// Keeps the pairing computed by the last successful try_push.
  void commit() { ++pairs_; }
  /// Drops the last pairing.
  void pop() { --pairs_; }

 private:
  /// Where row r of the packed lower triangle starts: rows 0 .. r - 1 hold 1 + 2 + ... + r entries.
  static constexpr std::size_t row_start(int r) {
    return static_cast<std::size_t>(r) * static_cast<std::size_t>(r + 1) / 2;
  }

  // L, lower triangle packed row by row (row r: entries 0 .. r). Packed covariance: half
  // the square it was.
  std::array<T, static_cast<std::size_t>(kRows) * (kRows + 1) / 2> L_{};
  std::array<T, kRows> y_{};          // L^-1 nu_H
  std::array<T, MaxPairs + 1> d2_{};  // d2_[p]: joint d2 of p pairings
  std::array<std::int16_t, MaxPairs> cand_{};
  int pairs_ = 0;
  bool check_reads_ = true;
};

}  // namespace geojcbb
