// ekf: new landmarks, ekf::Slam's augment (from an observation, the inverse model), add_known_landmark
// (a surveyed one), seed_landmark (one of the global map) and add_landmark; declared and documented in
// ekf/slam.hpp, defined here. In: z and R, or a landmark and its covariance; out: x, P and the book
// grown by one landmark, its id. Bounds: O(n) each. Definitions are `inline`, as the in-class ones were.
#pragma once

#include <cmath>

#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/ekf/slam.hpp"

namespace geojcbb::ekf {

template <typename T, class B>
inline Status Slam<T, B>::augment(const Vec2<T>& z, const Mat2<T>& R, FeatureId& id) {
  if (!z.allFinite() || !R.allFinite()) return Status::kNonFinite;
  if (z.x() < T(0)) return Status::kInvalidInput;
  if (!is_spd(R)) return Status::kNotPositiveDefinite;
  if (book_.full()) return Status::kCapacityExceeded;
  Mat23<T> Jp;
  Mat2<T> Jz;
  const Vec2<T> l = inverse_observe(pose(), mount_, z, &Jp, &Jz);
  const int n = dim();  // first row of the new landmark
  // A finite z can still overflow (a range near the scalar's max): check the new mean and
  // covariance before writing any of them.
  const Mat2<T> Pll = Jp * P_.template block<3, 3>(0, 0) * Jp.transpose() + Jz * R * Jz.transpose();
  if (!l.allFinite() || !Pll.allFinite()) return Status::kNonFinite;
  // R at rounding's edge, or a block so elongated that it is singular in T (double, R near 1e123:
  // the raw determinant rounds positive; fuzz_associate's finding): tested scale-free.
  const Mat2<T> Pll_sym = symmetric_part(Pll);
  if (!spd_block(Pll_sym)) return Status::kNotPositiveDefinite;
  if (!P_.correlated_finite(n, Jp)) return Status::kNonFinite;
  P_.append_correlated(n, Jp, Pll_sym);  // P_lx = Jp P_rx, the new columns n, n + 1
  id = add_landmark(l);
  return Status::kOk;
}

template <typename T, class B>
inline Status Slam<T, B>::add_known_landmark(const Vec2<T>& l, const Mat2<T>& Pll, FeatureId& id) {
  if (!l.allFinite() || !Pll.allFinite()) return Status::kNonFinite;
  const Mat2<T> Pll_sym = symmetric_part(Pll);
  if (!is_spd(Pll) || !spd_block(Pll_sym)) return Status::kNotPositiveDefinite;  // as augment()
  if (book_.full()) return Status::kCapacityExceeded;
  P_.append_uncorrelated(dim(), Pll_sym);
  id = add_landmark(l, true);
  return Status::kOk;
}

template <typename T, class B>
inline Status Slam<T, B>::seed_landmark(const Vec2<T>& l, const Mat2<T>& Pll, T exist_nats, FeatureId& id) {
  if (!l.allFinite() || !Pll.allFinite() || !std::isfinite(exist_nats)) return Status::kNonFinite;
  const Mat2<T> Pll_sym = symmetric_part(Pll);
  if (!is_spd(Pll) || !spd_block(Pll_sym)) return Status::kNotPositiveDefinite;
  if (book_.full()) return Status::kCapacityExceeded;
  P_.append_uncorrelated(dim(), Pll_sym);
  id = add_landmark(l);
  book_[landmarks() - 1].flags = kConfirmedFlag;
  book_[landmarks() - 1].exist = exist_nats;
  return Status::kOk;
}

template <typename T, class B>
inline FeatureId Slam<T, B>::add_landmark(const Vec2<T>& l, bool known) {
  const int k = dim();
  x_[k] = l.x();
  x_[k + 1] = l.y();
  return book_.add(l, P_.template block<2, 2>(k, k), known);
}

}  // namespace geojcbb::ekf
