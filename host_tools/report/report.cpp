#include "geojcbb_host/report.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "geojcbb/core/chi_square.hpp"

namespace geojcbb::host {

void RunAggregate::add(const RunResult& r, double run_s_, double kidnap_t_s) {
  const SubmapStats& m = r.submaps;
  submaps.maps += m.maps;
  submaps.offered += m.offered;
  submaps.fused += m.fused;
  submaps.declined += m.declined;
  submaps.removed += m.removed;
  submaps.refused += m.refused;
  submaps.wrong += m.wrong;
  submaps.wrong_in_group += m.wrong_in_group;
  submaps.seeded += m.seeded;
  submaps.joins.insert(submaps.joins.end(), m.joins.begin(), m.joins.end());
  submaps.frames += m.frames;
  submaps.requests += m.requests;
  submaps.handover_s.insert(submaps.handover_s.end(), m.handover_s.begin(), m.handover_s.end());
  for (std::size_t k = 1; k < m.joins.size() && m.joins[0].worst_step_s > 0; ++k) {
    worst_step_ratio = std::max(worst_step_ratio, m.joins[k].worst_step_s / m.joins[0].worst_step_s);
  }
  score.add(r.score);
  group_score.add(r.group_score);
  for (const StepRecord& k : r.steps) scan_ms.push_back(1e3 * k.assoc_s);
  if (kidnap_t_s > 0) {
    const KidnapScore k = kidnap_score(r, kidnap_t_s);
    ++reloc_runs;
    reloc_found3 += k.found_at >= 1 && k.found_at <= 3;
    reloc_false += k.false_relocalisation;
    reloc_error_m += k.pose_error_after_m;
    reloc_anees_before += k.anees_before;
    reloc_anees_after += k.anees_after;
  }
  ++runs;
  scans += r.scans;
  observations += r.observations;
#define GEOJCBB_RUN_COUNTER_SUM(name, key, doc) name += r.name;
  GEOJCBB_RUN_COUNTERS(GEOJCBB_RUN_COUNTER_SUM)
#undef GEOJCBB_RUN_COUNTER_SUM
  runs_over_5_fp += r.score.fp > 5;
  full_runs += r.not_augmented > 0 || r.evicted > 0;
  landmarks += r.landmarks;
  spurious_in_map += r.spurious_in_map;
  removed_true += r.removed_true_landmarks;
  {
    std::map<int, int> per_truth;
    for (const MapLandmark& l : r.map)
      if (l.truth >= 0 && per_truth[l.truth]++ > 0) ++duplicates;
  }
  assoc_s += r.association_s;
  run_s += run_s_;
  abs_x += r.mean_abs_x_m;
  abs_y += r.mean_abs_y_m;
  double nees = 0;
  for (const StepRecord& k : r.steps) nees += k.pose_nees;
  anees_sum += r.steps.empty() ? 0 : nees / static_cast<double>(r.steps.size());
  if (nees_sum.size() < r.steps.size()) {
    nees_sum.resize(r.steps.size(), 0.0);
    ex_sum.resize(r.steps.size(), 0.0);
    ey_sum.resize(r.steps.size(), 0.0);
    t.resize(r.steps.size(), 0.0);
  }
  for (std::size_t k = 0; k < r.steps.size(); ++k) {
    const StepRecord& s = r.steps[k];
    nees_sum[k] += s.pose_nees;
    ex_sum[k] += std::abs(s.estimate.x - s.truth.x);
    ey_sum[k] += std::abs(s.estimate.y - s.truth.y);
    t[k] = s.t_s;
  }
}

void RunAggregate::fail(const std::string& e) {
  ++failed;
  error = e;
}

ReportRow RunAggregate::row(const std::string& name, bool monte_carlo, bool map_known) const {
  ReportRow row;
  row.name = name;
  row.runs = runs;
  row.failed = failed;
  row.error = error;
  row.score = score;
  row.scans = scans;
  row.assoc_s = assoc_s;
  row.run_s = run_s;
#define GEOJCBB_RUN_COUNTER_COPY(name, key, doc) row.name = name;
  GEOJCBB_RUN_COUNTERS(GEOJCBB_RUN_COUNTER_COPY)
#undef GEOJCBB_RUN_COUNTER_COPY
  if (!scan_ms.empty()) {
    std::vector<double> ms = scan_ms;
    std::sort(ms.begin(), ms.end());
    row.ms_median = ms[ms.size() / 2];
    row.ms_p90 = ms[std::min(ms.size() - 1, ms.size() * 9 / 10)];
    row.ms_max = ms.back();
  }
  row.reloc_runs = reloc_runs;
  row.reloc_found3 = reloc_found3;
  row.reloc_false = reloc_false;
  row.runs_over_5_fp = runs_over_5_fp;
  row.full_runs = full_runs;
  if (reloc_runs > 0) {
    row.reloc_error_m = reloc_error_m / reloc_runs;
    row.reloc_anees_before = reloc_anees_before / reloc_runs;
    row.reloc_anees_after = reloc_anees_after / reloc_runs;
  }
  if (runs == 0) return row;
  row.abs_x = abs_x / runs;
  row.abs_y = abs_y / runs;
  row.landmarks = double(landmarks) / runs;
  row.spurious_in_map = map_known ? double(spurious_in_map) / runs : NAN;
  row.duplicates = map_known ? double(duplicates) / runs : NAN;
  if (!monte_carlo) {
    row.anees = anees_sum / runs;
    return row;
  }
  // NEES: the mean over runs at each scan against its 95 % bounds for 3 x runs dof, and the
  // average over the run.
  if (!nees_sum.empty()) {
    double sum = 0;
    int inside = 0;
    double l = 0, h = 0;
    const bool b = chi2_inv(0.025, 3 * runs, l) == Status::kOk && chi2_inv(0.975, 3 * runs, h) == Status::kOk;
    for (double v : nees_sum) {
      const double m = v / runs;
      sum += m;
      inside += b && m >= l / runs && m <= h / runs;
    }
    const double steps = static_cast<double>(nees_sum.size());
    row.anees = sum / steps;
    row.nees_inside = double(inside) / steps;
    const long dof = 3L * runs * static_cast<long>(nees_sum.size());
    row.anees_lo = chi2_quantile_wh(0.025, dof) / (double(runs) * steps);
    row.anees_hi = chi2_quantile_wh(0.975, dof) / (double(runs) * steps);
  }
  return row;
}

ReportRow RunAggregate::group_row(const std::string& name) const {
  ReportRow row;
  row.name = name;
  row.runs = runs;
  row.score = group_score;
  return row;
}

const std::vector<std::string>& run_csv_columns() {
  static const std::vector<std::string> c{"scans",
                                          "observations",
                                          "tp",
                                          "tn",
                                          "fp",
                                          "fn",
                                          "precision",
                                          "recall",
                                          "f1",
                                          "association_s",
                                          "run_s",
                                          "mean_abs_x_m",
                                          "mean_abs_y_m",
                                          "landmarks",
                                          "spurious_in_map",
                                          "budget_hits",
                                          "relocalised_at_scan",
                                          "anees",
                                          "duplicates",
                                          "fp_clutter",
                                          "group_f1",
                                          "ambiguous_scans",
                                          "fp_mover",
                                          "movers_in_map",
                                          "movers_caught"};
  return c;
}

std::string run_csv(const RunResult& r, double run_s, const std::vector<std::string>& columns, double kidnap_t_s) {
  std::ostringstream o;
  bool first = true;
  for (const std::string& c : columns) {
    if (!first) o << ',';
    first = false;
    if (c == "scans")
      o << r.scans;
    else if (c == "observations")
      o << r.observations;
    else if (c == "tp")
      o << r.score.tp;
    else if (c == "tn")
      o << r.score.tn;
    else if (c == "fp")
      o << r.score.fp;
    else if (c == "fn")
      o << r.score.fn;
    else if (c == "precision")
      o << r.score.precision();
    else if (c == "recall")
      o << r.score.recall();
    else if (c == "f1")
      o << r.score.f1();
    else if (c == "association_s")
      o << r.association_s;
    else if (c == "run_s")
      o << run_s;
    else if (c == "mean_abs_x_m")
      o << r.mean_abs_x_m;
    else if (c == "mean_abs_y_m")
      o << r.mean_abs_y_m;
    else if (c == "landmarks")
      o << r.landmarks;
    else if (c == "spurious_in_map")
      o << r.spurious_in_map;
    else if (c == "budget_hits")
      o << r.budget_hits;
    else if (c == "ambiguous_scans")
      o << r.ambiguous_scans;
    else if (c == "relocalised_at_scan")
      o << (kidnap_t_s > 0 ? kidnap_score(r, kidnap_t_s).found_at : -1);
    else if (c == "anees") {
      double nees = 0;
      for (const StepRecord& k : r.steps) nees += k.pose_nees;
      o << (r.steps.empty() ? 0.0 : nees / static_cast<double>(r.steps.size()));
    } else if (c == "duplicates") {
      std::map<int, int> per_truth;
      int dup = 0;
      for (const MapLandmark& l : r.map)
        if (l.truth >= 0 && per_truth[l.truth]++ > 0) ++dup;
      o << dup;
    } else if (c == "fp_clutter")
      o << r.fp_clutter;
    else if (c == "fp_mover")
      o << r.fp_mover;
    else if (c == "movers_in_map")
      o << r.movers_in_map;
    else if (c == "movers_caught")
      o << r.movers_caught;
    else if (c == "group_f1")
      o << r.group_score.f1();
    else
      throw std::invalid_argument("run_csv: unknown column '" + c + "'");
  }
  return o.str();
}

void print_summary(const std::vector<ReportRow>& rows, const std::vector<ReportRow>& group_rows, std::FILE* f,
                   const char* per) {
  std::fprintf(f,
               "Summary per strategy (landmarks, duplicates and spurious: in the final map, mean per %s; FP of "
               "clutter: other robots or false detections paired)\n  %-9s %7s %9s %7s %10s %10s %9s %13s %8s %9s\n",
               per, "strategy", "F1", "precision", "recall", "landmarks", "duplicates", "spurious", "FP of clutter",
               "ANEES", "group F1");
  for (std::size_t s = 0; s < rows.size(); ++s) {
    const ReportRow& w = rows[s];
    if (w.runs == 0) {  // nothing to score: never a perfect score
      std::fprintf(f, "  %-9s   all %d runs failed: %s\n", w.name.c_str(), w.failed, w.error.c_str());
      continue;
    }
    std::fprintf(f, "  %-9s %7.4f %9.4f %7.4f %10.1f %10.1f %9.1f %13d %8.2f %9.4f\n", w.name.c_str(), w.score.f1(),
                 w.score.precision(), w.score.recall(), w.landmarks, w.duplicates, w.spurious_in_map, w.fp_clutter,
                 w.anees, group_rows[s].score.f1());
  }
}

svg::Panel path_map_panel(const std::string& title, const RunResult& r, const std::vector<Eigen::Vector2d>& landmarks) {
  svg::Panel p;
  p.title = title;
  p.xlabel = "x [m]";
  p.ylabel = "y [m]";
  p.equal_aspect = true;
  svg::Series truth{"true path", {}, {}, svg::Style::kLine, "#000000"};
  svg::Series est{"estimated path", {}, {}, svg::Style::kDashed, "#D55E00"};
  for (const StepRecord& s : r.steps) {
    truth.x.push_back(s.truth.x);
    truth.y.push_back(s.truth.y);
    est.x.push_back(s.estimate.x);
    est.y.push_back(s.estimate.y);
  }
  svg::Series tl{"true landmarks", {}, {}, svg::Style::kMarkersCross, "#0072B2"};
  for (const Eigen::Vector2d& l : landmarks) {
    tl.x.push_back(l.x());
    tl.y.push_back(l.y());
  }
  svg::Series el{"estimated landmarks", {}, {}, svg::Style::kMarkersCircle, "#009E73"};
  svg::Series sl{"spurious landmarks", {}, {}, svg::Style::kMarkersDot, "#CC79A7"};
  for (const MapLandmark& m : r.map) {
    (m.truth >= 0 ? el : sl).x.push_back(m.x);
    (m.truth >= 0 ? el : sl).y.push_back(m.y);
  }
  p.series = {tl, truth, est, el, sl};
  return p;
}

void print_submaps(const std::vector<Method>& strategies, const std::vector<RunAggregate>& agg, std::FILE* f) {
  bool any = false;
  for (const RunAggregate& a : agg) any = any || a.submaps.maps > 0;
  if (!any) return;
  std::fprintf(f,
               "\nLocal maps joined on the host (docs/submaps.md; summed over the runs)\n"
               "| strategy | local maps | landmarks per map (max) | offered | fused | declined | joins refused | "
               "wrong joins (in a group) | global map | slowest step / first map's | seeds taken |\n"
               "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (std::size_t k = 0; k < agg.size() && k < strategies.size(); ++k) {
    const SubmapStats& m = agg[k].submaps;
    if (m.maps == 0) continue;
    int most = 0;
    for (const JoinRecord& j : m.joins) most = std::max(most, j.landmarks);
    const double global = agg[k].runs > 0 ? double(agg[k].landmarks) / agg[k].runs : 0;  // per run
    char ratio[32] = "-";  // not timed (through a device: geojcbb_qemu --budget counts instructions)
    if (agg[k].worst_step_ratio > 0) std::snprintf(ratio, sizeof ratio, "%.2f", agg[k].worst_step_ratio);
    std::fprintf(f, "| %s | %d | %d | %d | %d | %d | %d | %d (%d) | %.0f | %s | %d |\n", strategies[k].name().c_str(),
                 m.maps, most, m.offered, m.fused, m.declined, m.refused, m.wrong, m.wrong_in_group, global, ratio,
                 m.seeded);
  }
  for (std::size_t k = 0; k < agg.size() && k < strategies.size(); ++k) {
    const SubmapStats& m = agg[k].submaps;
    if (m.handover_s.empty()) continue;
    double sum = 0, most = 0;
    for (double t : m.handover_s) {
      sum += t;
      most = std::max(most, t);
    }
    std::fprintf(f,
                 "%s through the device: %zu hand-overs, %d SUBMAP/SUBMAP_COV frames, %d asked for again; pause "
                 "(last POSE to SUBMAP_ACK's ACK, join included) mean %.3f s, max %.3f s\n",
                 strategies[k].name().c_str(), m.handover_s.size(), m.frames, m.requests,
                 sum / static_cast<double>(m.handover_s.size()), most);
  }
}

}  // namespace geojcbb::host
