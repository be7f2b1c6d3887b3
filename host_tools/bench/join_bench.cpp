// The host's global map as it grows (docs/submaps.md, "How the host's join scales"; docs/mapping.md):
// a chain of generated local maps along a corridor, each with `--map-landmarks` landmarks of which
// `--overlap` are the previous map's last ones seen again (found by the join's association, not by
// their ids), joined one after the other until the global map holds `--max-landmarks`, dense or on
// the solver (`--solver`). Per size bin of the global map: the join's median and 95th percentile
// and maximum and the median's ratio to the first bin's (measured in the same run: timing is
// reported, never asserted), a joint-marginal query's (the base and the 100 landmarks nearest it)
// and how many the window answered, what was fused and kept apart, and the process's peak resident
// memory at the bin's end. Each bin is printed when the map grows past it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <Eigen/Dense>

#include "geojcbb_host/factor_graph.hpp"
#include "geojcbb_host/global_map.hpp"
#include "geojcbb_host/guarded_main.hpp"

namespace {

using geojcbb::FeatureId;
using geojcbb::host::GlobalMap;
using geojcbb::host::JoinOptions;
using geojcbb::host::JoinResult;
using geojcbb::host::Submap;

struct Options {
  int max_landmarks = 3200;
  int map_landmarks = 72;
  int overlap = 12;
  double sigma_m = 0.1;
  unsigned seed = 1;
  JoinOptions::Solver solver = JoinOptions::Solver::kDense;
  int window = JoinOptions{}.solver_window;
};

/// The process's peak resident memory so far [MB].
double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

/// Map k of the chain: its frame begins at the world's (k L, 0) heading along x and it ends at (L, 0,
/// 0) in it. `world` are the landmarks it sees (world frame), each measured with independent noise.
Submap make_map(int k, double L, const std::vector<Eigen::Vector2d>& world, FeatureId& next_id, double sigma,
                std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, sigma);
  Submap m;
  m.index = k;
  const int count = static_cast<int>(world.size());
  m.x.resize(3 + 2 * count);
  m.x.head<3>() << L, 0, 0;
  m.P = Eigen::MatrixXd::Identity(3 + 2 * count, 3 + 2 * count) * sigma * sigma;
  m.P.topLeftCorner<3, 3>() = Eigen::Vector3d(1e-4, 1e-4, 1e-6).asDiagonal();
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d& w = world[static_cast<std::size_t>(i)];
    const double ex = n(rng);
    m.x.segment<2>(3 + 2 * i) = Eigen::Vector2d(w.x() - k * L + ex, w.y() + n(rng));
    m.ids.push_back(next_id++);
    m.confirmed.push_back(true);
    m.exist_nats.push_back(10.0);
  }
  return m;
}

/// The q-quantile (nearest rank) of v.
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, k == 0 ? 0 : k - 1)];
}

/// The time of a joint-marginal query: the base and the 100 landmarks nearest it [ms].
double query_ms(const GlobalMap& g) {
  std::vector<std::pair<double, int>> near;
  near.reserve(static_cast<std::size_t>(g.landmarks()));
  const Eigen::Vector2d base = g.state().head<2>();
  for (int k = 0; k < g.landmarks(); ++k) near.emplace_back((g.landmark(k) - base).norm(), k);
  const auto n = std::min<std::size_t>(100, near.size());
  std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(n), near.end());
  std::vector<int> gs;
  for (std::size_t k = 0; k < n; ++k) gs.push_back(near[k].second);
  const auto t0 = std::chrono::steady_clock::now();
  const Eigen::MatrixXd S = g.joint_marginal(gs);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (S.rows() != 3 + 2 * static_cast<Eigen::Index>(n)) throw std::runtime_error("joint_marginal: wrong size");
  return ms;
}

