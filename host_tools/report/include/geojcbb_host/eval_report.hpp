// host_tools/report: the evaluation's report pieces shared by the simulation and
// the MRCLAM replay: one row per strategy (sums over runs), the papers' Table 1
// (time) and Table 2 (accuracy) as text, the same rows as JSON, a progress bar
// on stderr, and a chi-square quantile for large dof.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "geojcbb_host/run_counters.hpp"
#include "geojcbb_host/scene.hpp"

namespace geojcbb::host {

struct ReportRow {
  std::string name;
  int runs = 0, failed = 0;
  std::string error;  ///< of the last failed run
  Score score;
  int scans = 0;
  GEOJCBB_RUN_COUNTERS(GEOJCBB_RUN_COUNTER_MEMBER)  ///< sums over the runs
  double assoc_s = 0, run_s = 0;                    ///< sums over the runs
  double abs_x = NAN,
         abs_y = NAN;                             ///< mean absolute pose error [m], mean over runs
  double landmarks = NAN, spurious_in_map = NAN;  ///< at the end, mean over runs
  double anees = NAN, anees_lo = NAN,
         anees_hi = NAN;     ///< time-averaged NEES and its 95 % bounds
  double nees_inside = NAN;  ///< fraction of scans whose run-averaged NEES is
                             ///< inside its 95 % bounds
  double duplicates = NAN;   ///< map landmarks beyond one per true landmark, at the end, mean over runs
  double ms_median = NAN, ms_p90 = NAN, ms_max = NAN;  ///< per-scan association time over every scan [ms]
  int reloc_runs = 0, reloc_found3 = 0;                ///< kidnap scenes: runs, and runs relocalised within 3 scans
  int reloc_false = 0;                                 ///< runs with a false relocalisation
  int runs_over_5_fp = 0;                              ///< runs with more than 5 false pairs
  int full_runs = 0;                                   ///< runs whose map filled
  double reloc_error_m = NAN;                          ///< mean position error after the kidnap [m]
  double reloc_anees_before = NAN, reloc_anees_after = NAN;  ///< mean NEES before and after the kidnap
};

inline double accuracy(const Score& s) {
  const int n = s.tp + s.tn + s.fp + s.fn;
  return n == 0 ? 1.0 : double(s.tp + s.tn) / n;
}

/// The p-quantile of chi-square with k dof by Wilson-Hilferty (relative error <
/// 1e-4 from 200 dof up, checked against chi2_inv in the tests); for the
/// time-averaged NEES, whose dof (3 x runs x scans) is far beyond chi2_inv's
/// range.
inline double chi2_quantile_wh(double p, long k) {
  // Normal quantile by Acklam's rational approximation (|error| < 1.2e-9).
  const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                      1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02, 6.680131188771972e+01,
                      -1.328068155288572e+01};
  const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                      -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00, 3.754408661907416e+00};
  double z;
  if (p < 0.02425) {
    const double q = std::sqrt(-2 * std::log(p));
    z = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  } else if (p > 1 - 0.02425) {
    const double q = std::sqrt(-2 * std::log(1 - p));
    z = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  } else {
    const double q = p - 0.5, r = q * q;
    z = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
  }
  const double h = 2.0 / (9.0 * static_cast<double>(k));
  return static_cast<double>(k) * std::pow(1 - h + z * std::sqrt(h), 3);
}

inline std::string csv_escape(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char ch : s) o += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return o + "\"";
}

inline void print_accuracy(const std::vector<ReportRow>& rows, std::FILE* f) {
  std::fprintf(f, "  %-8s %8s %7s %6s %6s %10s %8s %8s %9s\n", "strategy", "TP", "TN", "FP", "FN", "precision",
               "recall", "F1", "accuracy");
  for (const ReportRow& r : rows) {
    if (r.runs == 0) continue;
    const Score& s = r.score;
    std::fprintf(f, "  %-8s %8d %7d %6d %6d %10.4f %8.4f %8.4f %9.4f\n", r.name.c_str(), s.tp, s.tn, s.fp, s.fn,
                 s.precision(), s.recall(), s.f1(), accuracy(s));
  }
}

