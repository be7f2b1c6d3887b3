// The evaluation's SLAM run: in a noise-free scenario every strategy makes every decision right and
// the pose stays on the truth; with the scenario's noise, every observation is scored exactly once
// (eq. 15) and the run is reproducible from its seed.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "geojcbb_host/eval_report.hpp"
#include "geojcbb_host/report.hpp"
#include "geojcbb/node/slam_step.hpp"
#include "geojcbb_host/slam_run.hpp"
#include "geojcbb_host/worlds.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {
Scenario env1() { return load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json"); }
}  // namespace

TEST_CASE("noise-free env1: every strategy scores F1 = 1 and stays on the truth") {
  // No simulated noise, while the filter keeps the scenario's sigmas: every innovation is far inside
  // its gate. (Shrinking the sigmas instead would shrink R and Q with them and leave d2's
  // distribution, and its 1 % beyond a 99 % gate, unchanged.)
  Scenario s = env1();
  s.noise_scale = 0.0;
  s.detection_probability = 1.0;
  s.clutter_per_scan = 0.0;
  for (int k = 0; k <= kStrategyCount; ++k) {  // the last pass: association by ground truth
    RunOptions o;
    o.step.strategy = static_cast<Strategy>(k % kStrategyCount);
    o.oracle = k == kStrategyCount;
    CAPTURE(to_string(o.step.strategy));
    CAPTURE(o.oracle);
    const RunResult r = run_slam(s, 1, o);
    CHECK(r.scans > 500);
    CHECK(r.score.fp == 0);
    CHECK(r.score.fn == 0);
    CHECK(r.score.tp > 1000);
    CHECK(r.spurious_landmarks == 0);
    CHECK(r.landmarks > 50);
    CHECK(r.mean_abs_x_m < 1e-2);
    CHECK(r.mean_abs_y_m < 1e-2);
  }
}

TEST_CASE("with noise and clutter: each observation is scored once, and a seed reproduces the run") {
  const Scenario s = env1();
  RunOptions o;
  o.max_steps = 2000;
  const RunResult a = run_slam(s, 5, o);
  const RunResult b = run_slam(s, 5, o);
  CHECK(a.observations == a.score.tp + a.score.tn + a.score.fp + a.score.fn);
  CHECK(a.score.tp == b.score.tp);
  CHECK(a.score.fp == b.score.fp);
  CHECK(a.mean_abs_x_m == b.mean_abs_x_m);
  CHECK(a.spurious_landmarks > 0);  // clutter far from every landmark becomes a (tentative) landmark
  // ... and leaves the map again: clutter is rarely seen twice in one place.
  CHECK(a.spurious_in_map * 10 < a.spurious_landmarks);
  CHECK(a.removed_spurious_landmarks + a.spurious_in_map == a.spurious_landmarks);
}

TEST_CASE("scorer: a false pair is counted by place, within the observed landmark's group or elsewhere") {
  // True landmarks 0 and 1 form a group (a row), 2 is alone. Map ids 0, 1, 2 from true 0, 1, 2;
  // id 3 from clutter.
  RunScorer sc(3, {0, 0, 1});
  sc.added(0, 0);
  sc.added(1, 1);
  sc.added(2, 2);
  sc.added(3, -1);
  // Observations of true 0 paired with: 1 (its neighbour), 2 (another group), 3 (clutter's landmark),
  // 0 (right); clutter paired with 0; true 1 not paired.
  sc.score({0, 0, 0, 0, -1, 1}, {1, 2, 3, 0, 0, -1});
  const RunResult& r = sc.result();
  CHECK(r.score.tp == 1);
  CHECK(r.score.fp == 4);
  CHECK(r.score.fn == 1);
  CHECK(r.fp_clutter == 1);
  CHECK(r.fp_to_original == 2);
  CHECK(r.fp_in_group == 1);
  CHECK(r.fp_other_group == 2);
  CHECK(r.group_score.tp == 2);  // the neighbour is right at group level
  CHECK(r.group_score.fp == 3);
}

