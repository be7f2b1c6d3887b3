// No setting is silently dropped on the way to a device: every option of the option table moved
// away from its default (each with a command-line flag, and those the host derives from its own
// --compensation and --view-margin), and each preset with "+V", is streamed over a pty to the
// desktop device (node::Node in float) and must give, bit for bit, what the in-process float SLAM
// step gives when configured directly from the same run options (not from the CONFIG sent), or be
// refused before the first frame with a message that names the setting.
#include <doctest/doctest.h>

#include <cstring>
#include <memory>
#include <string>

#include "geojcbb/node/node.hpp"
#include "geojcbb_host/stream.hpp"
#include "support/options.hpp"
#include "support/pty_device.hpp"
#include "support/reply_check.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {

struct Outcome {
  bool refused = false;
  std::string message;
  long scans = 0, mismatches = 0, paired = 0;
};

/// One run of `steps` control intervals of env1 over the link, each reply compared with the
/// in-process step configured from step_settings(o) at float32 precision.
Outcome run_over_device(LinkClient& link, const Scenario& sc, const RunOptions& o) {
  Outcome out;
  const proto::Stats before = link.stats();
  SimSource probe(sc, 3, o.max_steps);
  try {
    (void)link_config(probe.sensor, o);
    check_capacity(link_config(probe.sensor, o), link.capabilities());
  } catch (const std::invalid_argument& e) {
    out.refused = true;
    out.message = e.what();
    // Nothing reached the device: the STATS request and its reply are the only frames since.
    const proto::Stats after = link.stats();
    CHECK(after.frames_ok == before.frames_ok + 1);
    return out;
  }
  auto ref = std::make_unique<node::SlamStep<float, DesktopBounds>>();
  REQUIRE(ref->configure(test::at_wire_precision<float>(step_settings(o, probe.sensor))) == Status::kOk);
  Pose2<float> x0;
  Mat3<float> P0;
  node::reset_from(link_reset(probe.x0, probe.P0), x0, P0);
  REQUIRE(ref->reset(x0, P0) == Status::kOk);
  auto obs = std::make_unique<Observations<float, DesktopBounds>>();
  auto res = std::make_unique<node::StepResult<float, DesktopBounds>>();
  Simulator sim(sc, 3);
  SimStep step;
  auto hook = [&](const LinkObsBatch& b, const LinkClient::ScanReply& r) {
    while (sim.step(step)) {
      REQUIRE(ref->predict(node::odometry_from<float>(link_odometry(sc, step))) == Status::kOk);
      if (step.scan) break;
    }
    REQUIRE(node::observations_from(b, *obs) == Status::kOk);
    REQUIRE(ref->step(*obs, *res) == Status::kOk);
    ++out.scans;
    const test::ReplyCheck c = test::check_reply(r, *res, ref->slam());
    out.mismatches += c.mismatches;
    out.paired += c.paired;
    // A closing rule: the device handed its map over, was acknowledged and began the next (the host's
    // stream_run joins it); the reference does the same.
    if (res->submap_due) {
      CHECK(r.pose.submap_frames == proto::submap_frames(static_cast<std::uint32_t>(ref->slam().landmarks())));
      REQUIRE(ref->restart() == Status::kOk);
    } else {
      CHECK(r.pose.submap_frames == 0);
    }
  };
  const RunResult run = stream_scenario(link, sc, 3, o, hook);
  CHECK(run.scans == out.scans);
  return out;
}

}  // namespace