int run(int argc, char** argv) {
  CLI::App app{"the host's join as the global map grows (timing is measured, never asserted)"};
  Options o;
  app.add_option("--max-landmarks", o.max_landmarks, "stop when the global map holds this many")
      ->check(CLI::Range(100, 200000));
  app.add_option("--map-landmarks", o.map_landmarks, "landmarks per local map")->check(CLI::Range(8, 128));
  app.add_option("--overlap", o.overlap, "of those, the previous map's last ones seen again")->check(CLI::Range(0, 64));
  app.add_option("--sigma", o.sigma_m, "landmark noise [m]")->check(CLI::Range(0.001, 1.0));
  app.add_option("--seed", o.seed, "random seed");
  app.add_option("--solver", o.solver, "the global map: dense (the EKF-style join) or graph (factors on Ceres)")
      ->transform(CLI::CheckedTransformer(std::map<std::string, JoinOptions::Solver>{
          {"dense", JoinOptions::Solver::kDense}, {"graph", JoinOptions::Solver::kGraph}}));
  app.add_option("--window", o.window, "with --solver graph: the fixed window in front [local maps]; 0: none")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000000));
  CLI11_PARSE(app, argc, argv);
  if (o.overlap >= o.map_landmarks) throw std::runtime_error("--overlap must be below --map-landmarks");

  std::mt19937 rng(o.seed);
  const int fresh = o.map_landmarks - o.overlap;
  const double L = fresh * 0.5;  // 20 m wide corridor, one landmark per 10 m^2
  std::uniform_real_distribution<double> ux(0.0, L), uy(-10.0, 10.0);
  JoinOptions jo;
  jo.solver = o.solver;
  jo.solver_window = o.window;
  GlobalMap g{jo};
  FeatureId next_id = 0;
  std::vector<Eigen::Vector2d> previous;
  struct Bin {
    int upto;
    std::vector<double> ms, query_ms;
    int joins = 0, fused = 0, expected = 0, declined = 0, refused = 0, windowed = 0;
    double rss_mb = 0;
  };
  std::vector<Bin> bins;
  for (int b = 100; b <= o.max_landmarks * 2; b *= 2) bins.push_back(Bin{b, {}, {}, 0, 0, 0, 0, 0, 0, 0});
  std::printf("# the host's join as the global map grows (%s%s): %d-landmark local maps, %d seen again per map\n\n",
              o.solver == JoinOptions::Solver::kGraph ? "graph" : "dense",
              o.solver == JoinOptions::Solver::kGraph ? (", window " + std::to_string(o.window)).c_str() : "",
              o.map_landmarks, o.overlap);
  std::printf(
      "| global landmarks before the join | joins | join median [ms] | join p95 [ms] | join max [ms] | median / first "
      "bin's | query median [ms] | query p95 [ms] | queries from the window | fused / seen again | declined or "
      "pruned | refused | peak resident [MB] |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- "
      "| --- |\n");
  std::fflush(stdout);
  double base = 0;
  std::size_t printed = 0;
  int lo = 0;
  auto print_bins = [&](std::size_t upto) {  // each bin once it is complete
    for (; printed < upto; ++printed) {
      const Bin& b = bins[printed];
      if (b.joins > 0) {
        const double med = quantile(b.ms, 0.5);
        if (base == 0) base = med;
        std::printf("| %d-%d | %d | %.2f | %.2f | %.2f | %.1f | %.2f | %.2f | %d / %d | %d / %d | %d | %d | %.0f |\n",
                    lo, b.upto - 1, b.joins, med, quantile(b.ms, 0.95), quantile(b.ms, 1.0), med / base,
                    quantile(b.query_ms, 0.5), quantile(b.query_ms, 0.95), b.windowed, b.joins, b.fused, b.expected,
                    b.declined, b.refused, b.rss_mb);
        std::fflush(stdout);
      }
      lo = b.upto;
    }
  };
  for (int k = 0; g.landmarks() < o.max_landmarks; ++k) {
    std::vector<Eigen::Vector2d> world(previous.end() - std::min<std::ptrdiff_t>(o.overlap, previous.size()),
                                       previous.end());
    const int seen_again = static_cast<int>(world.size());
    for (int i = 0; i < fresh; ++i) {  // sorted along x: the last ones are the next map's overlap
      const double x = k * L + ux(rng);
      world.emplace_back(x, uy(rng));
    }
    std::sort(world.begin() + seen_again, world.end(),
              [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() < b.x(); });
    const Submap m = make_map(k, L, world, next_id, o.sigma_m, rng);
    const int before = g.landmarks();
    const auto t0 = std::chrono::steady_clock::now();
    const JoinResult j = g.join(m);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    auto bin = std::find_if(bins.begin(), bins.end(), [&](const Bin& x) { return before < x.upto; });
    print_bins(static_cast<std::size_t>(bin - bins.begin()));
    if (k > 0 && bin != bins.end()) {
      bin->ms.push_back(ms);
      ++bin->joins;
      bin->fused += j.fused;
      bin->expected += seen_again;
      bin->declined += j.declined + j.pruned;
      bin->refused += j.refused ? 1 : 0;
      bin->query_ms.push_back(query_ms(g));
      bin->windowed += g.graph() != nullptr && g.graph()->last_marginal_windowed() ? 1 : 0;
      bin->rss_mb = peak_rss_mb();
    }
    previous = std::move(world);
  }
  print_bins(bins.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
