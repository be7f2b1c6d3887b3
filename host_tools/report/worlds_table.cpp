#include "geojcbb_host/worlds_table.hpp"

#include <algorithm>
#include <cstdio>

namespace geojcbb::host {

namespace {
double tolerance(double base_m) { return std::max(0.5, 0.2 * base_m); }

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

FamilyRow row_of(const std::string& name, const std::vector<const WorldOutcome*>& ws) {
  FamilyRow r;
  r.family = name;
  r.worlds = static_cast<int>(ws.size());
  std::vector<double> eb, er, fb, fr, ab, ar;
  for (const WorldOutcome* w : ws) {
    r.worse += robust_worse(*w);
    r.recovered += robust_recovered(*w);
    eb.push_back(w->err_base);
    er.push_back(w->err_robust);
    fb.push_back(w->f1_base);
    fr.push_back(w->f1_robust);
    ab.push_back(w->anees_base);
    ar.push_back(w->anees_robust);
  }
  r.err_base = median(eb);
  r.err_robust = median(er);
  r.f1_base = median(fb);
  r.f1_robust = median(fr);
  r.anees_base = median(ab);
  r.anees_robust = median(ar);
  return r;
}
}  // namespace

bool robust_worse(const WorldOutcome& w) {
  return w.err_robust > w.err_base + tolerance(w.err_base) || w.f1_robust < w.f1_base - 0.005;
}

bool robust_recovered(const WorldOutcome& w) {
  if (!(w.err_base > 3.0)) return false;
  // TRUTH is the reference only where it did not diverge itself (a silent kidnap: it is not told).
  const bool truth = w.err_truth >= 0 && w.err_truth <= 3.0;
  return truth ? w.err_robust <= w.err_truth + tolerance(w.err_truth) : w.err_robust < 1.0;
}

std::vector<FamilyRow> non_inferiority(const std::vector<WorldOutcome>& worlds) {
  std::vector<std::string> order;
  for (const WorldOutcome& w : worlds)
    if (std::find(order.begin(), order.end(), w.family) == order.end()) order.push_back(w.family);
  std::vector<FamilyRow> rows;
  std::vector<const WorldOutcome*> all;
  for (const std::string& f : order) {
    std::vector<const WorldOutcome*> ws;
    for (const WorldOutcome& w : worlds)
      if (w.family == f) ws.push_back(&w);
    rows.push_back(row_of(f, ws));
  }
  all.reserve(worlds.size());
  for (const WorldOutcome& w : worlds) all.push_back(&w);
  rows.push_back(row_of("total", all));
  return rows;
}

std::string non_inferiority_markdown(const std::vector<WorldOutcome>& worlds) {
  std::string out =
      "PCJCBB+RL against PCJCBB per generated world: worse = pose error above PCJCBB's by more than max(0.5 m, 20 %) "
      "or F1 below by more than 0.005; recovered = PCJCBB's pose error over 3 m and PCJCBB+RL's within max(0.5 m, "
      "20 %) of TRUTH's (under 1 m without TRUTH or where TRUTH's is over 3 m). Pose error: the norm of the run's mean |x| and |y| errors; "
      "medians per family.\n\n"
      "| family | worlds | worse | recovered | pose err PCJCBB [m] | pose err PCJCBB+RL [m] | F1 PCJCBB | F1 "
      "PCJCBB+RL | ANEES PCJCBB | ANEES PCJCBB+RL |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  char line[512];
  for (const FamilyRow& r : non_inferiority(worlds)) {
    std::snprintf(line, sizeof line, "| %s | %d | %d | %d | %.2f | %.2f | %.4f | %.4f | %.2f | %.2f |\n",
                  r.family.c_str(), r.worlds, r.worse, r.recovered, r.err_base, r.err_robust, r.f1_base, r.f1_robust,
                  r.anees_base, r.anees_robust);
    out += line;
  }
  bool any = false;
  for (const WorldOutcome& w : worlds) {
    if (!robust_worse(w)) continue;
    if (!any) out += "\nWorse worlds (replay one with --scenario FILE):\n";
    any = true;
    std::snprintf(line, sizeof line, "- %s: pose err %.2f -> %.2f m, F1 %.4f -> %.4f\n", w.file.c_str(), w.err_base,
                  w.err_robust, w.f1_base, w.f1_robust);
    out += line;
  }
  return out;
}

namespace {
std::vector<std::string> first_seen(const std::vector<WorldStrategyOutcome>& ws, bool family) {
  std::vector<std::string> order;
  for (const WorldStrategyOutcome& w : ws) {
    const std::string& k = family ? w.family : w.strategy;
    if (std::find(order.begin(), order.end(), k) == order.end()) order.push_back(k);
  }
  return order;
}

std::string strategy_row(const std::string& family, const std::string& strategy,
                         const std::vector<const WorldStrategyOutcome*>& ws) {
  std::vector<double> f1, err;
  int tp = 0, fp = 0, fn = 0, clutter = 0, mover = 0, in_map = 0;
  for (const WorldStrategyOutcome* w : ws) {
    f1.push_back(w->f1);
    err.push_back(w->err);
    tp += w->tp;
    fp += w->fp;
    fn += w->fn;
    clutter += w->fp_clutter;
    mover += w->fp_mover;
    in_map += w->movers_in_map;
  }
  const double pooled = tp == 0 ? 0.0 : 2.0 * tp / (2.0 * tp + fp + fn);
  char line[512];
  std::snprintf(line, sizeof line, "| %s | %s | %zu | %.4f | %.4f | %.2f | %d | %d | %d | %d |\n", family.c_str(),
                strategy.c_str(), ws.size(), median(f1), pooled, median(err), fp, clutter, mover, in_map);
  return line;
}
}  // namespace

std::string strategies_markdown(const std::vector<WorldStrategyOutcome>& worlds) {
  std::string out =
      "Every strategy per family of generated worlds: F1 (median over the worlds, and pooled over their pairs), pose "
      "error (median; the norm of the run's mean |x| and |y| errors), and sums over the worlds' runs of the false "
      "pairs (FP), of those clutter paired, of those a mover's observation paired (FP mover), and the landmarks made "
      "from movers still mapped at the end.\n\n"
      "| family | strategy | worlds | F1 median | F1 pooled | pose err [m] | FP | FP clutter | FP mover | movers in "
      "map |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  const std::vector<std::string> families = first_seen(worlds, true), strategies = first_seen(worlds, false);
  for (const std::string& f : families)
    for (const std::string& st : strategies) {
      std::vector<const WorldStrategyOutcome*> ws;
      for (const WorldStrategyOutcome& w : worlds)
        if (w.family == f && w.strategy == st) ws.push_back(&w);
      if (!ws.empty()) out += strategy_row(f, st, ws);
    }
  if (families.size() > 1) {
    for (const std::string& st : strategies) {
      std::vector<const WorldStrategyOutcome*> ws;
      for (const WorldStrategyOutcome& w : worlds)
        if (w.strategy == st) ws.push_back(&w);
      out += strategy_row("total", st, ws);
    }
  }
  return out;
}

}  // namespace geojcbb::host