/// Table 1, relocalisation (kidnap scenes), Table 2 (scores = false: not printed, for logs without
/// labels) and the pose and map table.
inline void print_tables(const std::vector<ReportRow>& rows, std::FILE* f, bool scores = true) {
  std::fprintf(f, "Table 1: association time\n");
  std::fprintf(f, "  %-9s %6s %16s %16s %12s %12s %28s\n", "strategy", "runs", "per scan [ms]", "per run [s]",
               "run [s]", "budget hits", "scan [ms] median/p90/max");
  for (const ReportRow& r : rows) {
    if (r.runs == 0) {
      std::fprintf(f, "  %-8s %6d   all runs failed: %s\n", r.name.c_str(), r.failed, r.error.c_str());
      continue;
    }
    std::fprintf(f, "  %-9s %6d %16.4f %16.4f %12.4f %12d %10.4f/%8.4f/%8.3f\n", r.name.c_str(), r.runs,
                 r.scans ? 1e3 * r.assoc_s / r.scans : 0.0, r.assoc_s / r.runs, r.run_s / r.runs, r.budget_hits,
                 r.ms_median, r.ms_p90, r.ms_max);
  }
  bool kidnap = false;
  for (const ReportRow& r : rows) kidnap = kidnap || r.reloc_runs > 0;
  if (kidnap) {
    std::fprintf(f,
                 "Relocalisation: runs found within 3 scans of the kidnap (from that scan on, 10 scans with the pose "
                 "within 1 m, 5 deg and 3 sigma, and no false pairing); runs that declared themselves found with a "
                 "wrong pose; means after the kidnap\n");
    std::fprintf(f, "  %-9s %19s %12s %14s %12s %12s\n", "strategy", "found in 3 scans", "false reloc", "pose err [m]",
                 "ANEES before", "ANEES after");
    for (const ReportRow& r : rows) {
      if (r.reloc_runs > 0)
        std::fprintf(f, "  %-9s %4d / %4d (%5.1f%%) %12d %14.3f %12.2f %12.2f\n", r.name.c_str(), r.reloc_found3,
                     r.reloc_runs, 100.0 * r.reloc_found3 / r.reloc_runs, r.reloc_false, r.reloc_error_m,
                     r.reloc_anees_before, r.reloc_anees_after);
    }
  }
  if (scores) {
    std::fprintf(f, "Table 2: association accuracy (sums over the runs)\n");
    print_accuracy(rows, f);
    std::fprintf(
        f,
        "False pairs: runs with more than 5; of a landmark's observation paired with another landmark's map "
        "landmark, that map landmark a duplicate (made after the first of its identity) or the original; "
        "clutter paired, of which a simulated mover's observations, and the landmarks made from movers still mapped "
        "at the end; landmarks caught as movers (the world model's motion test and, with it, the static gate); with --loop-check, closures committed and scans held pending; with --duplicate-merge-d2, "
        "duplicates merged; a landmark's false pairs by place: another landmark of its group (MRCLAM: within a row of "
        "tubes) or elsewhere; with --hypotheses, windows opened, committed and scans open; with --cluster-first, observations "
        "paired anew\n");
    std::fprintf(f, "  %-9s %10s %12s %12s %10s %7s %7s %7s %9s %6s %7s %9s %10s %8s %9s %7s %9s\n", "strategy",
                 "runs > 5", "duplicate", "original", "clutter", "mover", "in map", "caught", "closures", "held",
                 "merged", "in group", "elsewhere", "windows", "committed", "open", "regrouped");
    for (const ReportRow& r : rows) {
      if (r.runs > 0)
        std::fprintf(f, "  %-9s %10d %12d %12d %10d %7d %7d %7d %9d %6d %7d %9d %10d %8d %9d %7d %9d\n", r.name.c_str(),
                     r.runs_over_5_fp, r.fp_to_duplicate, r.fp_to_original, r.fp_clutter, r.fp_mover, r.movers_in_map,
                     r.movers_caught, r.loop_commits, r.loop_held_scans, r.merges, r.fp_in_group, r.fp_other_group,
                     r.windows, r.window_commits, r.window_held_scans, r.regrouped);
    }
  }
  std::fprintf(f, "Pose and map (means over the runs)\n");
  std::fprintf(f, "  %-8s %10s %10s %10s %18s %12s %10s %10s\n", "strategy", "|x err| m", "|y err| m", "ANEES",
               "ANEES 95% bounds", "scans in b.", "landmarks", "spurious");
  for (const ReportRow& r : rows) {
    if (r.runs == 0) continue;
    char bounds[32] = "               -", inside[16] = "          -";
    if (std::isfinite(r.anees_lo) && std::isfinite(r.anees_hi)) {
      std::snprintf(bounds, sizeof bounds, "  [%5.3f, %5.3f]", r.anees_lo, r.anees_hi);
    }
    if (std::isfinite(r.nees_inside)) std::snprintf(inside, sizeof inside, "%10.1f%%", 100 * r.nees_inside);
    char spurious[24] = "         -";  // a device does not report its map
    if (std::isfinite(r.spurious_in_map)) std::snprintf(spurious, sizeof spurious, "%10.1f", r.spurious_in_map);
    std::fprintf(f, "  %-8s %10.4f %10.4f %10.3f %18s %12s %10.1f %s\n", r.name.c_str(), r.abs_x, r.abs_y, r.anees,
                 bounds, inside, r.landmarks, spurious);
  }
  for (const ReportRow& r : rows) {
    if (r.failed > 0) std::fprintf(f, "  %s: %d runs failed: %s\n", r.name.c_str(), r.failed, r.error.c_str());
    if (r.full_runs > 0)
      std::fprintf(
          f, "  %s: the map filled in %d runs; %d observations were not added as landmarks, %d landmarks evicted\n",
          r.name.c_str(), r.full_runs, r.not_augmented, r.evicted);
  }
}

