// The simulator: reproducible from its seed; drives its path counter-clockwise and stops after the
// laps; odometry noise and clutter rate match the scenario; the sensor respects range and field of
// view; bad scenario files are reported with their path.
#include <doctest/doctest.h>

#include <filesystem>
#include <random>

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "geojcbb_host/sim.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {
std::string scenario_path(const char* name) { return std::string(GEOJCBB_SCENARIO_DIR) + "/" + name + ".json"; }
}  // namespace

TEST_CASE("the bundled scenarios load") {
  for (const char* n : {"env1", "env2", "dense"}) {
    CAPTURE(n);
    const Scenario s = load_scenario(scenario_path(n));
    CHECK(s.landmarks.size() >= 100);
    CHECK(s.waypoints.size() >= 4);
  }
  // The lattice scenes: a regular grid, every landmark on it; noloop's band between the lanes empty.
  const Scenario lat = load_scenario(scenario_path("lattice"));
  CHECK(lat.landmarks.size() == 15u * 15u);
  for (const auto& l : lat.landmarks) {
    CHECK(std::fmod(l.x() + 105.0, 15.0) == doctest::Approx(0.0));
    CHECK(std::fmod(l.y() + 105.0, 15.0) == doctest::Approx(0.0));
  }
  const Scenario nl = load_scenario(scenario_path("noloop"));
  CHECK(nl.landmarks.size() == 37u * 6u);  // x -110..110 by 6 m; rows -36, -30, -24 and -6, 0, 6
  for (const auto& l : nl.landmarks) CHECK((l.y() < -23 || l.y() > -7));
  const Scenario e1 = load_scenario(scenario_path("env1"));
  CHECK(e1.sigma_range_m == doctest::Approx(0.1));
  CHECK(e1.sigma_bearing_rad == doctest::Approx(kPi<double> / 180));
  CHECK(e1.sigma_v_mps == doctest::Approx(0.3));
}

TEST_CASE("a run is reproducible, drives one counter-clockwise lap and stops") {
  const Scenario s = load_scenario(scenario_path("env1"));
  Simulator a(s, 7), b(s, 7);
  SimStep sa, sb;
  double area2 = 0;  // shoelace: twice the signed area enclosed by the true path
  Pose2<double> prev{};
  long steps = 0;
  bool first = true;
  while (a.step(sa)) {
    REQUIRE(b.step(sb));
    CHECK(sa.true_pose.x == sb.true_pose.x);
    CHECK(sa.v_mps == sb.v_mps);
    REQUIRE(sa.observations.size() == sb.observations.size());
    if (!first) area2 += prev.x * sa.true_pose.y - sa.true_pose.x * prev.y;
    prev = sa.true_pose;
    first = false;
    ++steps;
    REQUIRE(steps < 2000000);
  }
  CHECK_FALSE(b.step(sb));
  CHECK(area2 > 0);                                                   // counter-clockwise
  CHECK(0.5 * area2 == doctest::Approx(120.0 * 120.0).epsilon(0.1));  // about the path's square
}

TEST_CASE("odometry noise, sensor limits and clutter follow the scenario") {
  Scenario s = load_scenario(scenario_path("env1"));
  s.clutter_per_scan = 2.0;
  Simulator sim(s, 3);
  SimStep st;
  double sum = 0, sum2 = 0;
  long n = 0, scans = 0, clutter = 0;
  while (sim.step(st)) {
    const double e = st.v_mps - s.speed_mps;
    sum += e;
    sum2 += e * e;
    ++n;
    if (!st.scan) continue;
    ++scans;
    for (const SimObservation& o : st.observations) {
      if (o.truth < 0) {
        ++clutter;
        continue;
      }
      const Vec2<double> z = observe(st.true_pose, Vec2<double>(s.landmarks[o.truth]));
      CHECK(z.x() <= s.max_range_m);
      CHECK(std::abs(z.y()) <= 0.5 * s.fov_rad);
      CHECK(std::abs(o.z.x() - z.x()) < 6 * s.sigma_range_m);
    }
  }
  const double nd = static_cast<double>(n);
  const double mean = sum / nd, sd = std::sqrt(sum2 / nd - mean * mean);
  CHECK(std::abs(mean) < 4 * s.sigma_v_mps / std::sqrt(nd));
  CHECK(sd == doctest::Approx(s.sigma_v_mps).epsilon(0.05));
  const double rate = double(clutter) / static_cast<double>(scans);
  CHECK(std::abs(rate - 2.0) < 4 * std::sqrt(2.0 / static_cast<double>(scans)));
}

TEST_CASE("a bad scenario file is reported with its path") {
  // Only in a fresh temporary directory: tests never write into the working directory.
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("geojcbb_test_sim_" + std::to_string(std::random_device{}()));
  std::filesystem::create_directories(dir);
  const std::string p = (dir / "bad_scenario.json").string();
  std::ofstream(p) << R"({"landmarks": [[0, 0]], "waypoints": [[0, 0]]})";
  CHECK_THROWS_WITH_AS(load_scenario(p), doctest::Contains("bad_scenario.json"), std::runtime_error);
  std::ofstream(p) << R"({"landmarks": [[0, 0]], "waypoints": [[0, 0], [1, 1]], "dt_s": -1})";
  CHECK_THROWS_AS(load_scenario(p), std::runtime_error);
  CHECK_THROWS_AS(load_scenario((dir / "no_such_file.json").string()), std::runtime_error);
  std::ofstream(p) << R"({"landmarks": {"grid": {"min_x": 0, "max_x": 10, "min_y": 0, "max_y": 10, "spacing_m": 0}},
                          "waypoints": [[0, 0], [1, 1]]})";
  CHECK_THROWS_WITH_AS(load_scenario(p), doctest::Contains("spacing"), std::runtime_error);
  std::filesystem::remove_all(dir);
}
