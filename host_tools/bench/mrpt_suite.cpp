// Benchmark suite "mrpt": our ICNN and JCBB against MRPT's data_association_full_covariance (NN and
// JCBB) on identical generated EKF-SLAM-like scenes, in one process, calls interleaved in rotating
// order. Reports per cell: median / p90 / max microseconds per call, JCBB nodes, precision and recall
// against ground truth, and the share of outputs that fail the joint compatibility test.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "bench_common.hpp"

#if GEOJCBB_WITH_MRPT
#include <mrpt/math/CMatrixDynamic.h>
#include <mrpt/slam/data_association.h>
#endif

namespace geojcbb::bench {
namespace {

using B = Bounds<32, 128, 8, 200000, 128>;  // host capacity: M <= 32, N <= 128

enum Method { kMrptNn, kMrptJcbb, kOurIcnn, kOurJcbb, kMethods };
const char* kNames[kMethods] = {"MRPT-NN", "MRPT-JCBB", "our ICNN", "our JCBB"};

struct Cell {
  std::string set;
  int m, n;
  host::SceneParams params;
};

struct Stats {
  std::vector<double> us;
  std::vector<double> nodes;
  host::Score score;
  int fail_joint = 0;
  int calls = 0;
  bool available = true;
};

struct Ours {
  Observations<double, B> obs;
  Prediction<double, B> pred;
  AssociationWorkspace<double, B> ws;
  Association<double, B> out;
  AssociationConfig<double, B> icnn, jcbb;
};

// The cells: the standard set (N = 20, 50, 100 landmarks at a constant density, M = 5 - 30
// observations) and the dense set (50 landmarks in a 4 m field of view, M = dense_m).
std::vector<Cell> make_cells(const BenchOptions& o) {
  std::vector<Cell> cells;
  for (int n : {20, 50, 100}) {
    for (int m : {5, 10, 20, 30}) {
      if ((o.quick && m > 10) || o.dense_only) continue;
      host::SceneParams p;
      p.observations = m;
      p.landmarks = n;
      p.max_range_m = 8.0 * std::sqrt(n / 20.0);  // constant landmark density across N
      cells.push_back({"standard", m, n, p});
    }
  }
  for (int m : o.dense_m) {
    if (o.quick && m > 10) continue;
    host::SceneParams p;  // dense: 50 landmarks in a 4 m field of view, larger pose error
    p.observations = m;
    p.landmarks = 50;
    p.max_range_m = 4.0;
    p.sigma_pose_xy_m = 0.4;
    p.sigma_pose_theta_rad = 0.04;
    cells.push_back({"dense", m, 50, p});
  }
  return cells;
}

// Our ICNN and JCBB set up as MRPT runs: mutual exclusion, the optimal criterion. False: a bad
// confidence.
bool configure_ours(Ours& ours, double confidence) {
  for (auto* c : {&ours.icnn, &ours.jcbb}) {
    if (GateThresholds<double, B::kMaxObservations>::from_confidence(confidence, confidence, c->gate) != Status::kOk)
      return false;
    c->mutual_exclusion = true;   // as MRPT does
    c->optimal_criterion = true;  // MRPT ranks equal-size leaves by joint distance
  }
  ours.icnn.search = SearchMethod::kIcnn;
  ours.jcbb.search = SearchMethod::kJcbb;
  return true;
}

void print_header(const BenchOptions& o) {
  std::printf("# Side by side with MRPT\n\n");
  std::printf(
      "scenes per cell: %d, seed %llu, chi2 level %.4g, 20%% clutter, one R for all observations, "
      "bearings within +-%.0f deg (no innovation wraps, so MRPT's unwrapped innovations are exact)\n",
      o.scenes, static_cast<unsigned long long>(o.seed), o.confidence, 2.6 * 180 / kPi<double>);
  std::printf(
      "our ICNN and JCBB: double, mutual exclusion and optimal criterion on, fewest-candidates-first "
      "ordering, node budget %d\n",
      B::kMaxJcbbNodes);
#if GEOJCBB_WITH_MRPT
  std::printf("MRPT %s: data_association_full_covariance, metricMaha, S = C + blockdiag(R), kd-tree prefilter %s\n",
              "(libmrpt-slam 2.5)", o.mrpt_kdtree ? "ON (its default)" : "OFF");
#else
  std::printf("MRPT: not built (configure with -DGEOJCBB_WITH_MRPT=ON, preset 'bench')\n");
#endif
  std::printf(
      "\n| set | M | N | method | median us | p90 us | max us | nodes med/max | precision | recall | fail joint |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
}

#if GEOJCBB_WITH_MRPT
// A scene as MRPT takes it: the observations Z, the predictions Y and their covariance C + blockdiag(R).
struct MrptScene {
  mrpt::math::CMatrixDouble Z, Y, YC;
  explicit MrptScene(const host::Scene& scene)
      : Z(static_cast<int>(scene.z.size()), 2),
        Y(static_cast<int>(scene.h.size()), 2),
        YC(2 * static_cast<int>(scene.h.size()), 2 * static_cast<int>(scene.h.size())) {
    const int m = static_cast<int>(scene.z.size());
    const int n = static_cast<int>(scene.h.size());
    for (int i = 0; i < m; ++i) {
      Z(i, 0) = scene.z[i].x();
      Z(i, 1) = scene.z[i].y();
    }
    for (int j = 0; j < n; ++j) {
      Y(j, 0) = scene.h[j].x();
      Y(j, 1) = scene.h[j].y();
    }
    for (int r = 0; r < 2 * n; ++r)
      for (int c = 0; c < 2 * n; ++c) YC(r, c) = scene.C(r, c);
    for (int j = 0; j < n; ++j)
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) YC(2 * j + a, 2 * j + b) += scene.R(a, b);
  }
};
#else
struct MrptScene {
  explicit MrptScene(const host::Scene&) {}
};
#endif

// One call of `method` on a scene, timed into st: its hypothesis in hyp and its JCBB nodes. False:
// our association failed. MRPT's JCBB is skipped once its cell's total passes the cap.
bool time_call(int method, const BenchOptions& o, [[maybe_unused]] const MrptScene& mrpt, Ours& ours,
               [[maybe_unused]] double& mrpt_jcbb_total_s, Stats& st, std::vector<int>& hyp, double& nodes,
               bool& skipped) {
  skipped = false;
  const auto t0 = Clock::now();
  if (method == kOurIcnn || method == kOurJcbb) {
    const auto& cfg = method == kOurIcnn ? ours.icnn : ours.jcbb;
    if (associate(ours.obs, ours.pred, cfg, ours.ws, ours.out) != Status::kOk) return false;
    const auto t1 = Clock::now();
    st.us.push_back(elapsed_us(t0, t1));
    for (std::size_t i = 0; i < hyp.size(); ++i) hyp[i] = ours.out.candidate[i];
    nodes = ours.out.diag.jcbb_nodes;
    return true;
  }
#if GEOJCBB_WITH_MRPT
  if (method == kMrptJcbb && mrpt_jcbb_total_s > o.mrpt_cell_cap_s) {
    skipped = true;
    return true;
  }
  mrpt::slam::TDataAssociationResults res;
  mrpt::slam::data_association_full_covariance(mrpt.Z, mrpt.Y, mrpt.YC, res,
                                               method == kMrptNn ? mrpt::slam::assocNN : mrpt::slam::assocJCBB,
                                               mrpt::slam::metricMaha, o.confidence, o.mrpt_kdtree);
  const auto t1 = Clock::now();
  const double us = elapsed_us(t0, t1);
  st.us.push_back(us);
  if (method == kMrptJcbb) mrpt_jcbb_total_s += us * 1e-6;
  for (const auto& [i, j] : res.associations) hyp[i] = static_cast<int>(j);
  nodes = static_cast<double>(res.nNodesExploredInJCBB);
#else
  (void)o;
#endif
  return true;
}

// Every method on every scene of a cell, in rotating order, into st (per method). False: a scene
// over capacity or a failed association (reported on stderr).
bool run_cell(const Cell& cell, const BenchOptions& o, Ours& ours, IncrementalJoint<double, B::kMaxObservations>& joint,
              Stats (&st)[kMethods]) {
  double mrpt_jcbb_total_s = 0;
#if !GEOJCBB_WITH_MRPT
  st[kMrptNn].available = st[kMrptJcbb].available = false;
#endif
  for (int k = 0; k < o.scenes; ++k) {
    const host::Scene scene = host::make_scene(cell.params, o.seed + static_cast<std::uint64_t>(k));
    if (!host::to_inputs(scene, ours.obs, ours.pred)) {
      std::fprintf(stderr, "scene over capacity\n");
      return false;
    }
    const MrptScene mrpt(scene);
    for (int q = 0; q < kMethods; ++q) {
      const int method = (q + k) % kMethods;  // rotate which method runs first
      if (!st[method].available) continue;
      std::vector<int> hyp(scene.z.size(), -1);
      double nodes = 0;
      bool skipped = false;
      if (!time_call(method, o, mrpt, ours, mrpt_jcbb_total_s, st[method], hyp, nodes, skipped)) {
        std::fprintf(stderr, "associate failed\n");
        return false;
      }
      if (skipped) continue;
      st[method].nodes.push_back(nodes);
      ++st[method].calls;
      st[method].score.add(host::score(scene, hyp));
      // The joint test of the output, with the library's factor (double).
      std::array<std::int16_t, B::kMaxObservations> h{};
      int pairs = 0;
      for (std::size_t i = 0; i < hyp.size(); ++i) {
        h[i] = static_cast<std::int16_t>(hyp[i]);
        pairs += hyp[i] >= 0;
      }
      double d2 = 0;
      if (hypothesis_joint_d2(ours.obs, ours.pred, h, joint, d2) != Status::kOk ||
          !(d2 <= ours.jcbb.gate.joint[pairs])) {
        ++st[method].fail_joint;
      }
    }
  }
  return true;
}

// A cell's rows: per method the time quantiles, nodes, precision, recall and the share failing the
// joint test; to the CSV file too when it is open.
void print_cell(const Cell& cell, const Stats (&st)[kMethods], int scenes, std::ofstream& csvf) {
  for (int method = 0; method < kMethods; ++method) {
    const Stats& s = st[method];
    if (!s.available || s.calls == 0) continue;
    const double med = quantile(s.us, 0.5), p90 = quantile(s.us, 0.9), mx = quantile(s.us, 1.0);
    const double share = double(s.fail_joint) / s.calls;
    std::printf("| %s | %d | %d | %s%s | %.1f | %.1f | %.1f | %.0f/%.0f | %.3f | %.3f | %.2f |\n", cell.set.c_str(),
                cell.m, cell.n, kNames[method],
                s.calls < scenes ? (" (" + std::to_string(s.calls) + " scenes)").c_str() : "", med, p90, mx,
                quantile(s.nodes, 0.5), quantile(s.nodes, 1.0), s.score.precision(), s.score.recall(), share);
    if (csvf) {
      csvf << cell.set << ',' << cell.m << ',' << cell.n << ',' << kNames[method] << ',' << s.calls << ',' << med << ','
           << p90 << ',' << mx << ',' << quantile(s.nodes, 0.5) << ',' << quantile(s.nodes, 1.0) << ','
           << s.score.precision() << ',' << s.score.recall() << ',' << share << '\n';
    }
  }
}

}  // namespace

int run_mrpt_suite(const BenchOptions& o) {
  const std::string csv = o.out_dir.empty() ? std::string() : o.out_dir + "/mrpt.csv";
  const std::vector<Cell> cells = make_cells(o);
  auto ours = std::make_unique<Ours>();
  if (!configure_ours(*ours, o.confidence)) {
    std::fprintf(stderr, "bad confidence\n");
    return 2;
  }
  IncrementalJoint<double, B::kMaxObservations> joint;
  print_header(o);
  std::ofstream csvf;
  if (!csv.empty()) {
    csvf.open(csv);
    csvf << "set,M,N,method,calls,median_us,p90_us,max_us,nodes_median,nodes_max,precision,recall,fail_joint_share\n";
  }
  double ratio_m20_n50 = 0;
  for (const Cell& cell : cells) {
    Stats st[kMethods];
    if (!run_cell(cell, o, *ours, joint, st)) return 2;
    print_cell(cell, st, o.scenes, csvf);
    if (cell.set == "standard" && cell.m == 20 && cell.n == 50 && st[kMrptJcbb].calls > 0) {
      ratio_m20_n50 = quantile(st[kMrptJcbb].us, 0.5) / quantile(st[kOurJcbb].us, 0.5);
    }
    std::fflush(stdout);
  }
  if (ratio_m20_n50 > 0) {
    std::printf("\nM = 20, N = 50: MRPT-JCBB median / our JCBB median = %.1fx (same run, same scenes)\n",
                ratio_m20_n50);
  }
  return 0;
}

}  // namespace geojcbb::bench
