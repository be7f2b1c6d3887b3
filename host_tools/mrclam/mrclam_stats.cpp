// mrclam_stats: the counts and the noise of the UTIAS MRCLAM datasets 6 and 7, measured against
// their ground truth, as the Markdown table of docs/mrclam.md.
//   mrclam_stats [--data DIR] [--window S]
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "geojcbb_host/mrclam.hpp"
#include "geojcbb_host/mrclam_calibration.hpp"
#include "geojcbb_host/guarded_main.hpp"

namespace {

using namespace geojcbb::host::mrclam;

struct Column {
  long measurements = 0, landmark = 0, robot = 0, unknown = 0;
  long scans = 0, exact_scans = 0, max_per_scan = 0;
  double range_min = 1e9, range_max = -1e9, bearing_min = 1e9, bearing_max = -1e9;
  long truth_gaps = 0;  // consecutive ground-truth samples more than kMaxTruthGap_s apart
  MeasurementNoise z;
  OdometryNoise odo;
};

Column measure(int number, const std::string& root, double window_s) {
  const Dataset ds = load_dataset(dataset_dir(number, root));
  std::vector<RobotLog> logs;
  Column c;
  for (int r = 1; r <= kRobots; ++r) {
    logs.push_back(load_robot(ds, r));
    const RobotLog& log = logs.back();
    c.exact_scans += static_cast<long>(load_robot(ds, r, 0.0).scans.size());
    c.scans += static_cast<long>(log.scans.size());
    for (const Scan& s : log.scans) {
      c.max_per_scan = std::max(c.max_per_scan, static_cast<long>(s.z.size()));
      for (const Measurement& m : s.z) {
        ++c.measurements;
        if (ds.is_landmark(m.subject)) {
          ++c.landmark;
        } else if (m.subject == 0) {
          ++c.unknown;
        } else {
          ++c.robot;
        }
        c.range_min = std::min(c.range_min, m.range);
        c.range_max = std::max(c.range_max, m.range);
        c.bearing_min = std::min(c.bearing_min, m.bearing);
        c.bearing_max = std::max(c.bearing_max, m.bearing);
      }
    }
    for (std::size_t i = 1; i < log.truth.size(); ++i)
      c.truth_gaps += log.truth[i].t - log.truth[i - 1].t > kMaxTruthGap_s;
  }
  c.z = estimate_measurement_noise(ds, logs);
  c.odo = estimate_odometry_noise(logs, window_s);
  return c;
}

template <class T>
std::string format(const char* fmt, T v) {
  char b[64];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

}  // namespace

namespace {

int run(int argc, char** argv) {
  CLI::App app{"UTIAS MRCLAM datasets 6 and 7: counts, and noise against ground truth"};
  std::string root = default_data_dir();
  double window_s = 1.0;
  app.add_option("--data", root, "folder holding MRCLAM_Dataset6 and MRCLAM_Dataset7");
  app.add_option("--window", window_s, "odometry comparison window [s]")->check(CLI::PositiveNumber);
  bool calibrate = false;
  CalibrationOptions copt;
  app.add_flag("--calibrate", calibrate,
               "print each robot's fitted camera and drive (mrclam_calibration.hpp) instead of the tables");
  app.add_option("--fit-window", copt.fit_window_s, "window of the drive's scale and noise fit [s]")
      ->default_val(copt.fit_window_s);
  CLI11_PARSE(app, argc, argv);
  if (calibrate) {
    try {
      for (int n : {6, 7}) {
        const Dataset ds = load_dataset(dataset_dir(n, root));
        std::printf("MRCLAM_Dataset%d\n", n);
        for (int r = 1; r <= kRobots; ++r)
          std::printf("  %s\n", describe(calibrate_robot(ds, load_robot(ds, r), copt)).c_str());
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mrclam_stats: %s\n", e.what());
      return 1;
    }
    return 0;
  }

  Column c[2];
  try {
    c[0] = measure(6, root, window_s);
    c[1] = measure(7, root, window_s);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mrclam_stats: %s\n", e.what());
    return 1;
  }
  // One table row: the quantity, then its value in dataset 6 and 7 through printf format fmt.
  const auto row = [&](const char* name, const char* fmt, auto get) {
    std::printf("| %s | %s | %s |\n", name, format(fmt, get(c[0])).c_str(), format(fmt, get(c[1])).c_str());
  };
  std::printf("# MRCLAM datasets 6 and 7 (%s)\n\n", root.c_str());
  std::printf("| quantity | dataset 6 | dataset 7 |\n| --- | --- | --- |\n");
  row("measurements", "%ld", [](const Column& x) { return x.measurements; });
  row("of landmarks (subjects 6-20)", "%ld", [](const Column& x) { return x.landmark; });
  row("of robots (subjects 1-5)", "%ld", [](const Column& x) { return x.robot; });
  row("unknown barcodes", "%ld", [](const Column& x) { return x.unknown; });
  row("scans (exact timestamps)", "%ld", [](const Column& x) { return x.exact_scans; });
  row("scans (within 0.05 s)", "%ld", [](const Column& x) { return x.scans; });
  row("most measurements in a scan", "%ld", [](const Column& x) { return x.max_per_scan; });
  row("range min [m]", "%.3f", [](const Column& x) { return x.range_min; });
  row("range max [m]", "%.3f", [](const Column& x) { return x.range_max; });
  row("bearing min [rad]", "%.3f", [](const Column& x) { return x.bearing_min; });
  row("bearing max [rad]", "%.3f", [](const Column& x) { return x.bearing_max; });
  row("ground-truth gaps > 0.5 s", "%ld", [](const Column& x) { return x.truth_gaps; });
  row("landmark residuals", "%ld", [](const Column& x) { return x.z.count; });
  row("landmark measurements without ground truth", "%ld", [](const Column& x) { return x.z.skipped; });
  row("range residual mean [m]", "%.4f", [](const Column& x) { return x.z.range.mean; });
  row("range residual std [m]", "%.4f", [](const Column& x) { return x.z.range.std; });
  row("range residual robust std [m]", "%.4f", [](const Column& x) { return x.z.range.robust_std; });
  row("bearing residual mean [rad]", "%.4f", [](const Column& x) { return x.z.bearing.mean; });
  row("bearing residual std [rad]", "%.4f", [](const Column& x) { return x.z.bearing.std; });
  row("bearing residual robust std [rad]", "%.4f", [](const Column& x) { return x.z.bearing.robust_std; });
  row("outliers (\\|dr\\| > 0.5 m or \\|db\\| > 0.2 rad)", "%ld", [](const Column& x) { return x.z.outliers; });
  row("outlier fraction", "%.4f", [](const Column& x) { return x.z.outlier_fraction; });
  row("odometry windows used", "%ld", [](const Column& x) { return x.odo.windows; });
  row("odometry windows skipped", "%ld", [](const Column& x) { return x.odo.skipped; });
  row("v residual mean [m/s]", "%.4f", [](const Column& x) { return x.odo.v.mean; });
  row("v residual std [m/s]", "%.4f", [](const Column& x) { return x.odo.v.std; });
  row("v residual robust std [m/s]", "%.4f", [](const Column& x) { return x.odo.v.robust_std; });
  row("w residual mean [rad/s]", "%.4f", [](const Column& x) { return x.odo.w.mean; });
  row("w residual std [rad/s]", "%.4f", [](const Column& x) { return x.odo.w.std; });
  row("w residual robust std [rad/s]", "%.4f", [](const Column& x) { return x.odo.w.robust_std; });
  std::printf("\nOdometry residuals compare %g s averages of the commanded (v, w) with ground truth.\n", window_s);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
