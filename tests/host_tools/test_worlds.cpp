// Generated worlds (host_tools/sim/worlds.hpp) and the robust preset's non-inferiority table
// (host_tools/report/worlds_table.hpp): a world is the same for the same (family, seed) and written
// so that load_scenario reads it back unchanged; the table counts worse and recovered worlds by
// the stated rule.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "geojcbb_host/worlds.hpp"
#include "geojcbb_host/worlds_table.hpp"

using namespace geojcbb::host;

TEST_CASE("worlds: every family draws the same world from the same seed, and a file load_scenario reads back") {
  const std::string dir = (std::filesystem::temp_directory_path() / "geojcbb_test_worlds").string();
  std::filesystem::create_directories(dir);
  REQUIRE(world_families().size() >= 8);
  for (const WorldFamily& f : world_families()) {
    CAPTURE(f.name);
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
      const Scenario a = draw_world(f.name, seed), b = draw_world(f.name, seed), c = draw_world(f.name, seed + 1);
      REQUIRE(a.landmarks.size() >= 10);
      CHECK(a.landmarks == b.landmarks);
      CHECK(a.waypoints == b.waypoints);
      CHECK((a.landmarks != c.landmarks || a.sigma_v_mps != c.sigma_v_mps || a.kidnap_move != c.kidnap_move));
      CHECK(static_cast<int>(a.landmarks.size()) <= 1000);  // the host evaluation's capacity
      const std::string path = dir + "/" + f.name + ".json";
      save_scenario(a, path);
      const Scenario r = load_scenario(path);
      CHECK(r.name == a.name);
      CHECK(r.landmarks == a.landmarks);
      CHECK(r.waypoints == a.waypoints);
      CHECK(r.laps == a.laps);
      CHECK(r.speed_mps == a.speed_mps);
      CHECK(r.sigma_v_mps == a.sigma_v_mps);
      CHECK(r.sigma_w_radps == a.sigma_w_radps);
      CHECK(r.clutter_per_scan == a.clutter_per_scan);
      CHECK(r.max_range_m == a.max_range_m);
      CHECK(r.fov_rad == doctest::Approx(a.fov_rad).epsilon(1e-14));
      CHECK(r.kidnap_t_s == a.kidnap_t_s);
      CHECK(r.kidnap_move.x() == a.kidnap_move.x());
      CHECK(r.kidnap_move.z() == doctest::Approx(a.kidnap_move.z()).epsilon(1e-14));
      CHECK(r.kidnap_told == a.kidnap_told);
      CHECK(r.burst_t_s == a.burst_t_s);
      CHECK(r.burst_duration_s == a.burst_duration_s);
      CHECK(r.burst_every_s == a.burst_every_s);
      CHECK(r.burst_per_scan == a.burst_per_scan);
      REQUIRE(r.movers.size() == a.movers.size());
      for (std::size_t k = 0; k < a.movers.size(); ++k) {
        CHECK(r.movers[k].index == a.movers[k].index);
        CHECK(r.movers[k].v == a.movers[k].v);
        CHECK(r.movers[k].period_s == a.movers[k].period_s);
        REQUIRE(r.movers[k].legs.size() == a.movers[k].legs.size());
        for (std::size_t q = 0; q < a.movers[k].legs.size(); ++q) {
          CHECK(r.movers[k].legs[q].to == a.movers[k].legs[q].to);
          CHECK(r.movers[k].legs[q].speed_mps == a.movers[k].legs[q].speed_mps);
          CHECK(r.movers[k].legs[q].dwell_s == a.movers[k].legs[q].dwell_s);
          CHECK(b.movers[k].legs[q].to == a.movers[k].legs[q].to);  // the same seed, the same walk
        }
      }
      CHECK(r.detection_by_beams == a.detection_by_beams);
      CHECK(r.diameters_m == a.diameters_m);
      CHECK(b.diameters_m == a.diameters_m);
      CHECK(r.p_by_beams == a.p_by_beams);
      CHECK(r.beam_rad == doctest::Approx(a.beam_rad).epsilon(1e-14));
    }
  }
  CHECK_THROWS_AS(draw_world("no_such_family", 1), std::invalid_argument);
  std::filesystem::remove_all(dir);
}

