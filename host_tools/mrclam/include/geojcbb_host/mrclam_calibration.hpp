// host_tools/mrclam: per-robot calibration of the camera and the drive against ground truth
// (docs/mrclam.md, "The model"). What is fitted, per robot:
//   camera  relative range bias c0 + c1 b + c2 b^2 (robust IRLS on r_raw / r_true - 1), bearing
//           bias b0 (median), range std k_r r (MAD of the relative residual), bearing std (MAD);
//   drive   latency of the commands (the shift that best explains the heading's change over
//           0.25 s windows), scale of v and w (least squares over fit windows), and the process
//           noise terms of ekf::OdometryModel (least squares of the squared window residuals on
//           v^2 dt, w^2 dt and dt, negative terms dropped).
// The robots are the same in datasets 6 and 7, so the replay calibrates each robot on the other
// dataset ("cross") by default: nothing it is scored on is used to fit it.
#pragma once

#include <string>
#include <vector>

#include "geojcbb/ekf/motion.hpp"
#include "geojcbb/ekf/sensor_model.hpp"
#include "geojcbb_host/mrclam.hpp"

namespace geojcbb::host::mrclam {

struct CalibrationOptions {
  double fit_window_s = 4.0;          ///< the drive's scale and noise are fitted over windows of this length
  double max_latency_s = 0.5;         ///< latency searched in [0, max] by 0.01 s
  double sigma_range_floor_m = 0.01;  ///< constant part of the range std
};

struct RobotCalibration {
  int robot = 0;
  ekf::RangeBearingModel<double> sensor;
  ekf::OdometryModel<double> drive;
  double latency_s = 0;   ///< the commands take effect this long after their time stamp
  long measurements = 0;  ///< landmark measurements used for the camera
  long outliers = 0;      ///< of those, beyond kOutlierRange_m / kOutlierBearing_rad (not fitted)
  long windows = 0;       ///< drive windows used
};

/// Fits one robot's camera and drive to its log against ground truth. Throws std::runtime_error
/// when the log has too little data to fit (fewer than 100 landmark measurements or windows).
RobotCalibration calibrate_robot(const Dataset& ds, const RobotLog& log, const CalibrationOptions& options = {});

/// One line per field, for the reports.
std::string describe(const RobotCalibration& c);

}  // namespace geojcbb::host::mrclam
