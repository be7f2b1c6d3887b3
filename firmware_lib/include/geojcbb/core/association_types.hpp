// core: inputs and outputs of one association call. Inputs are independent of any filter:
// observations z_i = (range, bearing) with noise R_i, and a prediction for n candidate features
// (ids, predicted measurements h_j, and C = H P H^T, the 2n x 2n covariance of the predicted
// measurements with all cross terms). Sizes are bounded by a Bounds type (core/capacity.hpp).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "geojcbb/core/capacity.hpp"
#include "geojcbb/core/diagnostics.h"
#include "geojcbb/core/math.hpp"
#include "geojcbb/core/status.hpp"

namespace geojcbb {

using FeatureId = std::int32_t;
/// No candidate in the region is individually compatible: a new landmark (or clutter; the filter
/// decides with its own rule).
constexpr FeatureId kNewFeature = -1;
/// Individually compatible with some candidate, but left out of the jointly compatible hypothesis
/// (ambiguous): neither paired nor safe to add as a new landmark.
constexpr FeatureId kUnmatched = -2;

/// Index of a candidate in a Prediction (0 .. MaxCandidates - 1), or -1 for none.
using CandidateIndex = std::int16_t;
/// A hypothesis: per observation, the index of its paired candidate or -1. Every stage (JCBB, ICNN,
/// the merge, the consistency stage) reads and writes hypotheses in this one form.
template <class B>
using Hypothesis = std::array<CandidateIndex, B::kMaxObservations>;

template <typename T, class B>
struct Observations {
  int count = 0;
  std::array<Vec2<T>, B::kMaxObservations> z;  ///< (range [m], bearing [rad]), sensor frame
  std::array<Mat2<T>, B::kMaxObservations> R;  ///< measurement noise covariance [m^2, rad^2]

  void clear() { count = 0; }
  /// @return kOk, or kCapacityExceeded (nothing written) when full. Values are validated by
  ///         associate(), not here.
  [[nodiscard]] Status push(const Vec2<T>& zi, const Mat2<T>& Ri) {
    if (count >= B::kMaxObservations) return Status::kCapacityExceeded;
    z[count] = zi;
    R[count] = Ri;
    ++count;
    return Status::kOk;
  }
};

/// The symmetric 2n x 2n covariance C = H P H^T of n candidates (candidate j at rows 2j, 2j + 1),
/// stored as its lower block triangle (packed covariance): block (a, b), a >= b, a 2 x 2 at
/// a (a + 1) / 2 + b, so (MaxCandidates (MaxCandidates + 1) / 2) blocks instead of (2 MaxCandidates)^2
/// entries. A cross block (a != b) is stored once: C(r, c) and C(c, r) are the same entry, so a cross
/// block cannot be asymmetric; a dense C is checked for that where it comes in (assign_dense). A
/// diagonal block is stored whole, so its own symmetry is still validate()'s to check. The layout does
/// not depend on n: resize keeps the blocks of the first candidates.
template <typename T, int MaxCandidates>
class BlockCovariance {
 public:
  static constexpr int kMaxBlocks = MaxCandidates * (MaxCandidates + 1) / 2;

  /// n candidates (2n x 2n).
  int candidates() const { return n_; }
  int rows() const { return 2 * n_; }
  int cols() const { return 2 * n_; }

  /// n candidates; blocks not written before hold what they held.
  /// @return kOk; kInvalidInput for n < 0; kCapacityExceeded for n > MaxCandidates (no change).
  [[nodiscard]] Status resize(int n) {
    if (n < 0) return Status::kInvalidInput;
    if (n > MaxCandidates) return Status::kCapacityExceeded;
    n_ = n;
    return Status::kOk;
  }
  /// n candidates (clamped to [0, MaxCandidates]), C = s I. Bound: the blocks of n candidates.
  void set_identity(int n, T s = T(1)) {
    n_ = n < 0 ? 0 : (n > MaxCandidates ? MaxCandidates : n);
    for (int k = 0; k < n_ * (n_ + 1) / 2; ++k) blocks_[k] = Mat2<T>::Zero();     // <= kMaxBlocks
    for (int a = 0; a < n_; ++a) blocks_[index(a, a)] = Mat2<T>::Identity() * s;  // <= MaxCandidates
  }

  /// Block (a, b) of candidates a and b: C rows 2a, 2a + 1, columns 2b, 2b + 1.
  Mat2<T> block(int a, int b) const { return a >= b ? blocks_[index(a, b)] : blocks_[index(b, a)].transpose(); }
  /// Writes block (a, b), and so block (b, a) = m^T when a != b.
  void set_block(int a, int b, const Mat2<T>& m) {
    if (a >= b) {
      blocks_[index(a, b)] = m;
    } else {
      blocks_[index(b, a)] = m.transpose();
    }
  }
  /// Entry (r, c); (c, r) is the same entry in a cross block.
  T operator()(int r, int c) const {
    const int a = r / 2, b = c / 2;
    return a >= b ? blocks_[index(a, b)](r % 2, c % 2) : blocks_[index(b, a)](c % 2, r % 2);
  }
  T& operator()(int r, int c) {
    const int a = r / 2, b = c / 2;
    return a >= b ? blocks_[index(a, b)](r % 2, c % 2) : blocks_[index(b, a)](c % 2, r % 2);
  }

