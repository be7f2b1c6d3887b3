// docs/mrclam.md's reader example, as a program CTest builds and runs (docs.examples_current keeps
// the doc's block equal to the lines between the doc markers). Exits 77 (CTest: skipped) when the
// data folder is absent, 1 (failed) when it is absent and GEOJCBB_REQUIRE_DATA=1.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "geojcbb_host/mrclam.hpp"

using namespace geojcbb::host::mrclam;

int main() {
  if (!std::filesystem::exists(dataset_dir(6))) {
    const char* required = std::getenv("GEOJCBB_REQUIRE_DATA");
    std::printf("%s: %s is absent (MRCLAM: see README.md, \"Data\")\n",
                required != nullptr && std::strcmp(required, "1") == 0 ? "failed (GEOJCBB_REQUIRE_DATA=1)" : "skipped",
                dataset_dir(6).c_str());
    return required != nullptr && std::strcmp(required, "1") == 0 ? 1 : 77;
  }
  // [doc]
  const Dataset ds = load_dataset(dataset_dir(6));  // barcodes and landmark ground truth
  const RobotLog log = load_robot(ds, 1);           // odometry, ground truth, scans
  PoseSample p;
  interpolate_truth(log.truth, log.scans[0].t, p);  // false outside the log or across a gap > 0.5 s
  // [/doc]
  std::printf("mrclam: robot 1 of dataset 6, %zu scans; first at (%.2f, %.2f)\n", log.scans.size(), p.x, p.y);
  return log.scans.empty() ? 1 : 0;
}
