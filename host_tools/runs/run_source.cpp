// host_tools/runs: the simulator's and the recorded inputs of a run (run_source.hpp).
#include "geojcbb_host/run_source.hpp"

#include <cmath>
#include <memory>

#include "geojcbb/ekf/motion.hpp"

namespace geojcbb::host {

SimSource::SimSource(const Scenario& sc, std::uint64_t seed, int max_steps)
    : sc_(sc), seed_(seed), max_steps_(max_steps) {
  const Eigen::Vector2d d = sc.waypoints[1] - sc.waypoints[0];
  x0 = Pose2<double>{sc.waypoints[0].x(), sc.waypoints[0].y(), std::atan2(d.y(), d.x())};
  P0 = Eigen::Matrix3d::Identity() * 1e-12;
  sensor = SensorModel{sc.min_range_m, sc.max_range_m, sc.fov_rad,         sc.sigma_bearing_rad,
                       sc.sensor_x_m,  sc.sensor_y_m,  sc.sensor_theta_rad};
  true_landmarks = sc.landmarks.size();
  rewind();
}

SimSource::~SimSource() = default;

void SimSource::rewind() {
  sim_ = std::make_unique<Simulator>(sc_, seed_);
  k_ = 0;
  scan_due_ = false;
  kidnap_due_ = false;
}

bool SimSource::next(RunInput& in) {
  if (scan_due_) {  // the scan at the end of the interval just predicted
    scan_due_ = false;
    in.scan = true;
    in.observations = step_.observations;
    in.t_s = step_.t_s;
    in.have_truth = true;
    in.true_pose = step_.true_pose;
    return true;
  }
  if (kidnap_due_) {  // the kidnap, before the prediction of the interval it happened in
    kidnap_due_ = false;
    in = prediction(sc_, step_);
    scan_due_ = step_.scan;
    return true;
  }
  if (!sim_->step(step_) || (max_steps_ != 0 && k_ >= max_steps_)) return false;
  ++k_;
  if (step_.kidnapped && sc_.kidnap_told) {  // a silent kidnap: the filter is not told
    kidnap_due_ = true;
    in = RunInput{};
    in.relocalise = true;
    in.pose_cov =
        Eigen::Vector3d(sc_.kidnap_sigma_xy_m * sc_.kidnap_sigma_xy_m, sc_.kidnap_sigma_xy_m * sc_.kidnap_sigma_xy_m,
                        sc_.kidnap_sigma_theta_rad * sc_.kidnap_sigma_theta_rad)
            .asDiagonal();
    return true;
  }
  in = prediction(sc_, step_);
  scan_due_ = step_.scan;
  return true;
}

RunInput SimSource::prediction(const Scenario& sc, const SimStep& step) {
  RunInput in;
  in.v_mps = step.v_mps;
  in.w_radps = step.w_radps;
  in.dt_s = sc.dt_s;
  in.sigma_v_mps = sc.sigma_v_mps;
  in.sigma_w_radps = sc.sigma_w_radps;
  if (sc.odometry_increments) {  // the velocity model's motion from the origin, and its covariance
    const ekf::Odometry<double> u{in.v_mps, in.w_radps, in.dt_s, in.sigma_v_mps, in.sigma_w_radps};
    Mat32<double> J;
    const Pose2<double> d = ekf::move(Pose2<double>{0, 0, 0}, u, static_cast<Mat3<double>*>(nullptr), &J);
    in.increment = true;
    in.dx_m = d.x;
    in.dy_m = d.y;
    in.dtheta_rad = d.theta;
    in.increment_cov =
        J * Eigen::Vector2d(in.sigma_v_mps * in.sigma_v_mps, in.sigma_w_radps * in.sigma_w_radps).asDiagonal() *
        J.transpose();
  }
  return in;
}

RecordedSource::RecordedSource(RunSource& src) {
  sensor = src.sensor;
  true_landmarks = src.true_landmarks;
  x0 = src.x0;
  P0 = src.P0;
  RunInput in;
  while (src.next(in)) inputs_.push_back(in);
}

void RecordedSource::scale_noise(double range_var, double bearing_var, double odometry_var) {
  const double sr = std::sqrt(range_var), sb = std::sqrt(bearing_var), sq = std::sqrt(odometry_var);
  for (RunInput& in : inputs_) {
    for (SimObservation& o : in.observations) {
      o.R(0, 0) *= range_var;
      o.R(1, 1) *= bearing_var;
      o.R(0, 1) *= sr * sb;
      o.R(1, 0) *= sr * sb;
    }
    in.sigma_v_mps *= sq;
    in.sigma_w_radps *= sq;
    in.increment_cov *= odometry_var;
  }
}

bool RecordedSource::next(RunInput& in) {
  if (at_ >= inputs_.size()) return false;
  in = inputs_[at_++];
  return true;
}

}  // namespace geojcbb::host