TEST_CASE("scorer: a mover's observation paired is a false pair and an fp_mover; its landmarks counted while mapped") {
  // True landmarks 0 and 1; map ids 0 and 1 from them, 2 and 3 from movers 0 and 1, 4 from clutter.
  RunScorer sc(2, {});
  sc.added(0, 0);
  sc.added(1, 1);
  sc.added(2, -1, 0);
  sc.added(3, -1, 1);
  sc.added(4, -1);
  // Mover 0 paired with true 0's landmark and with its own; mover 1 unpaired; clutter paired with
  // mover 1's landmark; true 1 right.
  sc.score({-1, -1, -1, -1, 1}, {0, 2, -1, 3, 1}, {0, 0, 1, -1, -1});
  sc.removed(3);
  const RunResult r = sc.finish();
  CHECK(r.score.tp == 1);
  CHECK(r.score.fp == 3);
  CHECK(r.score.tn == 1);
  CHECK(r.fp_clutter == 3);
  CHECK(r.fp_mover == 2);
  CHECK(r.movers_in_map == 1);  // mover 0's; mover 1's left the map
  CHECK(r.spurious_landmarks == 3);
  CHECK_THROWS_AS(sc.score({-1}, {0}, {0, 1}), std::runtime_error);
}

TEST_CASE("movers world: TRUTH leaves every mover's observation unpaired, a strategy's pairs of them are counted") {
  Scenario s = draw_world("movers", 7);
  s.laps = 1;
  RunOptions o;
  o.oracle = true;
  const RunResult t = run_slam(s, 1, o);
  CHECK(t.fp_mover == 0);
  CHECK(t.observations == t.score.tp + t.score.tn + t.score.fp + t.score.fn);
  o.oracle = false;
  o.step.strategy = Strategy::kJcbb;
  const RunResult j = run_slam(s, 1, o);
  CHECK(j.fp_mover > 0);  // slow movers are followed
  CHECK(j.fp_mover <= j.fp_clutter);
  CHECK(j.movers_in_map <= j.spurious_in_map);
}

TEST_CASE("report: a preset whose runs all failed is never scored, a run whose map filled is") {
  RunAggregate failed;
  failed.fail("predict: kNonFinite");
  failed.fail("predict: kNonFinite");
  RunAggregate full;
  RunResult r;
  r.score.tp = 9;
  r.score.fn = 1;
  r.not_augmented = 7;
  full.add(r, 1.0);
  const std::vector<ReportRow> rows{failed.row("JCBB", false, true), full.row("PCJCBB", false, true)};
  std::FILE* f = std::tmpfile();
  REQUIRE(f != nullptr);
  print_summary(rows, rows, f);
  print_tables(rows, f);
  std::rewind(f);
  std::string text(1 << 16, '\0');
  text.resize(std::fread(&text[0], 1, text.size(), f));
  std::fclose(f);
  CHECK(text.find("JCBB        all 2 runs failed: predict: kNonFinite") != std::string::npos);
  CHECK(text.find("PCJCBB: the map filled in 1 runs; 7 observations were not added as landmarks") != std::string::npos);
  const nlohmann::json j = rows_json(rows);
  CHECK(j[0]["f1"].is_null());
  CHECK(j[0]["precision"].is_null());
  CHECK(j[1]["f1"].get<double>() == doctest::Approx(2 * 9.0 / (2 * 9 + 1)));
  CHECK(j[1]["not_augmented"] == 7);
  CHECK(j[1]["runs_map_full"] == 1);
}

