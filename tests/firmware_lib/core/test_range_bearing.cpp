// The range-bearing model: analytic Jacobians against central finite differences (in double), the
// inverse model against the forward one, and angle wrapping into (-pi, pi].
#include <doctest/doctest.h>

#include <random>
#include <vector>

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

TEST_CASE("a sensor mount: Jacobians equal central finite differences, the inverse inverts, zero is the origin") {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-5, 5);
  const double h = 1e-6;
  // Victoria Park's laser: 3.78 m ahead of the rear axle, 0.50 m left; and random mounts.
  std::vector<Mount<double>> mounts{{3.78, 0.5, 0.0}};
  for (int k = 0; k < 20; ++k) mounts.push_back({u(rng), u(rng), wrap_angle(u(rng))});
  for (const Mount<double>& m : mounts) {
    for (int trial = 0; trial < 20; ++trial) {
      const Pose2<double> x{u(rng), u(rng), wrap_angle(u(rng))};
      const Pose2<double> s = sensor_pose(x, m);
      Vec2<double> l(u(rng), u(rng));
      if ((l - Vec2<double>(s.x, s.y)).norm() < 0.3) continue;
      Mat23<double> Jp;
      Mat2<double> Jl;
      const Vec2<double> z = observe(x, m, l, &Jp, &Jl);
      CHECK((z - observe(s, l)).norm() < 1e-12);  // the landmark seen from the sensor's pose
      for (int k = 0; k < 3; ++k) {
        Pose2<double> a = x, b = x;
        (k == 0 ? a.x : k == 1 ? a.y : a.theta) += h;
        (k == 0 ? b.x : k == 1 ? b.y : b.theta) -= h;
        const Vec2<double> za = observe(a, m, l), zb = observe(b, m, l);
        const Vec2<double> d((za.x() - zb.x()) / (2 * h), wrap_angle(za.y() - zb.y()) / (2 * h));
        CHECK((d - Jp.col(k)).norm() < 1e-5);
      }
      for (int k = 0; k < 2; ++k) {
        Vec2<double> a = l, b = l;
        a[k] += h;
        b[k] -= h;
        const Vec2<double> za = observe(x, m, a), zb = observe(x, m, b);
        const Vec2<double> d((za.x() - zb.x()) / (2 * h), wrap_angle(za.y() - zb.y()) / (2 * h));
        CHECK((d - Jl.col(k)).norm() < 1e-5);
      }
      // The inverse: back to the landmark; its Jacobians against finite differences.
      Mat23<double> Ip;
      Mat2<double> Iz;
      CHECK((inverse_observe(x, m, z, &Ip, &Iz) - l).norm() < 1e-9);
      for (int k = 0; k < 3; ++k) {
        Pose2<double> a = x, b = x;
        (k == 0 ? a.x : k == 1 ? a.y : a.theta) += h;
        (k == 0 ? b.x : k == 1 ? b.y : b.theta) -= h;
        const Vec2<double> d = (inverse_observe(a, m, z) - inverse_observe(b, m, z)) / (2 * h);
        CHECK((d - Ip.col(k)).norm() < 1e-5);
      }
      for (int k = 0; k < 2; ++k) {
        Vec2<double> a = z, b = z;
        a[k] += h;
        b[k] -= h;
        const Vec2<double> d = (inverse_observe(x, m, a) - inverse_observe(x, m, b)) / (2 * h);
        CHECK((d - Iz.col(k)).norm() < 1e-5);
      }
    }
  }
  // At the origin the mount is the plain model, bit for bit (float too).
  const Pose2<float> xf{1.5f, -2.0f, 0.7f};
  const Vec2<float> lf(4.0f, 3.0f);
  Mat23<float> J0, J1;
  const Vec2<float> z0 = observe(xf, lf, &J0), z1 = observe(xf, Mount<float>{}, lf, &J1);
  CHECK(z0 == z1);
  CHECK(J0 == J1);
  CHECK(inverse_observe(xf, z0) == inverse_observe(xf, Mount<float>{}, z0));
}
