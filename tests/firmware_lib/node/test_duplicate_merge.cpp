// node/stages/duplicate_merge.hpp alone, over a map and scans built by hand: two landmarks 5 cm apart,
// one paired by a scan and the other predicted but not paired, are one landmark: merged, the earlier
// id kept; two landmarks a scan observed together are distinct for good and never merged; a merge
// threshold no pair passes changes nothing. Neither call allocates.
#include <doctest/doctest.h>

#include <memory>
#include <vector>

#include "firmware_lib/node/stage_rig.hpp"
#include "geojcbb/node/stages/duplicate_merge.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;

namespace {

using B = DefaultBounds;

/// A map of two landmarks 5 cm apart (a and b, a the earlier) and a third far away; a scan's
/// prediction holds the first two.
template <typename T>
struct DuplicateRig {
  std::vector<FeatureId> ids;
  std::unique_ptr<ekf::Slam<T, B>> slam =
      test::slam_with<T, B>(Pose2<T>{}, {Vec2<T>(T(4), T(1)), Vec2<T>(T(4.05), T(1)), Vec2<T>(T(-8), T(3))}, ids);
  std::unique_ptr<ekf::SlamWorkspace<T, B>> ws = std::make_unique<ekf::SlamWorkspace<T, B>>();
  std::unique_ptr<Prediction<T, B>> pred = std::make_unique<Prediction<T, B>>();
  std::unique_ptr<node::StepResult<T, B>> out = std::make_unique<node::StepResult<T, B>>();
  node::DuplicateMerge<T, B> merge;
  DuplicateRig() {
    pred->count = 2;
    pred->id[0] = ids[0];
    pred->id[1] = ids[1];
    merge.reset();
  }
  /// The scan paired observation 0 with a (and, when both, observation 1 with b).
  void scan(bool both) {
    out->count = both ? 2 : 1;
    out->outcome[0] = node::Outcome::kPaired;
    out->feature[0] = ids[0];
    out->outcome[1] = node::Outcome::kPaired;
    out->feature[1] = ids[1];
  }
};

constexpr double kMergeD2 = 1.0;
constexpr double kGateD2 = 9.21;

}  // namespace

TEST_CASE_TEMPLATE("duplicate merge: a landmark mapped twice is merged, the earlier id kept", T, float, double) {
  DuplicateRig<T> r;
  r.scan(false);
  // d2 of the difference: 0.05^2 / (0.01 + 0.01) = 0.125, within the merge test.
  CHECK(r.slam->duplicate_d2(0, 1) == doctest::Approx(0.125).epsilon(1e-4));
  int merged = -1;
  const std::uint64_t allocations = test::allocations_during([&] {
    r.merge.note(*r.slam, *r.out, T(kMergeD2), T(kGateD2));
    merged = r.merge.merge(T(kMergeD2), *r.pred, *r.out, *r.slam, *r.ws);
  });
  CHECK(allocations == 0);
  CHECK(merged == 1);
  CHECK(r.slam->landmarks() == 2);
  CHECK(r.slam->index_of(r.ids[0]) >= 0);
  CHECK(r.slam->index_of(r.ids[1]) < 0);
  CHECK(r.slam->index_of(r.ids[2]) >= 0);  // far away: untouched
  // The survivor lies between the two, nearer neither by more than the gap.
  const Vec2<T> l = r.slam->landmark(r.slam->index_of(r.ids[0]));
  CHECK(l.x() > T(3.999));
  CHECK(l.x() < T(4.051));
}

TEST_CASE_TEMPLATE("duplicate merge: two landmarks seen in one scan are distinct for good", T, float, double) {
  DuplicateRig<T> r;
  r.scan(true);  // both observed together: noted as distinct
  r.merge.note(*r.slam, *r.out, T(kMergeD2), T(kGateD2));
  r.scan(false);  // a later scan pairs a only
  const auto before = test::bytes_of(*r.slam);
  CHECK(r.merge.merge(T(kMergeD2), *r.pred, *r.out, *r.slam, *r.ws) == 0);
  CHECK(test::bytes_of(*r.slam) == before);
  // Forgotten by reset(): the same scan then merges them.
  r.merge.reset();
  CHECK(r.merge.merge(T(kMergeD2), *r.pred, *r.out, *r.slam, *r.ws) == 1);
}

TEST_CASE_TEMPLATE("duplicate merge: a threshold no pair passes, or no prediction, changes nothing", T, float, double) {
  DuplicateRig<T> r;
  r.scan(false);
  const auto before = test::bytes_of(*r.slam);
  CHECK(r.merge.merge(T(0.1), *r.pred, *r.out, *r.slam, *r.ws) == 0);  // 0.125 is not below 0.1
  CHECK(r.merge.merge(T(0), *r.pred, *r.out, *r.slam, *r.ws) == 0);
  r.pred->count = 0;
  CHECK(r.merge.merge(T(kMergeD2), *r.pred, *r.out, *r.slam, *r.ws) == 0);
  CHECK(test::bytes_of(*r.slam) == before);
}