TEST_CASE("worlds: the families' stated ranges hold over 20 seeds") {
  for (std::uint64_t seed = 100; seed < 120; ++seed) {
    const Scenario d = draw_world("drift_loop", seed);
    const double side = 2 * std::abs(d.waypoints[0].x());
    CHECK(side >= 80);
    CHECK(side <= 240);
    CHECK(d.sigma_v_mps >= 0.6);
    CHECK(d.sigma_v_mps <= 1.2);
    const Scenario k = draw_world("kidnap_reset", seed);
    const double moved = std::hypot(k.kidnap_move.x(), k.kidnap_move.y());
    CHECK(moved >= 5);
    CHECK(moved <= 20);
    CHECK(std::abs(k.kidnap_move.z()) >= 30 * 3.14159265358979 / 180 - 1e-12);
    CHECK(k.kidnap_t_s >= 30);
    const Scenario c = draw_world("clutter", seed);
    CHECK(c.clutter_per_scan >= 3);
    CHECK(c.clutter_per_scan <= 10);
    const Scenario q = draw_world("kidnap_silent", seed);
    CHECK(!q.kidnap_told);
    CHECK(std::hypot(q.kidnap_move.x(), q.kidnap_move.y()) >= 5);
    CHECK(k.kidnap_told);
    const Scenario b = draw_world("clutter_burst", seed);
    CHECK(b.burst_per_scan >= 10);
    CHECK(b.burst_per_scan <= 25);
    CHECK(b.burst_duration_s >= 3);
    CHECK(b.burst_duration_s < b.burst_every_s);
    const Scenario m = draw_world("movers", seed);
    CHECK(m.movers.size() >= 8);  // 4-10 out and back, 4-8 people
    CHECK(m.movers.size() <= 18);
    int people = 0, crossers = 0;
    for (const Scenario::Mover& v : m.movers) {
      if (!v.legs.empty()) {  // a person: legs at 0.05-1.5 m/s, standing 0-20 s, walking at least 400 s
        ++people;
        double t = 0;
        Eigen::Vector2d here = m.landmarks[static_cast<std::size_t>(v.index)];
        bool crossed = false;
        for (const Scenario::Mover::Leg& l : v.legs) {
          CHECK(l.speed_mps >= 0.05);
          CHECK(l.speed_mps <= 1.5);
          CHECK(l.dwell_s >= 0);
          CHECK(l.dwell_s <= 20);
          t += (l.to - here).norm() / l.speed_mps + l.dwell_s;
          // crossing the robot's path (the square of half side 20): one end inside, the other outside
          const bool in_here = here.cwiseAbs().maxCoeff() < 20, in_there = l.to.cwiseAbs().maxCoeff() < 20;
          crossed = crossed || in_here != in_there;
          here = l.to;
        }
        CHECK(t >= 400);
        crossers += crossed;
        continue;
      }
      CHECK(v.v.norm() >= 0.05 - 1e-12);
      CHECK(v.v.norm() <= 0.3 + 1e-12);
      // out and back: where it started after each period, at most half a period's travel away between
      CHECK((landmark_at(m, static_cast<std::size_t>(v.index), v.period_s) -
             m.landmarks[static_cast<std::size_t>(v.index)])
                .norm() < 1e-9);
      CHECK((landmark_at(m, static_cast<std::size_t>(v.index), 0.5 * v.period_s) -
             m.landmarks[static_cast<std::size_t>(v.index)])
                .norm() == doctest::Approx(0.5 * v.period_s * v.v.norm()));
    }
    CHECK(people >= 4);
    CHECK(people <= 8);
    CHECK(crossers >= 1);
    CHECK(m.movers.size() - static_cast<std::size_t>(people) >= 4);  // the slow out-and-back ones stay
    CHECK(m.movers.size() - static_cast<std::size_t>(people) <= 10);
    const Scenario f = draw_world("far", seed);
    CHECK(f.landmarks.size() >= 40);
    CHECK(f.landmarks.size() <= 60);
    CHECK(f.max_range_m >= 40);
    CHECK(f.max_range_m <= 50);
    CHECK(f.detection_by_beams);
    REQUIRE(f.diameters_m.size() == f.landmarks.size());
    for (double dia : f.diameters_m) {
      CHECK(dia >= 0.2);
      CHECK(dia <= 1.0);
    }
    const Scenario l = draw_world("large", seed);
    CHECK(l.landmarks.size() >= 140);  // 150-300 drawn; a few may not fit the separation
    CHECK(l.landmarks.size() <= 300);
  }
}

