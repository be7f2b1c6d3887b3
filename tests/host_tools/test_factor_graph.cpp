// The global map on the sparse solver (host_tools/mapping/factor_graph.hpp, docs/mapping.md): its
// joint marginals equal ceres::Covariance's to 1e-9 relative on problems of up to 2,000 variables;
// on a loop of local maps it decides every join as the dense join does; on a labelled run it joins
// with no wrong pair.
#include <ceres/ceres.h>
// glog's CHECK macros (through Ceres) give way to doctest's.
#undef CHECK
#undef CHECK_EQ
#undef CHECK_NE
#undef CHECK_LE
#undef CHECK_LT
#undef CHECK_GE
#undef CHECK_GT

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "geojcbb_host/factor_graph.hpp"
#include "geojcbb_host/global_map.hpp"
#include "geojcbb_host/slam_run.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {

/// Local maps around a circle (radius 30 m) in a ring of landmarks (22-38 m), `laps` times: map k
/// begins at the pose on the circle at angle k * step, ends at the next one, and holds the
/// landmarks within 12 m of its middle, each measured with independent noise (sigma_m) in its frame; its poses are exact up
/// to `pose_sigma` (1e-6: the linear case, where the solver and the dense join agree). The global
/// frame is the first map's.
struct Loop {
  std::vector<Eigen::Vector2d> world;
  std::vector<Submap> maps;
  std::vector<std::vector<int>> seen;  ///< per map: its landmarks' indices in `world`
};

Eigen::Vector3d on_circle(double a) { return {30 * std::cos(a), 30 * std::sin(a), a + M_PI / 2}; }

/// A world point in the frame of pose f.
Eigen::Vector2d world_to(const Eigen::Vector3d& f, const Eigen::Vector2d& w) {
  const double c = std::cos(f(2)), s = std::sin(f(2));
  const Eigen::Vector2d d = w - f.head<2>();
  return {c * d.x() + s * d.y(), -s * d.x() + c * d.y()};
}

Loop make_loop(int landmarks, int maps_per_lap, int laps, double sigma_m, double pose_sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ua(0, 2 * M_PI), ur(22, 38);
  std::normal_distribution<double> n(0, 1);
  Loop L;
  for (int k = 0; k < landmarks; ++k) {
    const double a = ua(rng), r = ur(rng);
    L.world.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  const double step = 2 * M_PI / maps_per_lap;
  FeatureId next = 0;
  for (int k = 0; k < maps_per_lap * laps; ++k) {
    const Eigen::Vector3d a = on_circle(k * step), b = on_circle((k + 1) * step), mid = on_circle((k + 0.5) * step);
    std::vector<Eigen::Vector2d> seen;
    L.seen.emplace_back();
    for (std::size_t w = 0; w < L.world.size(); ++w) {
      if ((L.world[w] - mid.head<2>()).norm() >= 12) continue;
      seen.push_back(L.world[w]);
      L.seen.back().push_back(static_cast<int>(w));
    }
    Submap m;
    m.index = k;
    const int c = static_cast<int>(seen.size());
    m.x.resize(3 + 2 * c);
    const Eigen::Vector2d end = world_to(a, b.head<2>());
    m.x.head<3>() << end.x() + pose_sigma * n(rng), end.y() + pose_sigma * n(rng), step + pose_sigma * n(rng);
    m.P = Eigen::MatrixXd::Identity(3 + 2 * c, 3 + 2 * c) * sigma_m * sigma_m;
    m.P.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * std::max(pose_sigma * pose_sigma, 1e-12);
    for (int i = 0; i < c; ++i) {
      m.x.segment<2>(3 + 2 * i) =
          world_to(a, seen[static_cast<std::size_t>(i)]) + sigma_m * Eigen::Vector2d(n(rng), n(rng));
      m.ids.push_back(next++);
      m.confirmed.push_back(true);
      m.exist_nats.push_back(10.0);
    }
    L.maps.push_back(std::move(m));
  }
  return L;
}

JoinOptions graph_options() {
  JoinOptions o;
  o.solver = JoinOptions::Solver::kGraph;
  return o;
}

/// The loop's maps as factors straight into `fg` (each landmark one variable by its world index: the
/// true association), from the true poses, solved.
void direct_graph(const Loop& L, int maps_per_lap, FactorGraph& fg) {
  const Eigen::Vector3d p0 = on_circle(0);
  const double step = 2 * M_PI / maps_per_lap;
  std::vector<int> var(L.world.size(), -1);
  auto frame = [&](int k) {
    const Eigen::Vector3d a = on_circle(k * step);
    const Eigen::Vector2d t = world_to(p0, a.head<2>());
    return Eigen::Vector3d(t.x(), t.y(), k * step);
  };
  fg.add_frame(frame(0));
  for (std::size_t k = 0; k < L.maps.size(); ++k) {
    const Submap& m = L.maps[k];
    MapFactor f;
    f.from = static_cast<int>(k);
    f.to = fg.add_frame(frame(static_cast<int>(k) + 1));
    for (int w : L.seen[k]) {
      int& v = var[static_cast<std::size_t>(w)];
      if (v < 0) v = fg.add_landmark(world_to(p0, L.world[static_cast<std::size_t>(w)]));
      f.landmarks.push_back(v);
    }
    f.y0 = m.x;
    const Eigen::LLT<Eigen::MatrixXd> info(m.P.inverse());  // W^T W = P^-1
    f.W = info.matrixU();
    f.c = Eigen::VectorXd::Zero(f.W.rows());
    fg.add_map(f);
  }
  fg.solve(20);
}

/// max |a - b| / max |b|.
double relative_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

/// The joint covariance of frames `fs` and landmarks `ls` by ceres::Covariance (sparse QR) on the
/// graph's whole problem.
Eigen::MatrixXd ceres_covariance(const FactorGraph& fg, const std::vector<int>& fs, const std::vector<int>& ls) {
  std::vector<const double*> blocks;
  blocks.reserve(fs.size() + ls.size());
  for (int k : fs) blocks.push_back(fg.frame_block(k));
  for (int j : ls) blocks.push_back(fg.landmark_block(j));
  std::vector<std::pair<const double*, const double*>> pairs;
  for (std::size_t a = 0; a < blocks.size(); ++a)
    for (std::size_t b = a; b < blocks.size(); ++b) pairs.emplace_back(blocks[a], blocks[b]);
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::SPARSE_QR;
  ceres::Covariance cov(co);
  const auto d = static_cast<Eigen::Index>(3 * fs.size() + 2 * ls.size());
  Eigen::MatrixXd out = Eigen::MatrixXd::Constant(d, d, std::numeric_limits<double>::quiet_NaN());
  if (cov.Compute(pairs, &fg.problem())) cov.GetCovarianceMatrix(blocks, out.data());  // symmetric: either order
  return out;
}

}  // namespace