TEST_CASE("device settings: every option away from its default runs on the device as in process, or is refused") {
  const Scenario sc = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  test::PtyDevice dev(0x5E77);
  PosixSerial port(dev.pty.slave_path());
  LinkClient link(port);
  link.hello();
  constexpr int kSteps = 120;  // about 24 scans of env1
  int compared = 0, refused = 0;
  auto cfg = std::make_unique<AssociationConfig<double, DesktopBounds>>();
  for (int k = 0; k < options::kCount; ++k) {
    const options::Info& info = options::kInfo[k];
    const std::string option = info.name;
    CAPTURE(option);
    RunOptions o;
    o.max_steps = kSteps;
    o.step = test::with_other<double>(k);
    // An option for one search (RJC: ungrouped JCBB) is run with a preset that has it; the preset
    // that cannot is refused by make_strategy, in process and on the device alike (below).
    if (make_strategy(o.step.strategy, o.step, *cfg) != Status::kOk) o.step.strategy = Strategy::kJcbb;
    REQUIRE(make_strategy(o.step.strategy, o.step, *cfg) == Status::kOk);
    const Outcome r = run_over_device(link, sc, o);
    if (r.refused) {
      ++refused;
      CHECK(r.message.find(info.name) != std::string::npos);  // the refusal names the setting
      continue;
    }
    ++compared;
    CHECK(r.scans > 10);
    CHECK(r.mismatches == 0);
  }
  // The host's own settings, carried through the step's radius and view.
  for (int which = 0; which < 2; ++which) {
    RunOptions o;
    o.max_steps = kSteps;
    (which == 0 ? o.compensation_m : o.view_margin_m) = 2.5;
    const Outcome r = run_over_device(link, sc, o);
    CHECK(!r.refused);
    CHECK(r.mismatches == 0);
    ++compared;
  }
  // Each preset with the verification switched in (JCBB+V over the device equals JCBB+V in process).
  for (int s = 0; s < kStrategyCount; ++s) {
    RunOptions o;
    o.max_steps = kSteps;
    const Method m{static_cast<Strategy>(s), false, true};
    m.apply(o);
    const std::string name = m.name();
    CAPTURE(name);
    CHECK(o.step.verify);
    const Outcome r = run_over_device(link, sc, o);
    CHECK(!r.refused);
    CHECK(r.mismatches == 0);
    CHECK(r.paired > 0);
    ++compared;
  }
  // Settings no preset can run are refused at CONFIG, as configure() refuses them in process.
  {
    RunOptions o;
    o.max_steps = kSteps;
    o.step.rjc = true;  // with GEOJCBB's grouping
    REQUIRE(make_strategy(o.step.strategy, o.step, *cfg) == Status::kInvalidInput);
    CHECK_THROWS_WITH_AS(stream_scenario(link, sc, 3, o), doctest::Contains("out-of-range"), LinkError);
  }
  // What a device cannot run is refused before the first frame, by name.
  {
    RunOptions o;
    o.max_steps = kSteps;
    o.known_map = {Eigen::Vector2d(1, 2)};
    const Outcome r = run_over_device(link, sc, o);
    CHECK(r.refused);
    CHECK(r.message.find("known_map") != std::string::npos);
    RunOptions g;
    g.max_steps = kSteps;
    g.step.node_budget = DesktopBounds::kMaxJcbbNodes + 1;  // over the device's capacity: not clamped
    const Outcome rg = run_over_device(link, sc, g);
    CHECK(rg.refused);
    CHECK(rg.message.find("node_budget") != std::string::npos);
  }
  MESSAGE(compared << " runs equal bit for bit, " << refused << " options refused");
  CHECK(compared == options::kCount - refused + 2 + kStrategyCount);
}

TEST_CASE(
    "device settings: env1 in local maps of 30 landmarks through the device, seeded over the link (SUBMAP_SEED)") {
  const Scenario sc = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  test::PtyDevice dev(0x5EED);
  PosixSerial port(dev.pty.slave_path());
  LinkClient link(port);
  link.hello();
  int shared[2] = {0, 0};  // landmarks joined by their ids, unseeded and seeded
  for (const bool seed : {false, true}) {
    CAPTURE(seed);
    RunOptions o;
    o.step.strategy = Strategy::kPcjcbb;
    o.submaps = true;
    o.submap_seed = seed;
    o.step.submap_landmarks = 30;
    const RunResult r = stream_scenario(link, sc, 3, o);
    CHECK(r.submaps.maps >= 5);
    CHECK(r.submaps.wrong == 0);
    CHECK(r.submaps.refused == 0);
    CHECK((r.submaps.seeded > 0) == seed);
    for (const JoinRecord& j : r.submaps.joins) shared[seed] += j.shared;
    CHECK(r.score.f1() > 0.98);
  }
  CHECK(shared[1] > shared[0]);  // the seeds were re-observed and joined by their ids
  // A seed needs the batches one at a time: the seed for a scan is chosen after the scan before.
  RunOptions w;
  w.submaps = w.submap_seed = true;
  SimSource src(sc, 3, 10);
  PlainLink pl(link);
  StreamOptions so;
  so.window = 2;
  CHECK_THROWS_WITH_AS(stream_run(pl, src, w, so), doctest::Contains("window"), std::invalid_argument);
}