TEST_CASE("one orchestrator: the evaluation's run is node::SlamStep::step on the same inputs, bit for bit") {
  // The in-process evaluation (run_inputs -> SlamSession) against a bare step fed the same inputs as
  // the session feeds them (the nearest kEvalMaxObservations of each scan, by range): the pose after
  // every input and the final map agree to the last bit, for presets that switch every stage in.
  using EB = Bounds<kEvalMaxObservations, 128, 8, 200000, kEvalMaxLandmarks>;
  struct Case {
    const char* scene;
    const char* preset;
  };
  for (const Case& c : {Case{"env1", "GEOJCBB"}, Case{"reloc_far", "PCJCBB+RL"}, Case{"loop", "PCJCBB+RLTHC"},
                        Case{"lattice", "PCJCBB+LH"}}) {
    CAPTURE(c.scene);
    CAPTURE(c.preset);
    const Scenario sc = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/" + c.scene + ".json");
    RunOptions o;
    select_methods({c.preset}, false).front().apply(o);
    o.record_trace = true;
    SimSource src(sc, 3, 700);
    const RunResult r = run_inputs(src, o);
    src.rewind();
    auto step = std::make_unique<node::SlamStep<double, EB>>();
    REQUIRE(step->configure(step_settings(o, src.sensor)) == Status::kOk);
    REQUIRE(step->reset(src.x0, src.P0) == Status::kOk);
    auto obs = std::make_unique<Observations<double, EB>>();
    auto out = std::make_unique<node::StepResult<double, EB>>();
    RunInput in;
    std::size_t k = 0, differ = 0, first = 0;
    while (src.next(in)) {
      if (in.relocalise) {
        REQUIRE(step->relocalise(step->slam().pose(), in.pose_cov) == Status::kOk);
        step->lost();
      } else if (in.scan) {
        std::vector<SimObservation> scan = in.observations;
        std::sort(scan.begin(), scan.end(), [](const auto& a, const auto& b) { return a.z.x() < b.z.x(); });
        if (scan.size() > static_cast<std::size_t>(EB::kMaxObservations)) scan.resize(EB::kMaxObservations);
        obs->clear();
        for (const SimObservation& z : scan) REQUIRE(obs->push(z.z, z.R) == Status::kOk);
        REQUIRE(step->step(*obs, *out) == Status::kOk);
      } else if (in.increment) {
        REQUIRE(step->predict(ekf::PoseIncrement<double>{in.dx_m, in.dy_m, in.dtheta_rad, in.increment_cov}) ==
                Status::kOk);
      } else {
        REQUIRE(step->predict(ekf::Odometry<double>{in.v_mps, in.w_radps, in.dt_s, in.sigma_v_mps, in.sigma_w_radps}) ==
                Status::kOk);
      }
      REQUIRE(k < r.trace.size());
      const Pose2<double> a = r.trace[k].pose, b = step->slam().pose();
      const bool same = a.x == b.x && a.y == b.y && a.theta == b.theta;
      if (!same && differ++ == 0) first = k;
      ++k;
    }
    CAPTURE(first);
    CHECK(differ == 0);
    CHECK(k == r.trace.size());
    CHECK(k > 500);
    CHECK(r.landmarks == step->slam().landmarks());
  }
}

TEST_CASE("noise from the innovations: R and the odometry noise given 4 times too wide are brought back") {
  // env1's simulated noise is what the filter assumes; the recording's noise is then made 4 times
  // too wide (variances), as a log whose sigmas were guessed high. The rounds match each component's
  // NIS to its expectation; no labels, no truth are read.
  const Scenario sc = env1();
  SimSource sim(sc, 3, 1500);
  RecordedSource rec(sim);
  rec.scale_noise(4, 4, 4);
  RunOptions o;
  o.step.strategy = Strategy::kJcbb;
  auto mean_nis = [](const RunResult& r) { return r.nis_sum / double(r.nis_pairings); };
  NoiseScales s;
  const RunResult first = innovation_round(rec, o, s);
  CHECK(mean_nis(first) < 0.8);  // the spread is a quarter of what the filter expects
  for (int round = 1; round < 8; ++round) (void)innovation_round(rec, o, s);
  NoiseScales after = s;
  const RunResult last = innovation_round(rec, o, after);
  MESSAGE("learnt x4: range " << 4 * s.range << ", bearing " << 4 * s.bearing << ", odometry " << 4 * s.odometry
                              << "; mean NIS " << mean_nis(first) << " -> " << mean_nis(last));
  // Back to the simulated noise within 30 %, and the NIS at its expectation (2, less the gate's 1 %).
  CHECK(4 * s.range > 0.7);
  CHECK(4 * s.range < 1.3);
  CHECK(4 * s.bearing > 0.7);
  CHECK(4 * s.bearing < 1.3);
  CHECK(4 * s.odometry > 0.7);
  CHECK(4 * s.odometry < 1.3);
  CHECK(mean_nis(last) > 1.7);
  CHECK(mean_nis(last) < 2.1);
}
