// The range-bearing model: analytic Jacobians against central finite differences (in double), the
// inverse model against the forward one, and angle wrapping into (-pi, pi].
#include <doctest/doctest.h>

#include <random>

#include "geojcbb/core/range_bearing.hpp"

using namespace geojcbb;

TEST_CASE("wrap_angle maps into the interval from -pi (excluded) to pi") {
  CHECK(wrap_angle(kPi<double>) == doctest::Approx(kPi<double>));
  CHECK(wrap_angle(-kPi<double>) == doctest::Approx(kPi<double>));
  CHECK(wrap_angle(3 * kPi<double>) == doctest::Approx(kPi<double>));
  CHECK(wrap_angle(0.25 + 4 * kPi<double>) == doctest::Approx(0.25));
  CHECK(wrap_angle(-0.25 - 6 * kPi<double>) == doctest::Approx(-0.25));
  for (float a = -20.f; a < 20.f; a += 0.37f) {
    const float w = wrap_angle(a);
    CHECK(w > -kPi<float>);
    CHECK(w <= kPi<float>);
  }
}

TEST_CASE("observe: Jacobians equal central finite differences") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5, 5);
  const double h = 1e-6;
  for (int trial = 0; trial < 200; ++trial) {
    const Pose2<double> x{u(rng), u(rng), wrap_angle(u(rng))};
    Vec2<double> l(u(rng), u(rng));
    if ((l - Vec2<double>(x.x, x.y)).norm() < 0.3) continue;
    Mat23<double> Jp;
    Mat2<double> Jl;
    observe(x, l, &Jp, &Jl);
    for (int k = 0; k < 3; ++k) {
      Pose2<double> a = x, b = x;
      (k == 0 ? a.x : k == 1 ? a.y : a.theta) += h;
      (k == 0 ? b.x : k == 1 ? b.y : b.theta) -= h;
      const Vec2<double> za = observe(a, l), zb = observe(b, l);
      const Vec2<double> d((za.x() - zb.x()) / (2 * h), wrap_angle(za.y() - zb.y()) / (2 * h));
      CHECK((d - Jp.col(k)).norm() < 1e-6);
    }
    for (int k = 0; k < 2; ++k) {
      Vec2<double> a = l, b = l;
      a[k] += h;
      b[k] -= h;
      const Vec2<double> za = observe(x, a), zb = observe(x, b);
      const Vec2<double> d((za.x() - zb.x()) / (2 * h), wrap_angle(za.y() - zb.y()) / (2 * h));
      CHECK((d - Jl.col(k)).norm() < 1e-6);
    }
  }
}

TEST_CASE("inverse_observe: inverts observe - Jacobians equal finite differences") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-5, 5);
  const double h = 1e-6;
  for (int trial = 0; trial < 200; ++trial) {
    const Pose2<double> x{u(rng), u(rng), wrap_angle(u(rng))};
    const Vec2<double> z(0.5 + std::abs(u(rng)), wrap_angle(u(rng)));
    Mat23<double> Jp;
    Mat2<double> Jz;
    const Vec2<double> l = inverse_observe(x, z, &Jp, &Jz);
    const Vec2<double> back = observe(x, l);
    CHECK(back.x() == doctest::Approx(z.x()).epsilon(1e-12));
    CHECK(std::abs(wrap_angle(back.y() - z.y())) < 1e-12);
    for (int k = 0; k < 3; ++k) {
      Pose2<double> a = x, b = x;
      (k == 0 ? a.x : k == 1 ? a.y : a.theta) += h;
      (k == 0 ? b.x : k == 1 ? b.y : b.theta) -= h;
      CHECK(((inverse_observe(a, z) - inverse_observe(b, z)) / (2 * h) - Jp.col(k)).norm() < 1e-6);
    }
    for (int k = 0; k < 2; ++k) {
      Vec2<double> a = z, b = z;
      a[k] += h;
      b[k] -= h;
      CHECK(((inverse_observe(x, a) - inverse_observe(x, b)) / (2 * h) - Jz.col(k)).norm() < 1e-6);
    }
  }
}
