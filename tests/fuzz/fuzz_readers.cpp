// tests/fuzz: libFuzzer target for the host's file readers: the simulator's scenario JSON
// (host::load_scenario) and the UTIAS MRCLAM files (host::mrclam::load_dataset, load_robot). The
// input's first byte picks the reader (and the robot number, 0..6, so invalid ones are tried); the
// rest is the file, or for MRCLAM up to five files separated by a line "%%" (Barcodes.dat,
// Landmark_Groundtruth.dat, then RobotN_Groundtruth, _Odometry, _Measurement.dat; missing ones are
// not written). The files go to a private temporary directory, removed at exit. Each call must give
// a result that keeps the documented guarantees, or throw std::runtime_error / std::invalid_argument;
// any other exception or a crash is a finding. corpus_runner.cpp runs it over corpus_readers/.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "geojcbb_host/mrclam.hpp"
#include "geojcbb_host/sim.hpp"

namespace {

namespace fs = std::filesystem;
namespace mrclam = geojcbb::host::mrclam;

void require(bool ok) {
  if (!ok) __builtin_trap();
}

/// The private temporary directory, created once and removed when the process exits.
const fs::path& work_dir() {
  static const fs::path dir = [] {
    std::string tmpl = (fs::temp_directory_path() / "geojcbb_fuzz_readers_XXXXXX").string();
    require(::mkdtemp(tmpl.data()) != nullptr);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(work_dir(), ec);
    });
    return fs::path(tmpl);
  }();
  return dir;
}

void write_file(const fs::path& p, std::string_view text) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  require(static_cast<bool>(out));
}

void clear_dir(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir)) fs::remove(e.path());
}

void check_scenario(const geojcbb::host::Scenario& s) {
  require(s.waypoints.size() >= 2 && s.dt_s > 0 && s.observe_every >= 1 && s.laps >= 1 && s.speed_mps > 0);
  require(s.min_range_m >= 0 && s.min_range_m < s.max_range_m);
  require(s.detection_probability >= 0 && s.detection_probability <= 1 && s.clutter_per_scan >= 0);
}

void check_dataset(const mrclam::Dataset& ds) {
  for (std::size_t i = 1; i < ds.landmarks.size(); ++i) require(ds.landmarks[i - 1].subject < ds.landmarks[i].subject);
  for (const mrclam::Landmark& l : ds.landmarks) {
    require(ds.is_landmark(l.subject) && ds.landmark(l.subject) != nullptr &&
            ds.landmark(l.subject)->subject == l.subject);
  }
}

void check_robot(const mrclam::Dataset& ds, const mrclam::RobotLog& log, int robot, double tol) {
  require(log.robot == robot && robot >= 1 && robot <= mrclam::kRobots);
  for (std::size_t i = 1; i < log.odometry.size(); ++i) require(log.odometry[i - 1].t <= log.odometry[i].t);
  for (std::size_t i = 1; i < log.truth.size(); ++i) require(log.truth[i - 1].t <= log.truth[i].t);
  for (std::size_t k = 0; k < log.scans.size(); ++k) {
    const mrclam::Scan& s = log.scans[k];
    require(!s.z.empty());
    if (k > 0) require(log.scans[k - 1].t <= s.t);
    for (const mrclam::Measurement& m : s.z) {
      require(m.t >= s.t && m.t - s.t <= tol + 1e-9);
      require(m.subject == ds.subject_of(m.barcode));
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0 || size > 65536) return 0;
  const fs::path& dir = work_dir();
  clear_dir(dir);
  const std::uint8_t mode = data[0];
  const std::string_view rest(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    if ((mode & 1) == 0) {
      const fs::path p = dir / "scenario.json";
      write_file(p, rest);
      check_scenario(geojcbb::host::load_scenario(p.string()));
      return 0;
    }
    const int robot = (mode >> 1) % 7;  // 0 and 6 are invalid
    const double tol = (mode & 0x80) ? 0.0 : mrclam::kScanTolerance_s;
    const std::string names[] = {
        "Barcodes.dat", "Landmark_Groundtruth.dat", "Robot" + std::to_string(robot) + "_Groundtruth.dat",
        "Robot" + std::to_string(robot) + "_Odometry.dat", "Robot" + std::to_string(robot) + "_Measurement.dat"};
    std::size_t at = 0;
    for (const std::string& name : names) {  // <= 5 files
      if (at > rest.size()) break;
      std::size_t end = rest.find("%%\n", at);
      if (end == std::string_view::npos) end = rest.size();
      write_file(dir / name, rest.substr(at, end - at));
      at = end + 3;
    }
    const mrclam::Dataset ds = mrclam::load_dataset(dir.string());
    check_dataset(ds);
    check_robot(ds, mrclam::load_robot(ds, robot, tol), robot, tol);
  } catch (const std::runtime_error&) {
    // a clear error: the file and reason
  } catch (const std::invalid_argument&) {
    // a bad robot number or tolerance
  }
  return 0;
}
