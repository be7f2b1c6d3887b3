// host_tools/mrclam: a reader for the UTIAS Multi-Robot Cooperative Localization and Mapping
// dataset (Leung et al., IJRR 2011), real range-bearing data whose associations are known from
// barcodes. The data stay outside the repository (../shared/data/mrclam); docs/mrclam.md describes
// the files, their quirks and the noise measured here.
//
// Layout of one dataset folder (MRCLAM_DatasetN):
//   Barcodes.dat               subject, barcode (subjects 1-5 are robots, 6-20 landmarks)
//   Landmark_Groundtruth.dat   subject, x, y, x std, y std [m]
//   RobotN_Groundtruth.dat     time [s], x, y [m], heading [rad]
//   RobotN_Odometry.dat        time [s], v [m/s], w [rad/s] (the commanded velocities)
//   RobotN_Measurement.dat     time [s], BARCODE, range [m], bearing [rad]
// Lines starting with '#' and blank lines are skipped; fields are separated by spaces or tabs; a
// CR before the line end is accepted. Times are Unix epoch seconds (ms resolution) and must not
// decrease within a file. Any other malformed line, or a missing file, throws std::runtime_error
// with "path:line: reason" (or "path: cannot open").
//
// Typical use:
//   const Dataset ds = load_dataset(dataset_dir(6));
//   for (int r = 1; r <= kRobots; ++r) { const RobotLog log = load_robot(ds, r); ... }
//
// Scans: one camera frame is sometimes logged over timestamps 1-4 ms apart, while consecutive
// frames are at least 0.147 s apart (docs/mrclam.md has the counts). load_robot therefore puts a
// measurement in the current scan when its time is within scan_tolerance_s (default 0.05 s) of the
// scan's first measurement; 0 groups by exact timestamp equality. Each measurement keeps its own
// time.
//
// Clutter: a barcode missing from Barcodes.dat (subject 0 here) is a false detection; a barcode of
// a robot (subject 1-5) is a moving object. Both are clutter for landmark SLAM: only subjects with
// a ground-truth landmark position (Dataset::is_landmark) are landmarks.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace geojcbb::host::mrclam {

constexpr int kRobots = 5;                 ///< robots are subjects 1..kRobots
constexpr double kScanTolerance_s = 0.05;  ///< default scan grouping tolerance (see above)
constexpr double kMaxTruthGap_s = 0.5;     ///< interpolate_truth refuses to bridge longer gaps
constexpr double kOutlierRange_m = 0.5;    ///< a residual beyond either bound is an outlier
constexpr double kOutlierBearing_rad = 0.2;

struct OdometrySample {
  double t, v, w;
};
struct PoseSample {
  double t, x, y, theta;
};

struct Measurement {
  double t;        ///< its own time as logged [s]
  double range;    ///< [m]
  double bearing;  ///< [rad], positive to the left
  int barcode;     ///< as logged
  int subject;     ///< via Barcodes.dat; 0 if the barcode is unknown (a false detection)
};

struct Scan {
  double t;  ///< time of the first measurement in the scan [s]
  std::vector<Measurement> z;
};

struct Landmark {
  int subject;
  double x, y, sx, sy;
};

struct RobotLog {
  int robot = 0;  ///< 1..kRobots
  std::vector<OdometrySample> odometry;
  std::vector<PoseSample> truth;
  std::vector<Scan> scans;  ///< in time order
};

struct Dataset {
  std::string dir;
  std::map<int, int> barcode_to_subject;
  std::vector<Landmark> landmarks;  ///< sorted by subject

  /// The subject of a barcode, 0 if the barcode is unknown.
  int subject_of(int barcode) const;
  /// True for a subject with a ground-truth landmark position (6-20 in both datasets).
  bool is_landmark(int subject) const;
  /// The landmark's ground truth, nullptr if the subject is not a landmark.
  const Landmark* landmark(int subject) const;
};

/// Reads Barcodes.dat and Landmark_Groundtruth.dat of one dataset folder.
Dataset load_dataset(const std::string& dir);

/// Reads robot `robot` (1..kRobots) of the dataset, grouping its measurements into scans.
RobotLog load_robot(const Dataset& ds, int robot, double scan_tolerance_s = kScanTolerance_s);

/// The ground-truth pose at time t: linear in x and y, along the shorter arc in theta (result in
/// (-pi, pi]). False before the first or after the last sample, and between two samples more than
/// kMaxTruthGap_s apart (a time equal to a sample's always succeeds).
bool interpolate_truth(const std::vector<PoseSample>& truth, double t, PoseSample& out);

/// The folder holding MRCLAM_Dataset6 and 7: $GEOJCBB_MRCLAM_DIR if set and not empty, else the
/// path CMake compiled in (../shared/data/mrclam beside the source tree).
std::string default_data_dir();
/// root/MRCLAM_Dataset<number>.
std::string dataset_dir(int number, const std::string& root = default_data_dir());

struct ResidualStats {
  double mean = 0, std = 0;  ///< sample mean and standard deviation
  double robust_std = 0;     ///< 1.4826 x median absolute deviation: the std if the core is Gaussian
};

/// Mean, std and robust std of a sample (all 0 when empty).
ResidualStats residual_stats(std::vector<double> x);

/// Residuals z - h(truth) of every landmark measurement: range and bearing predicted from the
/// ground-truth pose interpolated at the measurement's time and the landmark's surveyed position.
struct MeasurementNoise {
  ResidualStats range, bearing;  ///< [m], [rad] (bearing residual wrapped to (-pi, pi])
  long count = 0;                ///< landmark measurements with a ground-truth pose
  long outliers = 0;             ///< |dr| > kOutlierRange_m or |db| > kOutlierBearing_rad
  double outlier_fraction = 0;   ///< outliers / count
  long skipped = 0;              ///< landmark measurements with no ground-truth pose at their time
};
MeasurementNoise estimate_measurement_noise(const Dataset& ds, const std::vector<RobotLog>& robots);

/// Odometry against ground truth over consecutive windows of window_s seconds from each robot's
/// first odometry sample. In a window, the odometry's mean v and w (each command held until the
/// next sample) are compared with the ground truth's: the displacement between the window's end
/// poses projected on their mean heading, and their heading change, each over window_s. A
/// residual is odometry - truth, so the stats give the command's bias and the spread of its error
/// as a window_s average (not a per-sample noise: the errors are strongly correlated in time).
/// Windows without ground truth at both ends, or spanning an odometry gap longer than
/// kMaxTruthGap_s (most such gaps end with a stop command, and when the robot stopped is not
/// logged), are skipped.
struct OdometryNoise {
  double window_s = 0;
  ResidualStats v, w;  ///< [m/s], [rad/s]
  long windows = 0;    ///< windows used
  long skipped = 0;
};
OdometryNoise estimate_odometry_noise(const std::vector<RobotLog>& robots, double window_s = 1.0);

}  // namespace geojcbb::host::mrclam
