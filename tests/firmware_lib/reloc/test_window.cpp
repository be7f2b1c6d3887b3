// The hypothesis window (reloc/window.hpp, node::HypothesisWindow): a shift-symmetric row
// of landmarks opens it; with the disputed observations held and no hypothesis leading it never
// exceeds its bounds and ends having committed nothing; a second cluster in view resolves the row
// and the pose is right after; bad input a Status with nothing changed; no allocation; float and
// double agree. Clusters first (cluster_first): a row paired shifted is paired as a unit, right. A
// configuration that compiles both out (the small controller's) refuses their options.
#include <doctest/doctest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "firmware_lib/reloc/reloc_scene.hpp"
#include "geojcbb/node/slam_step.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;
using geojcbb::test::allocations_during;
using geojcbb::test::position_error;

namespace {

using B = DefaultBounds;

template <typename T>
using Rig = test::RelocRig<T, B>;

/// A row of 21 landmarks 1 m apart on y = 0 (ids 0 .. 20, x = -10 .. 10), and one off the row,
/// id 21 at (0.3, -1.2).
std::vector<Eigen::Vector2d> row_map() {
  std::vector<Eigen::Vector2d> map;
  for (int k = -10; k <= 10; ++k) map.emplace_back(k, 0);
  map.emplace_back(0.3, -1.2);
  return map;
}
constexpr int kOffRow = 21;

/// The robot at (0, -3) facing the row, believed half a spacing to the side (x = 0.5) with a
/// position variance (0.5 m^2 along the row) that makes both neighbours plausible.
const Pose2<double> kTruth{0, -3, kPi<double> / 2};
const Pose2<double> kBelieved{0.5, -3, kPi<double> / 2};

template <typename T>
std::unique_ptr<Rig<T>> make_rig(bool hold) {
  StepSettings<T> s = test::reloc_settings<T>();
  s.max_range_m = T(6);
  s.hypothesis_rivals = 2;
  s.hypothesis_window_scans = 4;
  s.hypothesis_hold = hold;
  return test::make_known_map_rig<T, B>(row_map(), s, kBelieved, Vec3<T>(T(0.5), T(0.01), T(1e-4)).asDiagonal());
}

/// Noise-free observations from x of the landmarks within 6 m (the row's middle eleven), and of the
/// off-row landmark when `off_row`.
template <typename T>
void observe(const Pose2<double>& x, bool off_row, Observations<T, B>& obs) {
  obs.clear();
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  const auto map = row_map();
  for (std::size_t k = 0; k < map.size(); ++k) {
    if (static_cast<int>(k) == kOffRow && !off_row) continue;
    const double dx = map[k].x() - x.x, dy = map[k].y() - x.y;
    const double r = std::hypot(dx, dy), b = wrap_angle(std::atan2(dy, dx) - x.theta);
    if (r > 6 || std::abs(b) > 1.5) continue;
    REQUIRE(obs.push(Vec2<T>(T(r), T(b)), R) == Status::kOk);
  }
}

template <typename T>
int paired(const Rig<T>& rig) {
  int n = 0;
  for (int i = 0; i < rig.out.count; ++i) n += rig.out.outcome[i] == node::Outcome::kPaired;
  return n;
}

}  // namespace

TEST_CASE_TEMPLATE("window: a shift-symmetric row is held, never exceeds its bounds, and commits nothing", T, float,
                   double) {
  auto rig = make_rig<T>(true);
  observe(kTruth, false, rig->obs);
  REQUIRE(rig->obs.count == 11);
  const Pose2<T> before = rig->step.slam().pose();
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.window.verdict == reloc::WindowVerdict::kOpened);
  CHECK(rig->out.window.hypotheses >= 2);
  CHECK(rig->out.window.hypotheses <= reloc::kMaxHypotheses);
  CHECK(rig->out.window.held == rig->obs.count);  // every pairing is disputed
  CHECK(paired(*rig) == 0);
  // The same view again and again: no hypothesis can lead, every scan is held, and the window ends
  // after hypothesis_window_scans with nothing committed.
  for (int scan = 2; scan <= 5; ++scan) {
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    CHECK(rig->out.window.hypotheses <= reloc::kMaxHypotheses);
    CHECK(std::abs(double(rig->out.window.lead)) < 3.0);
    CHECK(paired(*rig) == 0);
    CHECK(rig->out.window.verdict == (scan < 5 ? reloc::WindowVerdict::kHeld : reloc::WindowVerdict::kExpired));
  }
  CHECK(rig->step.slam().pose().x == before.x);  // nothing reached the filter
  CHECK(rig->step.slam().pose().y == before.y);
  CHECK(rig->step.slam().pose().theta == before.theta);
  // The window closed: the next scan is checked afresh and opens it again.
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.window.verdict == reloc::WindowVerdict::kOpened);
}

