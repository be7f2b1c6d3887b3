// Benchmark suite "strategies": the six strategies (and GEOJCBB with the papers' merge, without our
// joint re-check) on the same generated scenes, from sparse to dense maps, M = 10 .. 32. Per
// strategy: median / p90 / max microseconds per scan, JCBB nodes, precision, recall and F1 against
// ground truth, the share of answers failing the joint test, and ratios to plain JCBB in the same
// run. Packed covariance's baseline in the same run: JCBB and GEOJCBB as before it (all
// of C checked before the stages; EM stopped by the papers' objective tolerance only).
// Maps extend beyond the sensor's range (as a SLAM map does), which is what the local region prunes.
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "bench_common.hpp"

namespace geojcbb::bench {
namespace {

using SB = Bounds<32, 512, 8, 200000, 512>;  // M <= 32, every map feature a candidate

struct Variant {
  std::string name;
  AssociationConfig<double, SB> cfg;
};

struct Row {
  std::vector<double> us, nodes, cluster_it;
  host::Score score;
  int fail_joint = 0, budget_hits = 0, cluster_bound_hits = 0, calls = 0;
};

struct MapSet {
  const char* name;
  int landmarks;
  double map_range_m;
  double pose_xy_m, pose_theta_rad;
};

struct Problem {
  Observations<double, SB> obs;
  Prediction<double, SB> pred;
  AssociationWorkspace<double, SB> ws;
  Association<double, SB> out;
};

constexpr double kSensorRange = 10.0, kCompensation = 2.0;
constexpr std::size_t kJcbb = 1, kGeo = 5;  // indices of the presets in Variants::list

// The settings every variant starts from.
StepSettings<double> base_settings(const BenchOptions& o) {
  StepSettings<double> sp;
  sp.confidence = o.confidence;
  sp.local_radius_m = kSensorRange + kCompensation;
  sp.groups = 3;
  sp.dbscan_eps_m = 2.0;
  sp.dbscan_min_points = 2;
  sp.node_budget = o.node_budget;
  return sp;
}

// The six presets, GEOJCBB's variants, and packed covariance's baseline (JCBB and GEOJCBB as before
// it), with where that baseline sits in the list.
struct Variants {
  std::vector<Variant> list;
  std::size_t jcbb_old = 0, geo_old = 0;
};

// False: a preset could not be made from the settings.
bool make_variants(StepSettings<double> sp, Variants& vs) {
  std::vector<Variant>& variants = vs.list;
  for (int s = 0; s < kStrategyCount; ++s) {
    Variant v{to_string(static_cast<Strategy>(s)), {}};
    if (make_strategy(static_cast<Strategy>(s), sp, v.cfg) != Status::kOk) return false;
    variants.push_back(v);
  }
  Variant papers{"GEOJCBB, no re-check", {}};
  sp.joint_recheck = false;
  if (make_strategy(Strategy::kGeojcbb, sp, papers.cfg) != Status::kOk) return false;
  variants.push_back(papers);
  Variant conditioned{"GEOJCBB, conditioned groups", {}};
  sp.joint_recheck = true;
  sp.condition_groups = true;
  if (make_strategy(Strategy::kGeojcbb, sp, conditioned.cfg) != Status::kOk) return false;
  variants.push_back(conditioned);
  Variant ungrouped{"JCBB + exclusion + optimal", variants[kJcbb].cfg};  // GEOJCBB's search, one group
  ungrouped.cfg.mutual_exclusion = true;
  ungrouped.cfg.optimal_criterion = true;
  variants.push_back(ungrouped);
  // Packed covariance's baseline: the behaviour before it (full check of C up front; the
  // papers' EM stop).
  sp.condition_groups = false;
  sp.full_covariance_check = true;
  sp.papers_em = true;
  vs.jcbb_old = variants.size();
  vs.geo_old = vs.jcbb_old + 1;
  Variant jcbb_old{"JCBB, before packed covariance", {}};
  if (make_strategy(Strategy::kJcbb, sp, jcbb_old.cfg) != Status::kOk) return false;
  variants.push_back(jcbb_old);
  Variant geo_old{"GEOJCBB, before packed covariance", {}};
  if (make_strategy(Strategy::kGeojcbb, sp, geo_old.cfg) != Status::kOk) return false;
  variants.push_back(geo_old);
  return true;
}

void print_header(const BenchOptions& o, const StepSettings<double>& sp, const Variants& vs) {
  std::printf("# The six strategies\n\n");
  std::printf(
      "scenes per cell: %d, seed %llu, chi2 level %.4g; map of N landmarks within R of the robot, "
      "sensor range %.0f m (field of view +-149 deg), local region r + d = %.0f m; 20%% clutter; "
      "K = %d groups (k-means, GMM-EM), DBSCAN eps %.1f m / min points %d; node budget %d per scan; "
      "double\n",
      o.scenes, static_cast<unsigned long long>(o.seed), o.confidence, kSensorRange, kSensorRange + kCompensation,
      sp.groups, sp.dbscan_eps_m, sp.dbscan_min_points, vs.list[kJcbb].cfg.search_nodes());
  std::printf("speed-up and dF1 are against plain JCBB on the same scenes in the same run\n\n");
  std::printf(
      "maps: sparse N = 120 within R = 20 m, medium 180 within 16 m, dense 500 within 18 m; pose error "
      "sigma 0.2 / 0.3 / 0.4 m and 0.02 / 0.03 / 0.04 rad\n\n");
  std::printf(
      "| map | M | strategy | median us | p90 us | p99 us | max us | speed-up | nodes med/max | budget hits | cluster it. med/max | cluster bound hits | precision | recall | F1 | dF1 | fail joint |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
}

host::SceneParams cell_params(const MapSet& set, int m) {
  host::SceneParams params;
  params.observations = m;
  params.landmarks = set.landmarks;
  params.max_range_m = kSensorRange;
  params.map_range_m = set.map_range_m;
  params.min_separation_m = 0.5;
  params.sigma_pose_xy_m = set.pose_xy_m;
  params.sigma_pose_theta_rad = set.pose_theta_rad;
  return params;
}

// Every variant on every scene of a cell, in rotating order, into rows (per variant). False: a scene
// over capacity or a failed association (reported on stderr).
bool run_cell(const host::SceneParams& params, const BenchOptions& o, const std::vector<Variant>& variants, Problem& p,
              std::vector<Row>& rows) {
  for (int k = 0; k < o.scenes; ++k) {
    const host::Scene scene = host::make_scene(params, o.seed + static_cast<std::uint64_t>(k));
    if (!host::to_inputs(scene, p.obs, p.pred)) return false;
    for (std::size_t q = 0; q < variants.size(); ++q) {
      const std::size_t v = (q + static_cast<std::size_t>(k)) % variants.size();  // rotate the order
      const auto t0 = Clock::now();
      const Status s = associate(p.obs, p.pred, variants[v].cfg, p.ws, p.out);
      const auto t1 = Clock::now();
      if (s != Status::kOk) {
        std::fprintf(stderr, "%s: %s\n", variants[v].name.c_str(), to_string(s));
        return false;
      }
      Row& r = rows[v];
      r.us.push_back(elapsed_us(t0, t1));
      r.nodes.push_back(p.out.diag.jcbb_nodes);
      r.budget_hits += p.out.diag.node_budget_hit;
      r.cluster_it.push_back(p.out.diag.cluster_iterations);
      r.cluster_bound_hits += p.out.diag.cluster_bound_hit;
      r.fail_joint += !p.out.jointly_compatible;
      ++r.calls;
      std::vector<int> hyp(scene.z.size());
      for (std::size_t i = 0; i < hyp.size(); ++i) hyp[i] = p.out.candidate[i];
      r.score.add(host::score(scene, hyp));
    }
  }
  return true;
}

// A cell's rows: per variant the time quantiles, the ratios to plain JCBB, nodes, budget and
// cluster bound hits, the scores; to the CSV file too when it is open.
void print_cell(const MapSet& set, int m, const std::vector<Variant>& variants, const std::vector<Row>& rows,
                std::ofstream& csv) {
  const double jcbb_med = quantile(rows[kJcbb].us, 0.5);
  const double jcbb_f1 = rows[kJcbb].score.f1();
  for (std::size_t v = 0; v < variants.size(); ++v) {
    const Row& r = rows[v];
    const double med = quantile(r.us, 0.5), p90 = quantile(r.us, 0.9), p99 = quantile(r.us, 0.99),
                 mx = quantile(r.us, 1.0);
    const double speedup = jcbb_med / med, df1 = r.score.f1() - jcbb_f1;
    const double fail = double(r.fail_joint) / r.calls;
    std::printf(
        "| %s | %d | %s | %.1f | %.1f | %.1f | %.1f | %.2fx | %.0f/%.0f | %d | %.0f/%.0f | %d | %.4f | %.4f | %.4f | %+.4f | %.2f |\n",
        set.name, m, variants[v].name.c_str(), med, p90, p99, mx, speedup, quantile(r.nodes, 0.5),
        quantile(r.nodes, 1.0), r.budget_hits, quantile(r.cluster_it, 0.5), quantile(r.cluster_it, 1.0),
        r.cluster_bound_hits, r.score.precision(), r.score.recall(), r.score.f1(), df1, fail);
    if (csv) {
      csv << set.name << ',' << m << ',' << variants[v].name << ',' << r.calls << ',' << med << ',' << p90 << ',' << mx
          << ',' << speedup << ',' << quantile(r.nodes, 0.5) << ',' << quantile(r.nodes, 1.0) << ',' << r.budget_hits
          << ',' << r.score.precision() << ',' << r.score.recall() << ',' << r.score.f1() << ',' << df1 << ',' << fail
          << '\n';
    }
  }
}

// Packed covariance's goals, against the baseline in this run, and the dense maps' goal, over the cells.
struct Goals {
  std::vector<std::string> fixed_cost_rows;
  bool jcbb3x = true, geo_not_slower = true, geo_p99 = true;
  bool goal_met = true;
  int goal_cells = 0;

  void add(const MapSet& set, int m, const Variants& vs, const std::vector<Row>& rows) {
    const double jcbb_med = quantile(rows[kJcbb].us, 0.5);
    {  // packed covariance's goals, against the baseline in this run
      const double jcbb_old_med = quantile(rows[vs.jcbb_old].us, 0.5);
      const double geo_med = quantile(rows[kGeo].us, 0.5), geo_old_med = quantile(rows[vs.geo_old].us, 0.5);
      const double p99_ratio = quantile(rows[kJcbb].us, 0.99) / quantile(rows[kGeo].us, 0.99);
      char line[256];
      std::snprintf(line, sizeof line, "| %s | %d | %.2fx | %.2fx | %.2f | %.2fx | %+.4f | %+.4f |", set.name, m,
                    jcbb_old_med / jcbb_med, geo_old_med / geo_med, geo_med / jcbb_med, p99_ratio,
                    rows[kJcbb].score.f1() - rows[vs.jcbb_old].score.f1(),
                    rows[kGeo].score.f1() - rows[vs.geo_old].score.f1());
      fixed_cost_rows.push_back(line);
      const bool sparse_or_medium = std::string(set.name) != "dense";
      if (sparse_or_medium) jcbb3x = jcbb3x && jcbb_old_med / jcbb_med >= 3.0;
      geo_not_slower = geo_not_slower && geo_med <= jcbb_med;
      if (!sparse_or_medium && m >= 20) geo_p99 = geo_p99 && p99_ratio >= 5.0;
    }
    if (std::string(set.name) == "dense" && m >= 20) {
      ++goal_cells;
      const double speedup = jcbb_med / quantile(rows[kGeo].us, 0.5);
      const double df1 = rows[kGeo].score.f1() - rows[kJcbb].score.f1();
      goal_met = goal_met && speedup >= 5.0 && df1 >= -0.005;
    }
  }

  void print() const {
    std::printf("\n# Packed covariance: the association's fixed cost, against its baseline in the same run\n\n");
    std::printf(
        "| map | M | JCBB median speed-up | GEOJCBB median speed-up | GEOJCBB / JCBB median | JCBB / GEOJCBB p99 | "
        "JCBB dF1 | GEOJCBB dF1 |\n|---|---|---|---|---|---|---|---|\n");
    for (const std::string& l : fixed_cost_rows) std::printf("%s\n", l.c_str());
    std::printf(
        "\ngoals: JCBB median >= 3x lower than before on sparse and medium maps: %s; GEOJCBB never slower "
        "than JCBB at the median: %s; dense maps, M >= 20: GEOJCBB's p99 >= 5x below JCBB's: %s\n",
        jcbb3x ? "met" : "NOT met", geo_not_slower ? "met" : "NOT met", geo_p99 ? "met" : "NOT met");
    if (goal_cells > 0) {
      std::printf("\ngoal (dense maps, M >= 20: GEOJCBB >= 5x faster than JCBB, F1 loss <= 0.005): %s\n",
                  goal_met ? "met" : "NOT met");
    }
  }
};

}  // namespace

int run_strategy_suite(const BenchOptions& o) {
  const StepSettings<double> sp = base_settings(o);
  Variants vs;
  if (!make_variants(sp, vs)) return 2;
  const MapSet sets[] = {{"sparse", 120, 20, 0.2, 0.02}, {"medium", 180, 16, 0.3, 0.03}, {"dense", 500, 18, 0.4, 0.04}};
  print_header(o, sp, vs);
  std::ofstream csv;
  if (!o.out_dir.empty()) {
    csv.open(o.out_dir + "/strategies.csv");
    csv << "map,M,strategy,calls,median_us,p90_us,max_us,speedup_vs_jcbb,nodes_median,nodes_max,budget_hits,"
           "precision,recall,f1,df1_vs_jcbb,fail_joint_share\n";
  }
  auto p = std::make_unique<Problem>();
  Goals goals;
  for (const MapSet& set : sets) {
    for (int m : {10, 20, 32}) {
      if (o.quick && m > 10) continue;
      std::vector<Row> rows(vs.list.size());
      if (!run_cell(cell_params(set, m), o, vs.list, *p, rows)) return 2;
      print_cell(set, m, vs.list, rows, csv);
      goals.add(set, m, vs, rows);
      std::fflush(stdout);
    }
  }
  goals.print();
  return 0;
}

}  // namespace geojcbb::bench
