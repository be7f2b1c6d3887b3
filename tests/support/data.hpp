// Tests: the real data sets (MRCLAM, Victoria Park) are read in place from beside the repository
// (or the folder an environment variable names). A user who cloned the project has neither: a test
// that needs one is skipped with a message naming the folder and where to get the data (README.md,
// "Data"), unless GEOJCBB_REQUIRE_DATA=1 (CI sets it), which makes an absent folder a failure.
#pragma once

#include <doctest/doctest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "geojcbb_host/mrclam.hpp"
#include "geojcbb_host/victoria_park.hpp"

namespace geojcbb::test {

/// True when GEOJCBB_REQUIRE_DATA=1: a missing data folder fails the tests that need it.
inline bool data_required() {
  const char* v = std::getenv("GEOJCBB_REQUIRE_DATA");
  return v != nullptr && std::strcmp(v, "1") == 0;
}

/// Whether the data folder `dir` (of the data set `name`, overridden by the environment variable
/// `env`) is there; when it is not, a failed check (data_required()) or a skip message.
inline bool have_data(const std::string& dir, const char* name, const char* env) {
  if (std::filesystem::is_directory(dir)) return true;
  if (data_required()) {
    FAIL_CHECK("GEOJCBB_REQUIRE_DATA=1 and the " << name << " data are not at '" << dir << "' (set " << env
                                                 << ", or see README.md, \"Data\", for where to get them)");
  } else {
    MESSAGE("skipped: the " << name << " data are not at '" << dir << "' (set " << env
                            << ", or see README.md, \"Data\", for where to get them)");
  }
  return false;
}

/// The UTIAS MRCLAM data (datasets 6 and 7).
inline bool have_mrclam() { return have_data(host::mrclam::default_data_dir(), "MRCLAM", "GEOJCBB_MRCLAM_DIR"); }

/// A MRCLAM dataset's landmark positions in index order (for replay::landmark_groups).
inline std::vector<Eigen::Vector2d> landmark_xy(const host::mrclam::Dataset& ds) {
  std::vector<Eigen::Vector2d> p;
  for (const host::mrclam::Landmark& l : ds.landmarks) p.emplace_back(l.x, l.y);
  return p;
}

/// ACFR's Victoria Park (odometry, laser frames, tree detections, GPS).
inline bool have_victoria_park() {
  return have_data(host::victoria_park::default_data_dir(), "Victoria Park", "GEOJCBB_VICTORIA_PARK_DIR");
}

}  // namespace geojcbb::test