TEST_CASE("factor graph: joint marginals equal ceres::Covariance's to 1e-9 relative (up to 2,000 variables)") {
  for (const int size : {1, 2}) {  // about 200 variables joined by the global map; 2,000 built directly
    CAPTURE(size);
    const Loop L = size == 1 ? make_loop(80, 12, 2, 0.1, 0.02, 7) : make_loop(860, 24, 2, 0.1, 0.02, 7);
    GlobalMap g(graph_options());
    FactorGraph direct;
    if (size == 1) {
      for (const Submap& m : L.maps) g.join(m);
    } else {
      direct_graph(L, 24, direct);
    }
    const FactorGraph& fg = size == 1 ? *g.graph() : direct;
    const int vars = 3 * (fg.frames() - 1) + 2 * fg.landmarks();
    CAPTURE(vars);
    CHECK(vars <= 2000);
    CHECK(vars >= (size == 1 ? 150 : 1500));
    // The query: the first (fixed), a middle and the last frame, and every third landmark.
    std::vector<int> fs = {0, fg.frames() / 2, fg.frames() - 1}, ls;
    ls.reserve(static_cast<std::size_t>(fg.landmarks()) / 3 + 1);
    for (int j = 0; j < fg.landmarks(); j += 3) ls.push_back(j);
    const Eigen::MatrixXd ours = fg.marginal(fs, ls);
    CHECK(relative_difference(ours, ceres_covariance(fg, fs, ls)) < 1e-9);
    CHECK(ours.topLeftCorner<3, 3>().isZero());  // the fixed frame
  }
}