TEST_CASE_TEMPLATE("window: a second cluster in view resolves the row", T, float, double) {
  for (const bool hold : {false, true}) {
    CAPTURE(hold);
    auto rig = make_rig<T>(hold);
    observe(kTruth, false, rig->obs);
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    REQUIRE(rig->out.window.verdict == reloc::WindowVerdict::kOpened);
    // The off-row landmark comes in view: only the right shift explains it.
    observe(kTruth, true, rig->obs);
    REQUIRE(rig->obs.count == 12);
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    // The right hypothesis leads: committed, or it was the association's and the window closed.
    const reloc::WindowVerdict v = rig->out.window.verdict;
    CHECK((v == reloc::WindowVerdict::kCommitted || v == reloc::WindowVerdict::kMerged));
    CHECK(rig->out.window.lead >= T(3));
    CHECK(position_error(rig->step, kTruth) < 0.05);
    for (int i = 0; i < rig->out.count; ++i) {
      REQUIRE(rig->out.outcome[i] == node::Outcome::kPaired);
      // Observations in map order: the row's x = -5 .. 5 (ids 5 .. 15), then the off-row one.
      CHECK(rig->out.feature[i] == (i < 11 ? i + 5 : kOffRow));
    }
    // The scan after: no doubt left.
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    CHECK(rig->out.window.verdict == reloc::WindowVerdict::kNone);
  }
}

TEST_CASE("window: float and double agree: the same verdicts, hypotheses, pairs and pose") {
  for (const bool hold : {false, true}) {
    CAPTURE(hold);
    auto rf = make_rig<float>(hold);
    auto rd = make_rig<double>(hold);
    for (int scan = 0; scan < 4; ++scan) {  // the row alone, then the off-row landmark in view
      CAPTURE(scan);
      observe(kTruth, scan >= 2, rf->obs);
      observe(kTruth, scan >= 2, rd->obs);
      REQUIRE(rf->step.step(rf->obs, rf->out) == Status::kOk);
      REQUIRE(rd->step.step(rd->obs, rd->out) == Status::kOk);
      CHECK(rf->out.window.verdict == rd->out.window.verdict);
      CHECK(rf->out.window.hypotheses == rd->out.window.hypotheses);
      CHECK(rf->out.window.held == rd->out.window.held);
      CHECK(std::abs(double(rf->out.window.lead) - rd->out.window.lead) < 1e-2);
      for (int i = 0; i < rd->out.count; ++i) {
        CHECK(rf->out.outcome[i] == rd->out.outcome[i]);
        CHECK(rf->out.feature[i] == rd->out.feature[i]);
      }
      const Pose2<float> pf = rf->step.slam().pose();
      const Pose2<double> pd = rd->step.slam().pose();
      CHECK(std::hypot(double(pf.x) - pd.x, double(pf.y) - pd.y) < 1e-3);
      CHECK(std::abs(wrap_angle(double(pf.theta) - pd.theta)) < 1e-4);
    }
  }
}

TEST_CASE("window: off, too many rivals refused, bad input a Status, no allocation") {
  using T = double;
  auto rig = make_rig<T>(true);
  StepSettings<T> s = test::reloc_settings<T>();
  s.hypothesis_rivals = reloc::kMaxHypotheses;             // 1 + rivals would exceed the capacity
  CHECK(rig->step.configure(s) == Status::kInvalidInput);  // and the step kept its settings:
  observe(kTruth, false, rig->obs);
  Status st = Status::kNoConvergence;
  CHECK(allocations_during([&] { st = rig->step.step(rig->obs, rig->out); }) == 0);
  REQUIRE(st == Status::kOk);
  REQUIRE(rig->out.window.verdict == reloc::WindowVerdict::kOpened);
  const node::AssociationOverride<T, B> bad{test::miscounted_association<T, B>, nullptr};
  const Pose2<T> before = rig->step.slam().pose();
  CHECK(rig->step.step(rig->obs, rig->out, nullptr, &bad) == Status::kInvalidInput);
  CHECK(rig->step.slam().pose().x == before.x);
  // The open window survived the refused scan.
  CHECK(allocations_during([&] { st = rig->step.step(rig->obs, rig->out); }) == 0);
  REQUIRE(st == Status::kOk);
  CHECK(rig->out.window.verdict == reloc::WindowVerdict::kHeld);
  // Off: nothing happens.
  auto off = test::make_known_map_rig<T, B>(row_map(), test::reloc_settings<T>(), kBelieved,
                                            Vec3<T>(0.5, 0.01, 1e-4).asDiagonal());
  observe(kTruth, false, off->obs);
  REQUIRE(off->step.step(off->obs, off->out) == Status::kOk);
  CHECK(off->out.window.verdict == reloc::WindowVerdict::kNone);
  CHECK(off->out.counts.window == 0u);
}