  /// Loads a dense 2n x 2n C (any type with rows(), cols() and (r, c)), checking what the packed form
  /// cannot hold: each cross entry and its mirror image must agree (nearly_equal, as validate()'s
  /// check); the lower one is kept. A non-finite entry is kept (either side) for the stages to report
  /// where they read it. Diagonal blocks are copied whole and checked by validate().
  /// Bound: (2 MaxCandidates)^2 entries.
  /// @return kOk; kInvalidInput for a C not square, of odd size; kCapacityExceeded for more than
  ///         MaxCandidates candidates; kNotSymmetric. Nothing changes unless kOk.
  template <class Dense>
  [[nodiscard]] Status assign_dense(const Dense& C) {
    const int rows = static_cast<int>(C.rows());
    if (rows != static_cast<int>(C.cols()) || rows % 2 != 0) return Status::kInvalidInput;
    const int n = rows / 2;
    if (n > MaxCandidates) return Status::kCapacityExceeded;
    for (int r = 0; r < rows; ++r) {           // <= 2 MaxCandidates
      for (int c = 0; c < 2 * (r / 2); ++c) {  // <= 2 MaxCandidates: the cross blocks left of r's
        const T x = static_cast<T>(C(r, c));
        const T y = static_cast<T>(C(c, r));
        if (std::isfinite(x) && std::isfinite(y) && !nearly_equal(x, y)) return Status::kNotSymmetric;
      }
    }
    n_ = n;
    for (int a = 0; a < n; ++a) {     // <= MaxCandidates
      for (int b = 0; b <= a; ++b) {  // <= MaxCandidates
        Mat2<T>& m = blocks_[index(a, b)];
        for (int r = 0; r < 2; ++r) {
          for (int c = 0; c < 2; ++c) {
            const T x = static_cast<T>(C(2 * a + r, 2 * b + c));
            const T y = static_cast<T>(C(2 * b + c, 2 * a + r));
            m(r, c) = (a != b && std::isfinite(x) && !std::isfinite(y)) ? y : x;  // a non-finite side wins
          }
        }
      }
    }
    return Status::kOk;
  }

 private:
  static int index(int a, int b) { return a * (a + 1) / 2 + b; }

  std::array<Mat2<T>, kMaxBlocks> blocks_;
  int n_ = 0;
};

template <typename T, class B>
using JointCovariance = BlockCovariance<T, B::kMaxCandidates>;

template <typename T, class B>
struct Prediction {
  int count = 0;                                ///< n candidate features
  std::array<FeatureId, B::kMaxCandidates> id;  ///< map feature ids (>= 0)
  std::array<Vec2<T>, B::kMaxCandidates> h;     ///< predicted (range [m], bearing [rad])
  JointCovariance<T, B> C;                      ///< H P H^T, candidate j at rows 2j, 2j+1 (packed)
};

/// The C++ type of each TYPE of core/diagnostics.h.
namespace diagnostic_types {
using U32 = std::uint32_t;
using U16 = std::uint16_t;
using U8 = std::uint8_t;
using BOOL = bool;
}  // namespace diagnostic_types

/// What one association call reports about itself (per-call counters, as MAVLink keeps
/// mavlink_status_t): one member per line of core/diagnostics.h, in its order.
struct AssociationDiagnostics {
#define GEOJCBB_DIAG_MEMBER(TYPE, name, doc) diagnostic_types::TYPE name = 0;
  GEOJCBB_DIAGNOSTICS(GEOJCBB_DIAG_MEMBER)
#undef GEOJCBB_DIAG_MEMBER
};
static_assert(std::is_same<decltype(AssociationDiagnostics::jcbb_nodes), NodeCount>::value,
              "jcbb_nodes counts JCBB nodes");

/// Calls f(name, meaning, value) for every diagnostic of d, in the table's order (C, Python, the
/// tools). Bound: the table's lines.
template <typename D, typename F>
void for_each_diagnostic(D& d, F&& f) {
#define GEOJCBB_DIAG_VISIT(TYPE, name, doc) f(#name, doc, d.name);
  GEOJCBB_DIAGNOSTICS(GEOJCBB_DIAG_VISIT)
#undef GEOJCBB_DIAG_VISIT
}

template <typename T, class B>
struct Association {
  int count = 0;  ///< equals the number of observations
  /// Per observation: the paired feature's id, kNewFeature or kUnmatched.
  std::array<FeatureId, B::kMaxObservations> feature;
  /// Per observation: index of the paired candidate in the Prediction, or -1.
  std::array<std::int16_t, B::kMaxObservations> candidate;
  /// Per observation: individual d2 of its pair; when unpaired, the smallest d2 to any candidate in
  /// the region (infinity when there is none), which a filter can use as a second gate.
  std::array<T, B::kMaxObservations> d2;
  int pairings = 0;                ///< number of paired observations
  T joint_d2 = T(0);               ///< joint Mahalanobis distance of the hypothesis (eq. 4)
  bool jointly_compatible = true;  ///< the hypothesis passes the joint test at its size
  AssociationDiagnostics diag;
};

}  // namespace geojcbb
