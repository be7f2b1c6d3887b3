// The pairwise consistency graph (consistency/pairwise.hpp): the distance test against a world-frame
// oracle computed from the state covariance P; its independence of the estimated pose and of the pose
// and common map uncertainty; its calibration (chi-square, 1 dof, on true pairings); the wide gate,
// the node cap (best d2 kept) and the graph's edges.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <tuple>
#include <vector>

#include "geojcbb/consistency/pairwise.hpp"
#include "support/consistency_scene.hpp"
#include "support/helpers.hpp"

using namespace geojcbb;
using namespace geojcbb::test;

namespace {

using B = DefaultBounds;

template <typename T>
struct Inputs {
  Observations<T, B> obs;
  Prediction<T, B> pred;
  PairwiseGeometry<T, B> geo;
};
template <typename T>
std::unique_ptr<Inputs<T>> load(const host::Scene& s) {
  auto in = std::make_unique<Inputs<T>>();
  REQUIRE(host::to_inputs(s, in->obs, in->pred));
  in->geo.prepare(in->obs, in->pred);
  return in;
}

/// Rounding scale of a variance computed from C's blocks of a and b in Scalar T: the traces of the
/// predicted points' covariances J C J^T (= C_rr + r^2 C_bb) times a few hundred ulps.
template <typename T>
double rounding_scale(const host::Scene& s, int a, int b) {
  auto tr = [&](int j) { return s.C(2 * j, 2 * j) + s.h[j].x() * s.h[j].x() * s.C(2 * j + 1, 2 * j + 1); };
  return 256.0 * std::numeric_limits<T>::epsilon() * (tr(a) + tr(b));
}

/// select_pairings() with a cap of Cap nodes keeps the Cap smallest (d2, i, a) of `all` (every pairing
/// through the gate, sorted), listed by (i, a).
template <int Cap, typename T>
void check_selection(const Inputs<T>& in, const ConsistencyOptions<T>& opt,
                     const std::vector<std::tuple<T, int, int>>& all) {
  auto list = std::make_unique<PairingList<T, Cap>>();
  select_pairings(in.obs, in.pred, opt, *list);
  const int keep = std::min<int>(Cap, static_cast<int>(all.size()));
  CHECK(list->offered == static_cast<int>(all.size()));
  CHECK(list->truncated == (static_cast<int>(all.size()) > Cap));
  REQUIRE(list->count == keep);
  std::vector<std::tuple<int, int>> want, got;
  for (int x = 0; x < keep; ++x) want.emplace_back(std::get<1>(all[x]), std::get<2>(all[x]));
  for (int x = 0; x < list->count; ++x) got.emplace_back(list->node[x].obs, list->node[x].cand);
  std::sort(want.begin(), want.end());
  CHECK(got == want);
}

}  // namespace

TEST_CASE_TEMPLATE("consistency: the pair statistic equals a world-frame oracle computed from P", T, float, double) {
  const double eps = std::numeric_limits<T>::epsilon();
  int compared = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const host::Scene s = host::make_scene(
        consistency_scene_params(10, 16, 0.5 * static_cast<double>(seed), 0.05 * static_cast<double>(seed)), seed);
    auto in = load<T>(s);
    for (int i = 0; i < in->obs.count; ++i) {
      for (int k = i + 1; k < in->obs.count; ++k) {
        for (int a = 0; a < in->pred.count; a += 3) {
          for (int b = 1; b < in->pred.count; b += 2) {
            if (a == b) continue;
            PairStatistic<T> st;
            REQUIRE(pair_statistic(in->geo, in->pred, i, a, k, b, st) == Status::kOk);
            const WorldPairStatistic w = world_pair_statistic(s, i, a, k, b);
            const double ri = s.z[i].x() + s.z[k].x(), ra = s.h[a].x() + s.h[b].x();
            CHECK(std::abs(st.observed_m - w.observed_m) <= 16 * eps * ri);
            CHECK(std::abs(st.predicted_m - w.predicted_m) <= 16 * eps * ra);
            CHECK(std::abs(st.var_observed - w.var_observed) <= 64 * eps * w.var_observed);
            CHECK(std::abs(st.var_predicted - w.var_predicted) <=
                  64 * eps * w.var_predicted + rounding_scale<T>(s, a, b));
            ++compared;
          }
        }
      }
    }
  }
  CHECK(compared > 10000);
}

TEST_CASE_TEMPLATE("consistency: the pair statistic is pose-free (estimate, pose and common map covariance)", T, float,
                   double) {
  const double eps = std::numeric_limits<T>::epsilon();
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const host::Scene s = host::make_scene(consistency_scene_params(8, 12, 0.3, 0.03), seed);
    host::Scene moved = s;
    // A badly wrong estimate, a large pose covariance, and a large common rigid error of the whole
    // state (the robot and every landmark translated together and rotated about the origin).
    moved.est_pose = {s.est_pose.x + 3.0, s.est_pose.y - 2.0, wrap_angle(s.est_pose.theta + 1.2)};
    const int n = static_cast<int>(s.est_landmarks.size());
    const Eigen::MatrixXd A = host::rigid_motion_jacobian(s.est_pose, s.est_landmarks);
    moved.P = s.P + A * Eigen::Vector3d(4.0, 4.0, 0.25).asDiagonal() * A.transpose();
    moved.P.topLeftCorner<3, 3>() += Eigen::Vector3d(9.0, 9.0, 0.5).asDiagonal();
    host::predict_measurements(moved);
    auto in0 = load<T>(s);
    auto in1 = load<T>(moved);
    for (int i = 0; i < in0->obs.count; ++i) {
      for (int k = 0; k < in0->obs.count; ++k) {
        for (int a = 0; a < n; ++a) {
          for (int b = 0; b < n; ++b) {
            if (i == k || a == b) continue;
            PairStatistic<T> st0, st1;
            REQUIRE(pair_statistic(in0->geo, in0->pred, i, a, k, b, st0) == Status::kOk);
            REQUIRE(pair_statistic(in1->geo, in1->pred, i, a, k, b, st1) == Status::kOk);
            CHECK(st1.observed_m == st0.observed_m);
            CHECK(std::abs(st1.predicted_m - st0.predicted_m) <=
                  16 * eps * (s.h[a].x() + s.h[b].x() + moved.h[a].x() + moved.h[b].x()));
            CHECK(std::abs(st1.var_predicted - st0.var_predicted) <=
                  64 * eps * st0.var_predicted + rounding_scale<T>(moved, a, b));
          }
        }
      }
    }
  }
}

