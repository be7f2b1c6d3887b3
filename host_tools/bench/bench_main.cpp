// The association benchmark: `--suite mrpt` (ours side by side with MRPT), `--suite strategies`
// (the six strategies against plain JCBB), or both (default).
#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "bench_common.hpp"
#include "geojcbb_host/guarded_main.hpp"

namespace {

int run(int argc, char** argv) {
  using geojcbb::bench::BenchOptions;
  CLI::App app{"geojcbb association benchmark (timing is measured, never asserted)"};
  BenchOptions o;
  std::string suite = "all";
  app.add_option("--suite", suite, "mrpt | strategies | all")->check(CLI::IsMember({"mrpt", "strategies", "all"}));
  app.add_option("--scenes", o.scenes, "scenes per cell")->check(CLI::PositiveNumber);
  app.add_option("--seed", o.seed, "first scene seed (scene k of a cell uses seed + k)");
  app.add_option("--confidence", o.confidence, "chi-square level of the individual and joint tests")
      ->check(CLI::Range(0.5, 0.9999));
  app.add_flag("--quick", o.quick, "only the smallest cells (a smoke run)");
  app.add_option("--out-dir", o.out_dir, "write mrpt.csv and strategies.csv here");
  app.add_option("--mrpt-kdtree", o.mrpt_kdtree,
                 "MRPT's kd-tree prefilter of individual compatibility (its default: on)");
  app.add_option("--mrpt-cell-cap-s", o.mrpt_cell_cap_s,
                 "stop calling MRPT-JCBB in a cell once its calls there have taken this many seconds");
  app.add_option("--dense-m", o.dense_m, "observations per scan in the mrpt suite's dense-map cells");
  app.add_flag("--dense-only", o.dense_only, "mrpt suite: only the dense-map cells");
  app.add_option("--node-budget", o.node_budget, "strategies suite: JCBB nodes per scan (0: the capacity's maximum)")
      ->check(CLI::NonNegativeNumber);
  CLI11_PARSE(app, argc, argv);
  if (!o.out_dir.empty()) std::filesystem::create_directories(o.out_dir);
  std::printf("# geojcbb association benchmark\n\n");
  int rc = 0;
  if (suite != "strategies") rc = geojcbb::bench::run_mrpt_suite(o);
  if (rc == 0 && suite != "mrpt") {
    if (suite == "all") std::printf("\n");
    rc = geojcbb::bench::run_strategy_suite(o);
  }
  return rc;
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
