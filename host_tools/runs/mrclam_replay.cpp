// host_tools/runs: a MRCLAM robot's log as a run's inputs (MrclamSource), the noise and the model
// the filter assumes on it, and the run options MRCLAM replays start from (mrclam_replay.hpp).
#include "geojcbb_host/mrclam_replay.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace geojcbb::host {

MrclamNoise MrclamNoise::from_data(const mrclam::Dataset& ds, const std::vector<mrclam::RobotLog>& robots,
                                   double inflation) {
  const mrclam::MeasurementNoise m = mrclam::estimate_measurement_noise(ds, robots);
  const mrclam::OdometryNoise o = mrclam::estimate_odometry_noise(robots, 1.0);
  MrclamNoise n;
  n.sigma_range_m = inflation * m.range.robust_std;
  n.sigma_bearing_rad = inflation * m.bearing.robust_std;
  n.sigma_v_mps = inflation * o.v.robust_std;
  n.sigma_w_radps = inflation * o.w.robust_std;
  return n;
}

SensorModel mrclam_sensor(const MrclamNoise& n) { return SensorModel{0.9, 9.3, 1.2, n.sigma_bearing_rad}; }

MrclamSource::MrclamSource(const mrclam::Dataset& ds, const mrclam::RobotLog& log, const MrclamModel& model,
                           bool drop_other_robots) {
  if (log.odometry.size() < 2 || log.truth.empty()) throw std::runtime_error("robot log without odometry or truth");
  const mrclam::RobotCalibration& cal = model.calibration;
  const double k2 = model.inflation * model.inflation;
  // A command takes effect `lag` after its time stamp.
  const double lag = model.drive ? cal.latency_s : 0.0;
  const auto& o = log.odometry;
  // Start where both odometry and ground truth exist.
  std::size_t i = 0;
  mrclam::PoseSample p0{};
  while (i + 1 < o.size() && !mrclam::interpolate_truth(log.truth, o[i].t + lag, p0)) ++i;
  if (i + 1 >= o.size()) throw std::runtime_error("no odometry sample has a ground-truth pose");
  const MrclamNoise& noise = model.noise;
  sensor = mrclam_sensor(noise);
  true_landmarks = ds.landmarks.size();
  x0 = Pose2<double>{p0.x, p0.y, p0.theta};
  P0 = Eigen::Matrix3d::Identity() * 1e-6;
  const Eigen::Matrix2d R_const =
      Eigen::Vector2d(noise.sigma_range_m * noise.sigma_range_m, noise.sigma_bearing_rad * noise.sigma_bearing_rad)
          .asDiagonal();
  // Landmark index of each subject.
  std::vector<int> index_of_subject(64, -1);
  for (std::size_t k = 0; k < ds.landmarks.size(); ++k) {
    const int s = ds.landmarks[k].subject;
    if (s >= 0 && s < static_cast<int>(index_of_subject.size())) index_of_subject[s] = static_cast<int>(k);
  }
  double t = o[i].t + lag;  // the filter's time: every prediction starts here
  auto push_motion = [&](double v, double w, double dt, double extra_v_std, double extra_w_std) {
    RunInput in;
    if (model.drive) {
      ekf::Odometry<double> u;
      if (cal.drive.odometry(v, w, dt, u) != Status::kOk) throw std::runtime_error("drive model: bad odometry");
      in.v_mps = u.v_mps;
      in.w_radps = u.w_radps;
      in.sigma_v_mps = std::sqrt(k2 * u.sigma_v_mps * u.sigma_v_mps + extra_v_std * extra_v_std);
      in.sigma_w_radps = std::sqrt(k2 * u.sigma_w_radps * u.sigma_w_radps + extra_w_std * extra_w_std);
    } else {
      const double k = 1.0 / std::sqrt(std::max(dt, 1e-6));
      in.v_mps = v;
      in.w_radps = w;
      in.sigma_v_mps = noise.sigma_v_mps * k;
      in.sigma_w_radps = noise.sigma_w_radps * k;
    }
    in.dt_s = dt;
    in.t_s = t;  // the piece's start (the log converter writes it as the odom line's time)
    inputs_.push_back(std::move(in));
  };
  auto advance = [&](double to) {  // predict from t to `to` with the command of sample i
    while (t < to) {               // the hold limit splits a gap into a moving and a stopped part
      const double start = o[i].t + lag;
      const double hold_end = start + kHoldLimit_s;
      const bool moving = t < hold_end;
      const double end = moving ? std::min(to, hold_end) : to;
      const double dt = end - t;
      if (moving || !model.drive) {
        push_motion(moving ? o[i].v : 0.0, moving ? o[i].w : 0.0, dt, 0, 0);
      } else {
        // The rest of a gap: the robot goes on with the held command (the log only missed samples;
        // measured: 0.9 of the held motion at the median, 0.6-1.05 between the 10th and 90th
        // percentiles, docs/mrclam.md), with an extra std of kGapMotionStd of that motion over
        // the rest L, spread over the pieces in proportion to their length.
        const double gap_end = i + 1 < o.size() ? o[i + 1].t + lag : end;
        const double L = std::max(gap_end - hold_end, dt);
        const double f = kGapMotionStd * std::sqrt(L / dt);
        push_motion(o[i].v, o[i].w, dt, std::abs(o[i].v) * cal.drive.scale_v * f,
                    std::abs(o[i].w) * cal.drive.scale_w * f);
      }
      t = end;
    }
  };
  for (const mrclam::Scan& scan : log.scans) {
    if (scan.t < t) continue;  // before the start
    while (i + 1 < o.size() && o[i + 1].t + lag <= scan.t) {
      advance(o[i + 1].t + lag);
      ++i;
    }
    advance(scan.t);
    RunInput in;
    in.scan = true;
    std::vector<SimObservation>& obs = in.observations;
    std::vector<int>& subjects = scan_subjects.emplace_back();
    for (const mrclam::Measurement& m : scan.z) {
      if (drop_other_robots && m.subject >= 1 && m.subject <= mrclam::kRobots) continue;
      const int truth =
          m.subject >= 0 && m.subject < static_cast<int>(index_of_subject.size()) ? index_of_subject[m.subject] : -1;
      SimObservation so{Eigen::Vector2d(m.range, m.bearing), truth, R_const};
      if (model.camera) {
        Vec2<double> z;
        Mat2<double> R;
        if (cal.sensor.correct(so.z, z, R) != Status::kOk) continue;  // a non-positive range: not a measurement
        so.z = z;
        so.R = k2 * R;
      }
      obs.push_back(so);
      subjects.push_back(m.subject);
    }
    mrclam::PoseSample pt{};
    in.have_truth = mrclam::interpolate_truth(log.truth, scan.t, pt);
    in.true_pose = Pose2<double>{pt.x, pt.y, pt.theta};
    in.t_s = scan.t;
    inputs_.push_back(std::move(in));
  }
}

RunResult replay_robot(const mrclam::Dataset& ds, const mrclam::RobotLog& log, const RunOptions& opt,
                       const MrclamModel& model, bool drop_other_robots) {
  MrclamSource src(ds, log, model, drop_other_robots);
  return run_inputs(src, opt);
}

RunOptions mrclam_run_defaults() {
  RunOptions o;
  o.step.static_gate_level = 0.95;
  o.step.landmark_reserve_nats = 4.6f;  // a confirmed landmark missed six times in a row goes (movers)
  o.step.new_if_candidates_taken = true;
  o.step.occlusion_rad = 0.03;
  return o;
}

MrclamModel mrclam_model(const MrclamNoise& noise, const mrclam::RobotCalibration& calibration, bool camera, bool drive,
                         double inflation) {
  MrclamModel m;
  m.noise = noise;
  m.camera = camera;
  m.drive = drive;
  m.inflation = inflation;
  m.calibration = calibration;
  return m;
}
}  // namespace geojcbb::host