TEST_CASE("factor graph: the fixed window's marginals equal ceres::Covariance's; a factor behind it drops the prior") {
  // One lap of 24 maps (no loop closed), solved; every map but the last 4 absorbed into the prior.
  const Loop L = make_loop(300, 24, 1, 0.1, 0.02, 5);
  FactorGraph fg;
  direct_graph(L, 24, fg);
  fg.settle(4);
  CHECK(fg.settled() == 20);
  // The last frame and the landmarks of the last two maps: in the window.
  std::vector<int> vars;  // the graph's variables of those landmarks (direct_graph numbers them as first seen)
  {
    std::vector<int> var(L.world.size(), -1);
    int next = 0;
    for (std::size_t k = 0; k < L.maps.size(); ++k)
      for (int w : L.seen[k])
        if (var[static_cast<std::size_t>(w)] < 0) var[static_cast<std::size_t>(w)] = next++;
    for (std::size_t k = 22; k < 24; ++k)
      for (int w : L.seen[k])
        if (std::find(vars.begin(), vars.end(), var[static_cast<std::size_t>(w)]) == vars.end())
          vars.push_back(var[static_cast<std::size_t>(w)]);
  }
  REQUIRE(vars.size() >= 10);
  const std::vector<int> fs = {fg.frames() - 1, fg.frames() - 2};
  const Eigen::MatrixXd ours = fg.marginal(fs, vars);
  CHECK(fg.last_marginal_windowed());
  CHECK(relative_difference(ours, ceres_covariance(fg, fs, vars)) < 1e-9);
  // With the first map's landmarks (eliminated): from every factor, the same.
  std::vector<int> old = vars;
  old.push_back(0);
  const Eigen::MatrixXd all = fg.marginal(fs, old);
  CHECK_FALSE(fg.last_marginal_windowed());
  CHECK(relative_difference(all, ceres_covariance(fg, fs, old)) < 1e-9);
  // A factor on an eliminated landmark (a loop closure into the past): the prior is dropped.
  MapFactor f;
  f.from = fg.frames() - 1;
  f.to = fg.add_frame(fg.frame(f.from));
  f.landmarks = {0};
  f.y0 = Eigen::VectorXd::Zero(5);
  f.y0.tail<2>() = world_to(fg.frame(f.from), fg.landmark(0));
  f.W = Eigen::MatrixXd::Identity(5, 5);
  f.c = Eigen::VectorXd::Zero(5);
  fg.add_map(f);
  CHECK(fg.settled() == 0);
}

TEST_CASE("factor graph: around a loop of local maps every join decides as the dense join's") {
  const Loop L = make_loop(120, 10, 2, 0.15, 1e-6, 11);
  GlobalMap dense{JoinOptions{}}, graph(graph_options());
  int fused = 0;
  for (const Submap& m : L.maps) {
    CAPTURE(m.index);
    const JoinResult a = dense.join(m), b = graph.join(m);
    CHECK(a.offered == b.offered);
    CHECK(a.fused == b.fused);
    CHECK(a.declined == b.declined);
    CHECK(a.pruned == b.pruned);
    CHECK(a.dropped == b.dropped);
    CHECK(a.refused == b.refused);
    CHECK(a.pairs == b.pairs);
    CHECK(a.joint_d2 == doctest::Approx(b.joint_d2).epsilon(1e-4));
    fused += b.fused;
  }
  CHECK(fused > 100);  // the second lap closes the loop on the first
  // The same estimate, up to the dense join's fused constraint (l_new - l_global = 0 with variance
  // constraint_var_m2, 1e-6 m^2, against the graph's one variable): 1e-6 / 0.005 m^2 of a fused
  // landmark's variance.
  REQUIRE(dense.landmarks() == graph.landmarks());
  for (int k = 0; k < graph.landmarks(); ++k) {
    CHECK((dense.landmark(k) - graph.landmark(k)).norm() < 1e-4);
    CHECK(relative_difference(graph.landmark_covariance(k), dense.landmark_covariance(k)) < 1e-3);
  }
  CHECK(relative_difference(graph.base_covariance(), dense.base_covariance()) < 1e-3);
}

TEST_CASE("factor graph: env1 in local maps of 30 landmarks, seeded: no wrong join, every map joined, F1 as dense") {
  const Scenario s = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  RunOptions o;
  o.step.strategy = Strategy::kPcjcbb;
  o.submaps = true;
  o.submap_seed = true;
  o.step.submap_landmarks = 30;
  const RunResult dense = run_slam(s, 3, o);
  o.join.solver = JoinOptions::Solver::kGraph;
  const RunResult graph = run_slam(s, 3, o);
  CHECK(graph.submaps.maps == dense.submaps.maps);
  CHECK(graph.submaps.wrong == 0);
  CHECK(graph.submaps.refused == 0);
  CHECK(graph.score.f1() > 0.98);
  CHECK(graph.landmarks <= dense.landmarks + 2);
  CHECK(graph.landmarks >= dense.landmarks - 2);
}
