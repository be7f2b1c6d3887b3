// geojcbb_eval sim: Monte Carlo EKF-SLAM runs over simulated scenarios (default env1 and env2, 20
// runs each, every strategy on the same seeds); the runs and their report are sim_suite.hpp's.
#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "geojcbb_host/eval_cli.hpp"
#include "geojcbb_host/run_cli.hpp"
#include "geojcbb_host/sim_suite.hpp"
#include "geojcbb_host/worlds.hpp"

namespace geojcbb::host {

Subcommand add_sim_command(CLI::App& app) {
  auto o = std::make_shared<SimOptions>();
  auto flags = std::make_shared<CommonFlags>();
  flags->out_dir = "build/results/eval";
  CLI::App* sim =
      app.add_subcommand("sim", "Monte Carlo runs over simulated scenarios: Tables 1 and 2, pose error, NEES, figures");
  sim->add_option("--scenario", o->scenarios,
                  "scenario JSON file(s) (default: env1 and env2 from host_tools/scenarios)");
  sim->add_option("--runs", o->runs, "Monte Carlo runs per scenario and strategy (seeds seed .. seed+runs-1)")
      ->default_val(20)
      ->check(CLI::Range(1, 100000));
  sim->add_option("--seed", o->seed, "first seed")->default_val(1);
  std::string families;
  for (const WorldFamily& f : world_families()) families += std::string("\n    ") + f.name + ": " + f.ranges;
  sim->add_option("--worlds", o->worlds,
                  "generated worlds to run besides the --scenario files (one run each unless --runs is given; "
                  "without --scenario, only the worlds), "
                  "written to OUT_DIR/worlds/FAMILY_SEED.json; with PCJCBB and PCJCBB+RL among the strategies, the "
                  "non-inferiority table (worlds.csv; docs/simulator.md). Families, taken in turn:" +
                      families)
      ->check(CLI::Range(0, 100000));
  sim->add_flag("--batch", o->batch,
                "the batch reference: each run's poses and landmarks solved at once (Ceres) with its own pairings, "
                "its mean position error beside the run's trace's (batch.csv; docs/mapping.md)");
  sim->add_option("--world-seed", o->world_seed, "seed of the first world (world k: seed + k)")->default_val(1000);
  sim->add_option("--family", o->family, "draw every world from this family");
  add_common_flags(*sim, *flags, kAllCommonFlags, "runs.csv, summary.json and the SVG figures", "run");
  sim->add_option("--max-steps", o->run.max_steps,
                  "stop each run after this many control intervals (0: the whole path)")
      ->default_val(0);
  add_run_options(*sim, o->run);
  return {sim, [o, flags, sim]() {
            flags->progress = progress_bar(*flags);
            o->flags = *flags;  // the link's flags stay here: with_device below
            if (o->worlds > 0 && sim->count("--runs") > 0) o->world_runs = o->runs;
            add_generated_worlds(*o);
            if (o->scenarios.empty() && o->worlds == 0) {
              o->scenarios = {std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json",
                              std::string(GEOJCBB_SCENARIO_DIR) + "/env2.json"};
              o->world_family.assign(o->scenarios.size(), "");
            }
            return with_device(flags->link, flags->oracle, false,
                               [&](const RunInputsFn& runner, const std::string& info) {
                                 o->runner = runner;
                                 o->device_info = info;
                                 return run_sim(*o);
                               });
          }};
}

}  // namespace geojcbb::host