inline nlohmann::json rows_json(const std::vector<ReportRow>& rows) {
  nlohmann::json a = nlohmann::json::array();
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  for (const ReportRow& r : rows) {
    const Score& s = r.score;
    a.push_back({{"strategy", r.name},
                 {"runs", r.runs},
                 {"failed", r.failed},
                 {"tp", s.tp},
                 {"tn", s.tn},
                 {"fp", s.fp},
                 {"fn", s.fn},
                 // No run scored: no score (null), never a perfect one.
                 {"precision", r.runs > 0 ? num(s.precision()) : nlohmann::json(nullptr)},
                 {"recall", r.runs > 0 ? num(s.recall()) : nlohmann::json(nullptr)},
                 {"f1", r.runs > 0 ? num(s.f1()) : nlohmann::json(nullptr)},
                 {"accuracy", r.runs > 0 ? num(accuracy(s)) : nlohmann::json(nullptr)},
                 {"scans", r.scans},
                 {"association_s_total", r.assoc_s},
                 {"association_ms_per_scan", r.scans ? 1e3 * r.assoc_s / r.scans : 0.0},
                 {"run_s_mean", r.runs ? r.run_s / r.runs : 0.0},
                 {"mean_abs_x_m", num(r.abs_x)},
                 {"mean_abs_y_m", num(r.abs_y)},
                 {"anees", num(r.anees)},
                 {"anees_lo", num(r.anees_lo)},
                 {"anees_hi", num(r.anees_hi)},
                 {"nees_inside", num(r.nees_inside)},
                 {"landmarks", num(r.landmarks)},
                 {"spurious_in_map", num(r.spurious_in_map)},
                 {"association_ms_median", num(r.ms_median)},
                 {"association_ms_p90", num(r.ms_p90)},
                 {"association_ms_max", num(r.ms_max)},
                 {"relocalisation_runs", r.reloc_runs},
                 {"relocalised_within_3_scans", r.reloc_found3},
                 {"false_relocalisations", r.reloc_false},
                 {"runs_over_5_false_pairs", r.runs_over_5_fp},
                 {"runs_map_full", r.full_runs},
                 {"pose_error_after_kidnap_m", num(r.reloc_error_m)},
                 {"anees_before_kidnap", num(r.reloc_anees_before)},
                 {"anees_after_kidnap", num(r.reloc_anees_after)}});
    nlohmann::json& row = a.back();
#define GEOJCBB_RUN_COUNTER_JSON(name, key, doc) row[key] = r.name;
    GEOJCBB_RUN_COUNTERS(GEOJCBB_RUN_COUNTER_JSON)
#undef GEOJCBB_RUN_COUNTER_JSON
  }
  return a;
}

/// A one-line progress bar on stderr, redrawn in place; silent when disabled.
class ProgressBar {
 public:
  ProgressBar(std::size_t total, bool enabled) : total_(total), on_(enabled), t0_(std::chrono::steady_clock::now()) {}
  void show(std::size_t done) {
    if (!on_ || total_ == 0) return;
    const int width = 40, fill = static_cast<int>(width * done / total_);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    std::fprintf(stderr, "\r[%.*s%*s] %zu/%zu runs  %.1f s", fill, "########################################",
                 width - fill, "", done, total_, s);
    std::fflush(stderr);
  }
  void finish() {
    if (!on_) return;
    show(total_);
    std::fprintf(stderr, "\n");
  }

 private:
  std::size_t total_;
  bool on_;
  std::chrono::steady_clock::time_point t0_;
};

/// Runs job(0) .. job(count - 1) on `threads` threads (0: one per core), with a
/// progress bar. job must be safe to call concurrently for different indices.
/// Returns the wall time [s].
template <class Job>
double run_parallel(std::size_t count, int threads, bool progress, Job&& job) {
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::atomic<std::size_t> next{0}, done{0};
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads));
  for (int k = 0; k < threads; ++k) {
    pool.emplace_back([&] {
      for (std::size_t j = next++; j < count; j = next++) {
        job(j);
        ++done;
      }
    });
  }
  ProgressBar bar(count, progress);
  while (done.load() < count) {
    bar.show(done.load());
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  for (std::thread& t : pool) t.join();
  bar.finish();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace geojcbb::host
