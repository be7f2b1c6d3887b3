// host_tools/bench: what the benchmark suites share: options, timing, order statistics.
// Benchmarks measure; they never decide a pass. Ratios are taken against a baseline measured in
// the same run, on the same scenes.
#pragma once

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "geojcbb/associate.hpp"
#include "geojcbb_host/scene.hpp"

namespace geojcbb::bench {

using Clock = std::chrono::steady_clock;

struct BenchOptions {
  int scenes = 40;           ///< scenes per cell
  std::uint64_t seed = 1;    ///< scene k of a cell uses seed + k
  bool quick = false;        ///< a smoke run: the smallest cells only
  double confidence = 0.99;  ///< chi-square level of the individual and joint tests
  std::string out_dir;       ///< CSV files go here when set
  // mrpt suite
  bool mrpt_kdtree = true;
  double mrpt_cell_cap_s = 20.0;
  std::vector<int> dense_m{6, 8, 10};
  bool dense_only = false;
  // strategies suite
  NodeCount node_budget = 0;  ///< 0: the capacity's maximum
};

/// Order statistic by nearest rank: q = 0.5 median, 0.9 p90, 1 maximum.
inline double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t k =
      std::min(v.size() - 1, static_cast<std::size_t>(std::llround(q * static_cast<double>(v.size() - 1))));
  return v[k];
}

inline double elapsed_us(Clock::time_point t0, Clock::time_point t1) {
  return std::chrono::duration<double, std::micro>(t1 - t0).count();
}

int run_mrpt_suite(const BenchOptions& o);
int run_strategy_suite(const BenchOptions& o);

}  // namespace geojcbb::bench
