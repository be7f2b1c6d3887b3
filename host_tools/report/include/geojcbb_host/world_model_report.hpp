// host_tools/report: the world model's figures in the reports (docs/design.md, "The world model"):
// per strategy the landmarks that became movers, the clutter density and p_D per range bin the
// filter learned (learn_clutter, learn_detection; the mean over runs), and, where the data is
// labelled, p_D as the labels give it (labelled_detection).
#pragma once

#include <Eigen/Core>
#include <cstdio>
#include <string>
#include <vector>

#include "geojcbb/core/settings.hpp"
#include "geojcbb_host/run_score.hpp"
#include "geojcbb_host/run_source.hpp"

namespace geojcbb::host {

/// p_D per range bin counted from labels: bins as the filter's (ekf::DetectionModel: kDetectionBins
/// over the view's max range).
struct DetectionTable {
  double bin_m = 0;
  std::vector<long> hits, expected;
  double pd(std::size_t b) const { return expected[b] > 0 ? double(hits[b]) / double(expected[b]) : 0.0; }
  DetectionTable& operator+=(const DetectionTable& o);
};

/// The labelled p_D of a run's inputs: at each scan with a true pose, each true landmark (`positions`,
/// index = truth) that the view of `view` (min_range_m, max_range_m, half_fov_rad, the sensor's
/// mount) puts in view from the true pose is expected, and a hit when one of the scan's observations
/// carries its truth. No occlusion: the geometry alone.  O(scans x landmarks)
DetectionTable labelled_detection(RunSource& src, const std::vector<Eigen::Vector2d>& positions,
                                  const StepSettings<double>& view);

/// The world model's sums over one strategy's runs.
struct WorldModelSums {
  int runs = 0, movers_caught = 0;
  std::vector<double> pd_sum;  ///< per bin, over the runs that learned p_D
  int pd_runs = 0;
  double bin_m = 0;
  double clutter_sum = 0;  ///< over the runs that learned the clutter density
  int clutter_runs = 0;
  void add(const RunResult& r);
};

/// One line per strategy: movers caught, the learned clutter density, the learned p_D per bin; then
/// the labelled table (`labelled`, nullptr: none). Nothing when no strategy learned or caught anything.
void print_world_model(const std::vector<std::string>& names, const std::vector<WorldModelSums>& sums,
                       const DetectionTable* labelled, std::FILE* out);

}  // namespace geojcbb::host
