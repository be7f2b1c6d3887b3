// host_tools/runs: the counters of an evaluated run, described once (an X-macro, as the option
// table core/options.h is for the settings).
#pragma once

/// A run's counters, each summed over the runs into the report: (member, the reports' JSON key,
/// meaning). RunResult, RunAggregate and ReportRow declare them from this table, RunAggregate::add
/// sums them, RunAggregate::row copies them and rows_json writes them: a new counter is one line
/// here and the line of the scorer (or the link's stream_run) that counts it.
// clang-format off
#define GEOJCBB_RUN_COUNTERS(X) \
  X(fp_clutter, "false_pairs_to_clutter", "of the FP, clutter (other robots, false detections) paired") \
  X(fp_mover, "false_pairs_to_mover", "of the FP of clutter, a simulated mover's observation paired with any map landmark") \
  X(movers_in_map, "movers_in_map", "landmarks made from a simulated mover's observation, still mapped at the end") \
  X(fp_to_duplicate, "false_pairs_to_duplicate", "a landmark's FP with a map landmark made after the first of its identity") \
  X(fp_to_original, "false_pairs_to_original", "a landmark's FP with the first map landmark of another identity") \
  X(fp_in_group, "false_pairs_in_group", "a landmark's FP with another landmark of its group (MRCLAM: a row of tubes)") \
  X(fp_other_group, "false_pairs_other_group", "a landmark's FP elsewhere (another group, or clutter's landmark)") \
  X(dropped_observations, "dropped_observations", "observations over the capacity of a scan") \
  X(not_augmented, "not_augmented", "observations that would have become landmarks, but the map was full") \
  X(evicted, "landmarks_evicted", "landmarks evicted to make room (evict_when_full)") \
  X(budget_hits, "budget_hits", "scans whose JCBB node budget ran out") \
  X(relocalisations, "relocalisations", "poses the relocaliser accepted") \
  X(ambiguous_scans, "ambiguous_scans", "scans whose alignment (relocaliser or loop check) had distinct poses within the margin: nothing committed") \
  X(loop_commits, "loop_closures_committed", "loop closures the closure check committed (loop_check)") \
  X(loop_held_scans, "loop_scans_held", "scans whose disputed pairs it held (a pending closure)") \
  X(windows, "hypothesis_windows", "hypothesis windows opened") \
  X(window_commits, "hypothesis_windows_committed", "windows that committed a leader") \
  X(window_held_scans, "hypothesis_window_scans", "scans a window was open (the opening one included)") \
  X(regrouped, "cluster_first_regrouped", "observations cluster_first paired anew") \
  X(merges, "landmarks_merged", "duplicates merged by evidence (duplicate_merge_d2)") \
  X(movers_caught, "movers_caught", "landmarks that failed the motion test (or the static gate with it) and became movers (motion_false_alarm)")
// clang-format on
#define GEOJCBB_RUN_COUNTER_MEMBER(name, key, doc) int name = 0;