TEST_CASE("worlds: the non-inferiority table counts worse and recovered worlds by the stated rule") {
  std::vector<WorldOutcome> w;
  //            family   file  err_base err_robust f1_base f1_robust anees_b anees_r truth
  w.push_back({"a", "a1", 1.0, 1.4, 0.99, 0.99, 3, 3, -1});          // +0.4 m: within max(0.5, 20 %)
  w.push_back({"a", "a2", 1.0, 1.6, 0.99, 0.99, 3, 3, -1});          // +0.6 m: worse
  w.push_back({"a", "a3", 10.0, 11.9, 0.99, 0.99, 3, 3, -1});        // +1.9 m of 10: within 20 %
  w.push_back({"b", "b1", 1.0, 1.0, 0.990, 0.984, 3, 3, -1});        // F1 -0.006: worse
  w.push_back({"b", "b2", 8.0, 0.8, 0.90, 0.99, 50, 3, 0.6});        // diverged, recovered (TRUTH 0.6 m)
  w.push_back({"b", "b3", 8.0, 1.5, 0.90, 0.99, 50, 3, 0.6});        // better, but not within TRUTH + 0.5
  w.push_back({"b", "b4", 8.0, 0.9, 0.90, 0.99, 50, 3, -1});         // no TRUTH: under 1 m
  w.push_back({"b", "b5", 20.0, 18.0, 0.98, 0.98, 5e4, 5e4, 19.0});  // TRUTH diverged too: not recovered
  w.push_back({"b", "b6", 20.0, 0.2, 0.98, 0.99, 5e4, 3, 19.0});     // TRUTH diverged: under 1 m is recovered
  CHECK(!robust_worse(w[0]));
  CHECK(robust_worse(w[1]));
  CHECK(!robust_worse(w[2]));
  CHECK(robust_worse(w[3]));
  CHECK(robust_recovered(w[4]));
  CHECK(!robust_recovered(w[5]));
  CHECK(robust_recovered(w[6]));
  CHECK(!robust_recovered(w[7]));
  CHECK(robust_recovered(w[8]));
  const std::vector<FamilyRow> rows = non_inferiority(w);
  REQUIRE(rows.size() == 3);
  CHECK(rows[0].family == "a");
  CHECK(rows[0].worlds == 3);
  CHECK(rows[0].worse == 1);
  CHECK(rows[0].err_base == 1.0);  // median
  CHECK(rows[1].worse == 1);
  CHECK(rows[1].recovered == 3);
  CHECK(rows[2].family == "total");
  CHECK(rows[2].worlds == 9);
  CHECK(rows[2].worse == 2);
  const std::string md = non_inferiority_markdown(w);
  CHECK(md.find("| total | 9 | 2 | 3 |") != std::string::npos);
  CHECK(md.find("- a2:") != std::string::npos);
  CHECK(md.find("- b1:") != std::string::npos);
}