TEST_CASE_TEMPLATE("clusters first: a row paired shifted by nearest neighbour is paired as a unit, right", T, float,
                   double) {
  // Believed 0.6 m to the side: each observation's nearest landmark (ICNN's pair) is its
  // neighbour in the row; the off-row landmark, in the row's cluster (within dbscan_eps_m of its
  // neighbours), is explained only by the right shift.
  const Pose2<double> believed{0.6, -3, kPi<double> / 2};
  const Mat3<T> P0 = Vec3<T>(T(0.5), T(0.01), T(1e-4)).asDiagonal();
  for (const bool first : {false, true}) {
    CAPTURE(first);
    StepSettings<T> s = test::reloc_settings<T>();
    s.max_range_m = T(6);
    s.strategy = Strategy::kIcnn;
    s.cluster_first = first;
    auto rig = test::make_known_map_rig<T, B>(row_map(), s, believed, P0);
    observe(kTruth, true, rig->obs);
    REQUIRE(rig->obs.count == 12);
    Status st = Status::kNoConvergence;
    CHECK(allocations_during([&] { st = rig->step.step(rig->obs, rig->out); }) == 0);
    REQUIRE(st == Status::kOk);
    int right = 0;
    for (int i = 0; i < rig->out.count; ++i) {
      right += rig->out.outcome[i] == node::Outcome::kPaired && rig->out.feature[i] == (i < 11 ? i + 5 : kOffRow);
    }
    MESSAGE("cluster_first " << first << ": " << right << " of 12 right, re-paired " << rig->out.window.regrouped
                             << ", position error " << position_error(rig->step, kTruth));
    if (first) {
      CHECK(right == 12);
      CHECK(rig->out.window.regrouped == 11);  // the row's; the off-row pair was right
      // One update from 0.6 m off, linearised at the believed pose: within a sixth of the start and
      // within three posterior standard deviations.
      const auto& slam = rig->step.slam();
      const double sd = std::sqrt(double(slam.cov(0, 0)) + double(slam.cov(1, 1)));
      CHECK(position_error(rig->step, kTruth) < 0.1);
      CHECK(position_error(rig->step, kTruth) < 3 * sd);
      CHECK(rig->out.counts.window == 0u);  // no clock given
    } else {
      CHECK(right == 1);  // nearest neighbour: the row shifted, the off-row pair right
      CHECK(rig->out.window.regrouped == 0);
    }
  }
}

TEST_CASE("clusters first: a lone observation is the gate's business; a cluster the association got right stands") {
  using T = double;
  StepSettings<T> s = test::reloc_settings<T>();
  s.max_range_m = T(6);
  s.cluster_first = true;
  // The pose known: the association is right and nothing is paired anew.
  auto rig = test::make_known_map_rig<T, B>(row_map(), s, kTruth, Vec3<T>(1e-4, 1e-4, 1e-6).asDiagonal());
  observe(kTruth, true, rig->obs);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.window.regrouped == 0);
  for (int i = 0; i < rig->out.count; ++i) CHECK(rig->out.feature[i] == (i < 11 ? i + 5 : kOffRow));
  // One observation: no cluster of two, nothing to pair as a unit.
  rig->obs.clear();
  Mat2<T> R;
  R << 0.01, 0, 0, 3e-4;
  REQUIRE(rig->obs.push(Vec2<T>(3.0, 0.0), R) == Status::kOk);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.window.regrouped == 0);
  CHECK(rig->out.window.verdict == reloc::WindowVerdict::kNone);
}

// The small controller's image leaves the window and clusters first out (OptionalStages): its step
// refuses their options, keeps the settings it had, and steps as before; the default configuration
// takes them.
TEST_CASE("window: a configuration without the window refuses its options and keeps its settings") {
  using T = float;
  using Small = SmallControllerBounds;
  static_assert(!OptionalStages<Small>::kHypotheses && OptionalStages<DefaultBounds>::kHypotheses);
  auto small = std::make_unique<node::SlamStep<T, Small>>();
  StepSettings<T> s = test::reloc_settings<T>();
  REQUIRE(small->configure(s) == Status::kOk);
  StepSettings<T> window = s;
  window.hypothesis_rivals = 2;
  StepSettings<T> clusters = s;
  clusters.cluster_first = true;
  CHECK(small->configure(window) == Status::kInvalidInput);
  CHECK(small->configure(clusters) == Status::kInvalidInput);
  CHECK(small->configured());
  REQUIRE(small->reset(Pose2<T>{}, Mat3<T>::Identity() * T(1e-4)) == Status::kOk);
  Observations<T, Small> obs;
  node::StepResult<T, Small> out;
  CHECK(small->step(obs, out) == Status::kOk);
  CHECK(out.window.verdict == reloc::WindowVerdict::kNone);
  auto dflt = std::make_unique<node::SlamStep<T, B>>();
  CHECK(dflt->configure(window) == Status::kOk);
  CHECK(dflt->configure(clusters) == Status::kOk);
}
