// host_tools/report: the robust preset against its base on generated worlds (the
// non-inferiority table of docs/results/worlds.md). Per world, the robust preset (PCJCBB+RL) is *worse* than its base
// (PCJCBB) when its pose error passes the base's by more than max(0.5 m, 20 %) or its F1 is below
// the base's by more than 0.005; the base *diverged and the robust preset recovered* when the base's
// pose error is over 3 m and the robust preset's within max(0.5 m, 20 %) of TRUTH's (when TRUTH ran)
// or under 1 m. Pose error: the norm of the run's mean |x| and |y| errors.
#pragma once

#include <string>
#include <vector>

namespace geojcbb::host {

struct WorldOutcome {
  std::string family, file;
  double err_base = 0, err_robust = 0;  ///< pose error [m]
  double f1_base = 0, f1_robust = 0;
  double anees_base = 0, anees_robust = 0;
  double err_truth = -1;  ///< TRUTH's pose error [m]; < 0: TRUTH did not run
};

bool robust_worse(const WorldOutcome& w);
bool robust_recovered(const WorldOutcome& w);

struct FamilyRow {
  std::string family;  ///< "total" for the last row
  int worlds = 0, worse = 0, recovered = 0;
  double err_base = 0, err_robust = 0, f1_base = 0, f1_robust = 0, anees_base = 0, anees_robust = 0;  ///< medians
};

/// One row per family in first-seen order, then the total.
std::vector<FamilyRow> non_inferiority(const std::vector<WorldOutcome>& worlds);

/// The table as markdown, with the definitions above it and the worse worlds' files below it.
std::string non_inferiority_markdown(const std::vector<WorldOutcome>& worlds);

/// One generated world's result for one strategy (every strategy, beside the robust preset's table).
struct WorldStrategyOutcome {
  std::string family, strategy;
  double err = 0;                    ///< pose error [m], the mean over the world's runs
  double f1 = 0;                     ///< over the world's runs' pairs
  int tp = 0, fp = 0, fn = 0;        ///< sums over the world's runs
  int fp_clutter = 0, fp_mover = 0;  ///< of the FP: clutter paired; of those, a mover's observation
  int movers_in_map = 0;             ///< landmarks made from movers still mapped at the end
};

/// Per family and strategy (both in first-seen order), then per strategy over every family: worlds,
/// median and pooled F1, median pose error, and the sums of FP, FP of clutter, FP of movers and
/// movers in the map, as markdown.
std::string strategies_markdown(const std::vector<WorldStrategyOutcome>& worlds);

}  // namespace geojcbb::host
