// Chi-square quantiles against published table values (e.g. NIST/SEMATECH e-Handbook 1.3.6.7.4,
// Abramowitz & Stegun table 26.8), within 0.1 %.
#include <doctest/doctest.h>

#include <cmath>

#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/core/gate_thresholds.hpp"

using geojcbb::Status;

namespace {
struct Row {
  int dof;
  double p90, p95, p99, p999;
};
constexpr Row kTable[] = {
    {1, 2.706, 3.841, 6.635, 10.828},     {2, 4.605, 5.991, 9.210, 13.816},     {3, 6.251, 7.815, 11.345, 16.266},
    {4, 7.779, 9.488, 13.277, 18.467},    {5, 9.236, 11.070, 15.086, 20.515},   {6, 10.645, 12.592, 16.812, 22.458},
    {8, 13.362, 15.507, 20.090, 26.124},  {10, 15.987, 18.307, 23.209, 29.588}, {12, 18.549, 21.026, 26.217, 32.909},
    {16, 23.542, 26.296, 32.000, 39.252}, {20, 28.412, 31.410, 37.566, 45.315}, {24, 33.196, 36.415, 42.980, 51.179},
    {30, 40.256, 43.773, 50.892, 59.703}, {40, 51.805, 55.758, 63.691, 73.402}, {50, 63.167, 67.505, 76.154, 86.661},
    {60, 74.397, 79.082, 88.379, 99.607},
};
}  // namespace

TEST_CASE("chi2_inv matches the published table within 0.1 %") {
  for (const Row& r : kTable) {
    const double ps[] = {0.90, 0.95, 0.99, 0.999};
    const double want[] = {r.p90, r.p95, r.p99, r.p999};
    for (int k = 0; k < 4; ++k) {
      double x = 0;
      REQUIRE(geojcbb::chi2_inv(ps[k], r.dof, x) == Status::kOk);
      CAPTURE(r.dof);
      CAPTURE(ps[k]);
      CHECK(std::abs(x - want[k]) <= 1e-3 * want[k]);
    }
  }
}

TEST_CASE("chi2_inv for 2 dof is exactly -2 ln(1 - p), and inverts chi2_cdf for 1..2*24 dof") {
  for (double p : {0.5, 0.9, 0.95, 0.99, 0.999, 0.9999}) {
    double x = 0;
    REQUIRE(geojcbb::chi2_inv(p, 2, x) == Status::kOk);
    CHECK(x == doctest::Approx(-2.0 * std::log(1.0 - p)).epsilon(1e-10));
  }
  for (int dof = 1; dof <= 48; ++dof) {
    for (double p : {0.90, 0.95, 0.99, 0.999}) {
      double x = 0, back = 0;
      REQUIRE(geojcbb::chi2_inv(p, dof, x) == Status::kOk);
      REQUIRE(geojcbb::chi2_cdf(x, dof, back) == Status::kOk);
      CAPTURE(dof);
      CHECK(back == doctest::Approx(p).epsilon(1e-9));
    }
  }
}

TEST_CASE("chi2_inv rejects a level outside (0, 1) and a bad dof") {
  double x = 42;
  CHECK(geojcbb::chi2_inv(0.0, 2, x) == Status::kInvalidInput);
  CHECK(geojcbb::chi2_inv(1.0, 2, x) == Status::kInvalidInput);
  CHECK(geojcbb::chi2_inv(NAN, 2, x) == Status::kInvalidInput);
  CHECK(geojcbb::chi2_inv(0.99, 0, x) == Status::kInvalidInput);
  CHECK(x == 42);
}

TEST_CASE_TEMPLATE("gate thresholds: joint[p] is chi2inv(alpha, 2p) - raw thresholds are validated", T, float, double) {
  using G = geojcbb::GateThresholds<T, 20>;
  G g;
  REQUIRE(G::from_confidence(0.99, 0.95, g) == Status::kOk);
  CHECK(g.individual == doctest::Approx(9.2103).epsilon(1e-4));
  CHECK(g.joint[1] == doctest::Approx(5.9915).epsilon(1e-4));
  CHECK(g.joint[20] == doctest::Approx(55.758).epsilon(1e-4));
  CHECK(g.valid());
  G raw = g;
  raw.joint[3] = raw.joint[2] - T(1);  // a stricter bound for more pairings
  CHECK_FALSE(raw.valid());
  raw = g;
  raw.individual = T(-1);
  CHECK_FALSE(raw.valid());
  G untouched = g;
  CHECK(G::from_confidence(1.5, 0.95, untouched) == Status::kInvalidInput);
  CHECK(untouched.individual == g.individual);
}