TEST_CASE("consistency: the distance test is calibrated on true pairings (chi-square, 1 dof)") {
  // The scene generator draws every error from the covariances it reports, so on true pairings the
  // statistic is chi-square with 1 dof to first order: mean 1, 99 % below chi2inv(0.99, 1).
  double chi2_99 = 0;
  REQUIRE(chi2_inv(0.99, 1, chi2_99) == Status::kOk);
  double sum = 0;
  int pairs = 0, passed = 0;
  for (std::uint64_t seed = 1; seed <= 400; ++seed) {
    host::SceneParams p = consistency_scene_params(10, 14, 1.0, 0.2);
    p.clutter_fraction = 0;
    const host::Scene s = host::make_scene(p, seed);
    auto in = load<double>(s);
    for (int i = 0; i < in->obs.count; ++i) {
      for (int k = i + 1; k < in->obs.count; ++k) {
        const int a = s.truth[i], b = s.truth[k];
        if (a < 0 || b < 0) continue;
        PairStatistic<double> st;
        REQUIRE(pair_statistic(in->geo, in->pred, i, a, k, b, st) == Status::kOk);
        sum += st.d2();
        passed += st.d2() <= chi2_99;
        ++pairs;
      }
    }
  }
  const double mean = sum / pairs, rate = double(passed) / pairs;
  MESSAGE("true pairings: " << pairs << " pairs, mean d2 " << mean << ", " << 100 * rate << " % within chi2(0.99, 1)");
  CHECK(pairs > 15000);
  CHECK(mean == doctest::Approx(1.0).epsilon(0.05));
  CHECK(rate == doctest::Approx(0.99).epsilon(0.005));
}

TEST_CASE_TEMPLATE("consistency: graph nodes from the wide gate, capped at MaxNodes by best d2", T, float, double) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const host::Scene s = host::make_scene(consistency_scene_params(12, 20, 1.0, 0.1), seed);
    auto in = load<T>(s);
    for (const PairingGate gate : {PairingGate::kWide, PairingGate::kEveryCandidate}) {
      ConsistencyOptions<T> opt;
      REQUIRE(opt.set_confidence(0.99999, 0.999) == Status::kOk);
      opt.pairing_gate = gate;
      opt.local_region = seed % 2 == 0;
      opt.local_radius_m = T(7);
      // Every pairing the gate passes, by (d2, i, a).
      std::vector<std::tuple<T, int, int>> all;
      for (int i = 0; i < in->obs.count; ++i) {
        for (int a = 0; a < in->pred.count; ++a) {
          if (!opt.in_region(in->pred.h[a])) continue;
          const Mat2<T> S = in->pred.C.block(a, a) + in->obs.R[i];
          const T d2 = mahalanobis2(innovation(in->obs.z[i], in->pred.h[a]), S);
          if (gate == PairingGate::kWide && !(d2 <= opt.wide_d2)) continue;
          all.emplace_back(d2, i, a);
        }
      }
      std::sort(all.begin(), all.end());
      check_selection<64>(*in, opt, all);  // the default
      check_selection<8>(*in, opt, all);   // truncates more often
    }
  }
}

TEST_CASE_TEMPLATE("consistency: graph edges are the oracle's consistent pairs", T, float, double) {
  const double margin = std::is_same<T, float>::value ? 1e-3 : 1e-9;
  int edges = 0, borderline = 0;
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    const host::Scene s = host::make_scene(consistency_scene_params(10, 14, 1.0, 0.2), seed);
    auto in = load<T>(s);
    ConsistencyOptions<T> opt;
    REQUIRE(opt.set_confidence(0.99999, 0.999) == Status::kOk);
    opt.pairing_gate = PairingGate::kEveryCandidate;
    auto list = std::make_unique<PairingList<T, 64>>();
    select_pairings(in->obs, in->pred, opt, *list);
    auto g = std::make_unique<BitsetGraph<64>>();
    REQUIRE(build_consistency_graph(in->geo, in->pred, *list, opt.pair_d2, *g) == Status::kOk);
    CHECK(g->count == list->count);
    for (int x = 0; x < list->count; ++x) {
      for (int y = 0; y < list->count; ++y) {
        const auto& p = list->node[x];
        const auto& q = list->node[y];
        if (x == y || p.obs == q.obs || p.cand == q.cand) {
          CHECK_FALSE(g->has_edge(x, y));
          continue;
        }
        const double d2 = world_pair_statistic(s, p.obs, p.cand, q.obs, q.cand).d2();
        const double thr = static_cast<double>(opt.pair_d2);
        if (std::abs(d2 - thr) <= margin * thr) {
          ++borderline;
          continue;
        }
        CHECK(g->has_edge(x, y) == (d2 <= thr));
        edges += g->has_edge(x, y);
      }
    }
  }
  MESSAGE("edges " << edges / 2 << ", borderline pairs skipped " << borderline / 2);
  CHECK(edges > 100);
}
