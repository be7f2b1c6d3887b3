#include "geojcbb_host/victoria_park.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <stdexcept>

namespace geojcbb::host::victoria_park {

std::string default_data_dir() {
  const char* env = std::getenv("GEOJCBB_VICTORIA_PARK_DIR");
  if (env != nullptr && *env != '\0') return env;
  return GEOJCBB_VICTORIA_PARK_DEFAULT_DIR;
}

namespace {

// Rows of a CSV file with a known header, each as `columns` numbers.
std::vector<std::vector<double>> read_csv(const std::string& path, const std::string& header, std::size_t columns) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open (the Victoria Park data: README.md, \"Data\")");
  std::string line;
  long n = 1;
  if (!std::getline(f, line) || line.substr(0, header.size()) != header)
    throw std::runtime_error(path + ":1: header '" + header + "' expected");
  std::vector<std::vector<double>> rows;
  while (std::getline(f, line)) {
    ++n;
    if (line.empty() || line == "\r") continue;
    std::vector<double> r;
    const char* p = line.c_str();
    for (std::size_t k = 0; k < columns; ++k) {
      errno = 0;
      char* end = nullptr;
      const double v = std::strtod(p, &end);
      if (end == p || errno == ERANGE || !std::isfinite(v))
        throw std::runtime_error(path + ":" + std::to_string(n) + ": column " + std::to_string(k + 1) +
                                 " is not a finite number");
      r.push_back(v);
      p = end;
      if (k + 1 < columns) {
        if (*p != ',')
          throw std::runtime_error(path + ":" + std::to_string(n) + ": " + std::to_string(columns) +
                                   " columns expected");
        ++p;
      }
    }
    if (*p != '\0' && *p != '\r')
      throw std::runtime_error(path + ":" + std::to_string(n) + ": " + std::to_string(columns) + " columns expected");
    if (!rows.empty() && r[0] < rows.back()[0] && columns != 6)
      throw std::runtime_error(path + ":" + std::to_string(n) + ": out of order");
    rows.push_back(std::move(r));
  }
  return rows;
}

}  // namespace

Data read(const std::string& dir) {
  Data d;
  for (const auto& r : read_csv(dir + "/odometry.csv", "t_s,speed_mps,steering_rad", 3))
    d.odometry.push_back({r[0], r[1], r[2]});
  for (const auto& r : read_csv(dir + "/gps.csv", "t_s,x_east_m,y_north_m", 3)) d.gps.push_back({r[0], r[1], r[2]});
  std::map<long, std::size_t> index;  // frame number -> d.frames
  for (const auto& r : read_csv(dir + "/laser_frames.csv", "frame,t_s,n_detections", 3)) {
    index[std::lround(r[0])] = d.frames.size();
    d.frames.push_back({r[1], {}, {}});
  }
  const std::string det = dir + "/tree_detections.csv";
  for (const auto& r : read_csv(det, "frame,t_s,range_m,angle_scan_rad,bearing_rad,diameter_m", 6)) {
    const auto it = index.find(std::lround(r[0]));
    if (it == index.end())
      throw std::runtime_error(det + ": a detection of frame " + std::to_string(r[0]) + ", not in laser_frames.csv");
    d.frames[it->second].range_m.push_back(r[2]);
    d.frames[it->second].bearing_rad.push_back(r[4]);
  }
  for (std::size_t k = 1; k < d.frames.size(); ++k)
    if (d.frames[k].t < d.frames[k - 1].t) throw std::runtime_error(dir + "/laser_frames.csv: times out of order");
  return d;
}

ekf::PoseIncrement<double> ackermann_increment(double speed_mps, double steer_rad, double dt_s, double sigma_speed_mps,
                                               double sigma_steer_rad, const Vehicle& veh) {
  const double L = veh.wheelbase_m, k = veh.encoder_offset_m / L;
  const double tn = std::tan(steer_rad), sec2 = 1 + tn * tn;
  const double g = 1 - tn * k;
  const double v = speed_mps / g, w = v * tn / L;
  // d(v, w) / d(speed, steer)
  const double dv_ds = 1 / g, dv_dd = speed_mps * k * sec2 / (g * g);
  const double dw_ds = dv_ds * tn / L, dw_dd = (dv_dd * tn + v * sec2) / L;
  // The arc: d(dx, dy, dtheta) / d(v, w).
  const double a = w * dt_s;
  double dx, dy, dx_dv, dx_dw, dy_dv, dy_dw;
  if (std::abs(a) < 1e-6) {  // the series to second order
    dx = v * dt_s * (1 - a * a / 6);
    dy = v * dt_s * a / 2;
    dx_dv = dt_s;
    dx_dw = -v * w * dt_s * dt_s * dt_s / 3;
    dy_dv = a * dt_s / 2;
    dy_dw = v * dt_s * dt_s / 2;
  } else {
    const double s = std::sin(a), c = std::cos(a);
    dx = v * s / w;
    dy = v * (1 - c) / w;
    dx_dv = s / w;
    dx_dw = v * (dt_s * c * w - s) / (w * w);
    dy_dv = (1 - c) / w;
    dy_dw = v * (dt_s * s * w - (1 - c)) / (w * w);
  }
  Eigen::Matrix<double, 3, 2> J_vw;
  J_vw << dx_dv, dx_dw, dy_dv, dy_dw, 0, dt_s;
  Eigen::Matrix2d J_in;
  J_in << dv_ds, dv_dd, dw_ds, dw_dd;
  const Eigen::Matrix<double, 3, 2> J = J_vw * J_in;
  ekf::PoseIncrement<double> u;
  u.dx_m = dx;
  u.dy_m = dy;
  u.dtheta_rad = a;
  u.cov = J * Eigen::Vector2d(sigma_speed_mps * sigma_speed_mps, sigma_steer_rad * sigma_steer_rad).asDiagonal() *
          J.transpose();
  u.cov = 0.5 * (u.cov + u.cov.transpose()).eval();
  return u;
}

