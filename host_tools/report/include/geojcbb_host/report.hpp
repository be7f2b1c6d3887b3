// host_tools/report: the one reporting path of the simulation, the MRCLAM replay and the own-log
// replay. A RunAggregate sums one row's runs (a strategy on a scenario, a dataset or a log) and
// gives its ReportRow (eval_report.hpp prints the tables and the JSON rows); run_csv writes a
// run's CSV fields by column name; print_summary prints the per-strategy summary (F1, map, ANEES,
// group F1); path_map_panel draws a run's true and estimated path and map for the SVG figures.
#pragma once

#include <Eigen/Core>
#include <cstdio>
#include <string>
#include <vector>

#include "geojcbb_host/eval_report.hpp"
#include "geojcbb_host/slam_run.hpp"
#include "geojcbb_host/svg_plot.hpp"

namespace geojcbb::host {

struct RunAggregate {
  Score score, group_score;
  int runs = 0, failed = 0, scans = 0, observations = 0;
  GEOJCBB_RUN_COUNTERS(GEOJCBB_RUN_COUNTER_MEMBER)  ///< RunResult's, summed
  int landmarks = 0, spurious_in_map = 0, duplicates = 0, removed_true = 0;
  double assoc_s = 0, run_s = 0, abs_x = 0, abs_y = 0;
  double anees_sum = 0;                             ///< sum over runs of each run's time-averaged NEES
  std::vector<double> nees_sum, ex_sum, ey_sum, t;  ///< per scan, over the runs
  std::vector<double> scan_ms;                      ///< every scan's association time [ms]
  int reloc_runs = 0, reloc_found3 = 0;             ///< kidnap scenes: runs, and found within 3 scans
  int reloc_false = 0;                              ///< runs with a false relocalisation
  int runs_over_5_fp = 0;                           ///< runs with more than 5 false pairs
  int full_runs = 0;                                ///< runs whose map filled
  double reloc_error_m = 0, reloc_anees_before = 0, reloc_anees_after = 0;  ///< sums over the runs
  SubmapStats submaps;          ///< summed over the runs (the per-map vectors concatenated)
  double worst_step_ratio = 0;  ///< the largest, over runs and local maps, of a map's slowest step / the first map's
  RunResult first;              ///< the run the path figure shows (set by the caller)
  bool have_first = false;
  std::string error;  ///< of the last failed run

  /// Adds a run; kidnap_t_s > 0: a kidnap scene (relocalisation counted).
  void add(const RunResult& r, double run_s, double kidnap_t_s = 0);
  void fail(const std::string& e);
  /// The row. monte_carlo: the simulation's ANEES (the mean over runs at each scan, averaged over the
  /// scans, with 95 % bounds for 3 x runs dof; runs of equal length); otherwise the mean over runs of
  /// each run's time-averaged NEES, no bounds. map_known: spurious landmarks and duplicates are
  /// known (not over a device link, which does not report its map).
  ReportRow row(const std::string& name, bool monte_carlo, bool map_known) const;
  /// The same row at landmark-group level (group_score as the score).
  ReportRow group_row(const std::string& name) const;
};

/// The CSV columns a run can give (run_csv): scans, observations, tp, tn, fp, fn, precision,
/// recall, f1, association_s, run_s, mean_abs_x_m, mean_abs_y_m, landmarks, spurious_in_map,
/// budget_hits, relocalised_at_scan, anees, duplicates, fp_clutter, group_f1, ambiguous_scans,
/// fp_mover, movers_in_map.
const std::vector<std::string>& run_csv_columns();
/// A run's fields for `columns` (names from run_csv_columns), comma separated, numbers as an
/// ostream writes them. kidnap_t_s <= 0: relocalised_at_scan is -1. Throws on an unknown column.
std::string run_csv(const RunResult& r, double run_s, const std::vector<std::string>& columns, double kidnap_t_s = 0);

/// Per strategy: F1, precision, recall, landmarks, duplicates, spurious, FP of clutter, ANEES and
/// group F1 (rows and group_rows in the same order); `per` names what the means are over ("robot").
void print_summary(const std::vector<ReportRow>& rows, const std::vector<ReportRow>& group_rows, std::FILE* f,
                   const char* per = "robot");

/// The submaps table (RunOptions::submaps): per strategy the local maps, their landmarks, the joins'
/// pairs fused, declined and refused, the wrong ones (labelled data), the global map's landmarks and
/// the slowest step of a local map against the first map's. Prints nothing when no row joined maps.
void print_submaps(const std::vector<Method>& strategies, const std::vector<RunAggregate>& agg, std::FILE* f);

/// One panel of the path figure: the true path (where known), the estimated path, the true
/// landmarks, and the final map's landmarks (made from a landmark, or spurious).
svg::Panel path_map_panel(const std::string& title, const RunResult& r, const std::vector<Eigen::Vector2d>& landmarks);

}  // namespace geojcbb::host
