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

namespace {
// Three landmarks ahead of a robot that hardly moves: 0 stands, 1 goes out and back (mover 0), 2
// walks and stands (mover 1); every landmark in view is seen, no clutter.
Scenario movers_scene() {
  Scenario s;
  s.landmarks = {{10, 0}, {12, 4}, {8, -4}};
  s.waypoints = {{0, 0}, {1000, 0}};
  s.speed_mps = 1e-3;
  s.duration_s = 60;
  s.detection_probability = 1.0;
  Scenario::Mover out;
  out.index = 1;
  out.v = Eigen::Vector2d(0, 0.5);
  out.period_s = 10;
  Scenario::Mover walk;
  walk.index = 2;
  walk.legs = {{Eigen::Vector2d(8, 4), 1.0, 5.0}, {Eigen::Vector2d(14, 4), 2.0, 0.0}};
  s.movers = {out, walk};
  return s;
}
}  // namespace

TEST_CASE("a mover's observation is labelled as a mover: truth -1 and its index, where it is then") {
  const Scenario s = movers_scene();
  Simulator sim(s, 11);
  SimStep st;
  std::vector<long> seen(3, 0), seen_mover(2, 0);
  while (sim.step(st)) {
    for (const SimObservation& o : st.observations) {
      if (o.mover < 0) {
        REQUIRE(o.truth == 0);  // only the standing landmark has a truth
        ++seen[0];
        continue;
      }
      CHECK(o.truth == -1);
      REQUIRE(o.mover < 2);
      ++seen_mover[static_cast<std::size_t>(o.mover)];
      const std::size_t j = static_cast<std::size_t>(s.movers[static_cast<std::size_t>(o.mover)].index);
      const Vec2<double> z = observe(st.true_pose, Vec2<double>(landmark_at(s, j, st.t_s)));
      CHECK(std::abs(o.z.x() - z.x()) < 6 * s.sigma_range_m);
    }
  }
  CHECK(seen[0] > 200);
  CHECK(seen_mover[0] == seen[0]);  // detection 1: every scan sees all three
  CHECK(seen_mover[1] == seen[0]);
  CHECK(mover_of(s, 0) == -1);
  CHECK(mover_of(s, 1) == 0);
  CHECK(mover_of(s, 2) == 1);
}

TEST_CASE("a walking mover walks each leg at its speed, stands its dwell, and stands after the last") {
  const Scenario s = movers_scene();  // from (8, -4): 8 m north at 1 m/s, 5 s standing, 6 m east at 2 m/s
  auto at = [&](double t) { return landmark_at(s, 2, t); };
  CHECK((at(0) - Eigen::Vector2d(8, -4)).norm() < 1e-12);
  CHECK((at(4) - Eigen::Vector2d(8, 0)).norm() < 1e-12);
  CHECK((at(10) - Eigen::Vector2d(8, 4)).norm() < 1e-12);  // standing 8-13 s
  CHECK((at(12.9) - Eigen::Vector2d(8, 4)).norm() < 1e-12);
  CHECK((at(14.5) - Eigen::Vector2d(11, 4)).norm() < 1e-12);
  CHECK((at(16) - Eigen::Vector2d(14, 4)).norm() < 1e-12);
  CHECK((at(1e4) - Eigen::Vector2d(14, 4)).norm() < 1e-12);
  CHECK((landmark_at(s, 1, 5) - Eigen::Vector2d(12, 6.5)).norm() < 1e-12);  // out and back: turning
}

TEST_CASE("detection by beams: p_D falls with range as a tree's beams do, and the simulator draws it") {
  // A tree of 0.5 m at 10 m and one at 35 m, straight ahead of a robot that hardly moves.
  Scenario s;
  s.landmarks = {{10, 0}, {0, 35}};
  s.waypoints = {{0, 0}, {1000, 0}};
  s.speed_mps = 1e-6;
  s.observe_every = 1;
  s.duration_s = 4000 * s.dt_s;
  s.max_range_m = 50;
  s.fov_rad = 2 * kPi<double>;
  s.detection_by_beams = true;
  s.diameters_m = {0.5, 0.5};
  // The model, written out: n = 2 atan(d / 2r) / 0.5 deg beams; p_D 0, 0.2, 0.5, 0.8, 0.9 at 0-4+.
  auto model = [](double d, double r) {
    const double n = 2 * std::atan(d / (2 * r)) / (0.5 * kPi<double> / 180);
    const double p[] = {0, 0.2, 0.5, 0.8, 0.9};
    if (n >= 4) return 0.9;
    const int k = static_cast<int>(n);
    return p[k] + (n - k) * (p[k + 1] - p[k]);
  };
  const double p10 = model(0.5, 10), p35 = model(0.5, 35);
  CHECK(p10 == doctest::Approx(0.9));  // 5.7 beams
  CHECK(p35 == doctest::Approx(0.2 + (2 * std::atan(0.5 / 70) / (0.5 * kPi<double> / 180) - 1) * 0.3));
  CHECK(detection_probability_at(s, 0, 10) == doctest::Approx(p10));
  CHECK(detection_probability_at(s, 1, 35) == doctest::Approx(p35));
  CHECK(detection_probability_at(s, 1, 1e6) == doctest::Approx(0.0));
  Simulator sim(s, 5);
  SimStep st;
  long scans = 0;
  double near = 0, far = 0;
  while (sim.step(st)) {
    ++scans;
    for (const SimObservation& o : st.observations) (o.truth == 0 ? near : far) += o.truth >= 0 ? 1 : 0;
  }
  REQUIRE(scans >= 3999);
  const double n = static_cast<double>(scans);
  CHECK(std::abs(near - n * p10) < 4.5 * std::sqrt(n * p10 * (1 - p10)));  // binomial, 4.5 sigma
  CHECK(std::abs(far - n * p35) < 4.5 * std::sqrt(n * p35 * (1 - p35)));
  CHECK(far < near);
}

TEST_CASE("bad movers and detection settings are refused with their field") {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("geojcbb_test_sim_" + std::to_string(std::random_device{}()));
  std::filesystem::create_directories(dir);
  const std::string p = (dir / "movers.json").string();
  const std::string base = R"({"landmarks": [[0, 0], [5, 5]], "waypoints": [[0, 0], [1, 1]], )";
  std::ofstream(p) << base + R"("movers": [{"index": 1, "legs": [[1, 2, 0, 1]]}]})";
  CHECK_THROWS_WITH_AS(load_scenario(p), doctest::Contains("movers.legs"), std::runtime_error);
  std::ofstream(p) << base + R"("movers": [{"index": 1, "period_s": 5}, {"index": 1, "period_s": 5}]})";
  CHECK_THROWS_WITH_AS(load_scenario(p), doctest::Contains("twice"), std::runtime_error);
  std::ofstream(p) << base + R"("detection": {"model": "beams"}, "landmark_diameters_m": [0.5]})";
  CHECK_THROWS_WITH_AS(load_scenario(p), doctest::Contains("landmark_diameters_m"), std::runtime_error);
  std::ofstream(p) << base + R"("detection": {"model": "beams"}, "landmark_diameters_m": 0.4})";
  const Scenario s = load_scenario(p);
  CHECK(s.detection_by_beams);
  CHECK(s.diameters_m == std::vector<double>{0.4, 0.4});
  std::filesystem::remove_all(dir);
}
