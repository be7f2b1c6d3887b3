// host_tools/report: the world model's figures (world_model_report.hpp).
#include "geojcbb_host/world_model_report.hpp"

#include <algorithm>
#include <cmath>

#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/ekf/detection.hpp"

namespace geojcbb::host {

DetectionTable& DetectionTable::operator+=(const DetectionTable& o) {
  if (hits.empty()) {
    *this = o;
    return *this;
  }
  for (std::size_t b = 0; b < hits.size() && b < o.hits.size(); ++b) {
    hits[b] += o.hits[b];
    expected[b] += o.expected[b];
  }
  return *this;
}

DetectionTable labelled_detection(RunSource& src, const std::vector<Eigen::Vector2d>& positions,
                                  const StepSettings<double>& view) {
  constexpr int kBins = ekf::DetectionModel<double>::kDetectionBins;
  DetectionTable t;
  t.bin_m = view.max_range_m / kBins;
  t.hits.assign(kBins, 0);
  t.expected.assign(kBins, 0);
  const Mount<double> mount{view.sensor_x_m, view.sensor_y_m, view.sensor_theta_rad};
  std::vector<char> seen(positions.size());
  RunInput in;
  while (src.next(in)) {
    if (!in.scan || !in.have_truth) continue;
    std::fill(seen.begin(), seen.end(), 0);
    for (const SimObservation& o : in.observations) {
      if (o.truth >= 0 && static_cast<std::size_t>(o.truth) < seen.size()) seen[static_cast<std::size_t>(o.truth)] = 1;
    }
    for (std::size_t k = 0; k < positions.size(); ++k) {
      const Vec2<double> z = observe(in.true_pose, mount, Vec2<double>(positions[k]));
      if (z.x() < view.min_range_m || z.x() > view.max_range_m || std::abs(z.y()) > view.half_fov_rad) continue;
      const int b = std::min(kBins - 1, static_cast<int>(z.x() / t.bin_m));
      ++t.expected[static_cast<std::size_t>(b)];
      t.hits[static_cast<std::size_t>(b)] += seen[k];
    }
  }
  src.rewind();
  return t;
}

void WorldModelSums::add(const RunResult& r) {
  ++runs;
  movers_caught += r.movers_caught;
  if (!r.learned_pd.empty()) {
    pd_sum.resize(r.learned_pd.size(), 0.0);
    for (std::size_t b = 0; b < r.learned_pd.size(); ++b) pd_sum[b] += r.learned_pd[b];
    ++pd_runs;
    bin_m = r.pd_bin_m;
  }
  if (r.clutter_density > 0) {
    clutter_sum += r.clutter_density;
    ++clutter_runs;
  }
}

void print_world_model(const std::vector<std::string>& names, const std::vector<WorldModelSums>& sums,
                       const DetectionTable* labelled, std::FILE* out) {
  bool any = false;
  for (const WorldModelSums& s : sums) any = any || s.movers_caught > 0 || s.pd_runs > 0 || s.clutter_runs > 0;
  if (!any) return;
  std::fprintf(out,
               "World model (movers caught over the runs; clutter density and p_D by range learned, mean over runs)\n");
  for (std::size_t k = 0; k < sums.size() && k < names.size(); ++k) {
    const WorldModelSums& s = sums[k];
    std::fprintf(out, "  %-12s movers %d", names[k].c_str(), s.movers_caught);
    if (s.clutter_runs > 0) std::fprintf(out, ", clutter %.5f /m^2", s.clutter_sum / s.clutter_runs);
    if (s.pd_runs > 0) {
      std::fprintf(out, ", p_D by %.1f m:", s.bin_m);
      for (double v : s.pd_sum) std::fprintf(out, " %.2f", v / s.pd_runs);
    }
    std::fprintf(out, "\n");
  }
  if (labelled == nullptr || labelled->expected.empty()) return;
  std::fprintf(out, "  %-12s p_D by %.1f m:", "labelled", labelled->bin_m);
  for (std::size_t b = 0; b < labelled->expected.size(); ++b) std::fprintf(out, " %.2f", labelled->pd(b));
  std::fprintf(out, "   (sightings:");
  for (long e : labelled->expected) std::fprintf(out, " %ld", e);
  std::fprintf(out, ")\n");
}

}  // namespace geojcbb::host