replay::EventLog to_log(const Data& data, const ConvertOptions& o) {
  const auto& od = data.odometry;
  if (od.size() < 2) throw std::runtime_error("Victoria Park: fewer than 2 odometry samples");
  const double t0 = od.front().t, t_end = o.seconds > 0 ? std::min(t0 + o.seconds, od.back().t) : od.back().t;
  replay::EventLog log;
  const Vehicle& veh = o.vehicle;
  log.meta["min_range_m"] = o.min_range_m;
  log.meta["max_range_m"] = o.max_range_m;
  log.meta["fov_rad"] = 2 * o.max_bearing_rad;
  log.meta["sigma_bearing_rad"] = o.sigma_bearing_rad;
  log.meta["scan_tolerance_s"] = 0;
  log.meta["sensor_x_m"] = veh.laser_x_m;
  log.meta["sensor_y_m"] = veh.laser_y_m;
  log.meta["sensor_theta_rad"] = 0;
  log.meta["gps_x_m"] = veh.laser_x_m;
  log.meta["gps_y_m"] = veh.laser_y_m;
  const double c = std::cos(o.start_theta_rad), s = std::sin(o.start_theta_rad);
  log.meta["start_x_m"] = o.start_laser_x_m - (c * veh.laser_x_m - s * veh.laser_y_m);
  log.meta["start_y_m"] = o.start_laser_y_m - (s * veh.laser_x_m + c * veh.laser_y_m);
  log.meta["start_theta_rad"] = o.start_theta_rad;
  log.meta["start_var"] = o.start_var;
  // The scans within the odometry, with the detections kept.
  std::vector<const Frame*> frames;
  for (const Frame& f : data.frames)
    if (f.t >= t0 && f.t <= t_end) frames.push_back(&f);
  for (const Frame* f : frames) {
    bool any = false;
    for (std::size_t k = 0; k < f->range_m.size(); ++k) {
      const double r = f->range_m[k], b = f->bearing_rad[k];
      if (!(r >= o.min_range_m && r <= o.max_range_m && std::abs(b) <= o.max_bearing_rad)) continue;
      log.measurements.push_back({f->t, r, b, "", o.sigma_range_m, o.sigma_bearing_rad});
      any = true;
    }
    if (!any) log.empty_scans.push_back(f->t);
  }
  // The increments: the start, then each sample's interval split at the frames' times.
  log.increments.push_back({t0, 0, 0, 0, {}, true});
  std::size_t fi = 0;
  for (std::size_t i = 0; i + 1 < od.size() && od[i].t < t_end; ++i) {
    const double a = od[i].t, b = std::min(od[i + 1].t, t_end), T = od[i + 1].t - od[i].t;
    if (!(T > 0)) continue;
    double from = a;
    while (fi < frames.size() && frames[fi]->t <= a) ++fi;
    auto piece = [&](double to) {
      const double dt = to - from;
      if (!(dt > 0)) return;
      const double f = std::sqrt(T / dt);
      const ekf::PoseIncrement<double> u =
          ackermann_increment(od[i].speed_mps, od[i].steer_rad, dt, o.sigma_speed_mps * f, o.sigma_steer_rad * f, veh);
      const Eigen::Matrix3d& q = u.cov;
      log.increments.push_back(
          {to, u.dx_m, u.dy_m, u.dtheta_rad, {q(0, 0), q(0, 1), q(0, 2), q(1, 1), q(1, 2), q(2, 2)}, true});
      from = to;
    };
    for (; fi < frames.size() && frames[fi]->t < b; ++fi) piece(frames[fi]->t);
    piece(b);
  }
  for (const replay::GpsEvent& g : data.gps)
    if (g.t >= t0 && g.t <= t_end) log.gps.push_back(g);
  return log;
}

}  // namespace geojcbb::host::victoria_park
