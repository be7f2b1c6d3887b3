#include "geojcbb_host/event_log.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <istream>
#include <ostream>
#include <sstream>
#include <set>
#include <stdexcept>

namespace geojcbb::host::replay {

namespace {

[[noreturn]] void fail(const std::string& name, long line, const std::string& why) {
  throw std::runtime_error(name + ":" + std::to_string(line) + ": " + why);
}

std::string trim(const std::string& s) {
  const std::size_t a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  const std::size_t b = s.find_last_not_of(" \t\r");
  return s.substr(a, b - a + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> f;
  std::size_t a = 0;
  for (;;) {
    const std::size_t c = line.find(',', a);
    f.push_back(trim(line.substr(a, c == std::string::npos ? std::string::npos : c - a)));
    if (c == std::string::npos) break;
    a = c + 1;
  }
  return f;
}

struct Parser {
  const std::string& name;
  long line;
  double number(const std::string& field, const char* what) const {
    if (field.empty()) fail(name, line, std::string(what) + ": empty field, a number expected");
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(field.c_str(), &end);
    if (end != field.c_str() + field.size()) fail(name, line, std::string(what) + ": '" + field + "' is not a number");
    if (errno == ERANGE || !std::isfinite(v)) fail(name, line, std::string(what) + ": '" + field + "' is not finite");
    return v;
  }
  double sigma(const std::string& field, const char* what, bool zero_ok) const {
    const double v = number(field, what);
    if (zero_ok ? !(v >= 0) : !(v > 0)) {
      fail(name, line,
           std::string(what) + ": a standard deviation must be " + (zero_ok ? "non-negative" : "positive") + ", not " +
               field);
    }
    return v;
  }
  void count(const std::vector<std::string>& f, std::size_t lo, std::size_t hi, const char* form) const {
    if (f.size() < lo || f.size() > hi) {
      fail(name, line, "'" + f[0] + "' takes " + form + " (" + std::to_string(f.size() - 1) + " fields given)");
    }
  }
};

void check_time(double& last, double t, const std::string& name, long line, const char* kind) {
  if (t < last) fail(name, line, std::string("time goes back in the ") + kind + " lines");
  last = t;
}

std::string fmt(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

}  // namespace

const std::vector<std::string>& meta_keys() {
  static const std::vector<std::string> k{
      "min_range_m",     "max_range_m", "fov_rad",    "sigma_bearing_rad", "scan_tolerance_s", "start_x_m", "start_y_m",
      "start_theta_rad", "start_var",   "sensor_x_m", "sensor_y_m",        "sensor_theta_rad", "gps_x_m",   "gps_y_m"};
  return k;
}

Eigen::Matrix3d OdomDeltaEvent::covariance() const {
  Eigen::Matrix3d c;
  c << cov[0], cov[1], cov[2],  //
      cov[1], cov[3], cov[4],   //
      cov[2], cov[4], cov[5];
  return c;
}

Eigen::Matrix2d MeasEvent::R() const {
  const double c = rho * sigma_range * sigma_bearing;
  Eigen::Matrix2d r;
  r << sigma_range * sigma_range, c, c, sigma_bearing * sigma_bearing;
  return r;
}

int EventLog::truth_index(const std::string& label) const {
  const std::map<std::string, int> m = label_indices();
  const auto it = m.find(label);
  return it == m.end() ? -1 : it->second;
}

std::map<std::string, int> EventLog::label_indices() const {
  std::map<std::string, int> m;
  const std::vector<std::string> l = landmark_labels();
  for (std::size_t k = 0; k < l.size(); ++k) m.emplace(l[k], static_cast<int>(k));
  return m;
}

std::vector<std::string> EventLog::landmark_labels() const {
  std::vector<std::string> l;
  std::set<std::string> seen;
  if (!landmarks.empty()) {
    for (const LandmarkEvent& e : landmarks) l.push_back(e.label);
    return l;
  }
  for (const MeasEvent& m : measurements)
    if (!m.label.empty() && m.label != kClutterLabel && seen.insert(m.label).second) l.push_back(m.label);
  return l;
}

bool EventLog::labelled() const {
  if (measurements.empty()) return false;
  for (const MeasEvent& m : measurements)
    if (m.label.empty()) return false;
  return true;
}

EventLog read_event_log(std::istream& in, const std::string& name) {
  EventLog log;
  std::string raw;
  long n = 0;
  double t_odom = -INFINITY, t_meas = -INFINITY, t_truth = -INFINITY, t_gps = -INFINITY;
  long first_odom = 0, first_delta = 0;
  int labelled = 0, unlabelled = 0;
  long first_unlabelled = 0, first_labelled = 0;
  while (std::getline(in, raw)) {
    ++n;
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> f = split(line);
    const Parser p{name, n};
    const std::string& kind = f[0];
    if (kind == "odom") {
      p.count(f, 4, 6, "t,v,w[,sigma_v,sigma_w]");
      if (f.size() == 5) fail(name, n, "'odom' gives both sigma_v and sigma_w, or neither");
      OdomEvent e{p.number(f[1], "t"), p.number(f[2], "v"), p.number(f[3], "w")};
      if (f.size() == 6) {
        e.sigma_v = p.sigma(f[4], "sigma_v", true);  // no process noise (standing still) is a model
        e.sigma_w = p.sigma(f[5], "sigma_w", true);
      }
      if (first_delta > 0)
        fail(name, n,
             "odom line in a log of odom_delta lines (line " + std::to_string(first_delta) + "): one or the other");
      if (first_odom == 0) first_odom = n;
      check_time(t_odom, e.t, name, n, "odom");
      log.odometry.push_back(e);
    } else if (kind == "odom_delta") {
      p.count(f, 5, 11, "t,dx,dy,dtheta[,cxx,cxy,cxt,cyy,cyt,ctt]");
      if (f.size() != 5 && f.size() != 11) fail(name, n, "'odom_delta' gives all 6 covariance terms, or none");
      if (first_odom > 0)
        fail(name, n,
             "odom_delta line in a log of odom lines (line " + std::to_string(first_odom) + "): one or the other");
      if (first_delta == 0) first_delta = n;
      OdomDeltaEvent e{p.number(f[1], "t"), p.number(f[2], "dx"), p.number(f[3], "dy"), p.number(f[4], "dtheta")};
      if (std::abs(e.dtheta) > 3.2) fail(name, n, "dtheta: must be in [-pi, pi] rad, not " + f[4]);
      if (f.size() == 11) {
        static const char* const names[6] = {"cxx", "cxy", "cxt", "cyy", "cyt", "ctt"};
        for (std::size_t k = 0; k < 6; ++k) e.cov[k] = p.number(f[5 + k], names[k]);
        e.has_cov = true;
        // Positive semi-definite, to rounding: the filter refuses anything else.
        const Eigen::Matrix3d c = e.covariance();
        const Eigen::Vector3d ev =
            Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c, Eigen::EigenvaluesOnly).eigenvalues();
        if (ev.minCoeff() < -1e-12 * std::max(1.0, ev.cwiseAbs().maxCoeff()))
          fail(name, n, "odom_delta: the covariance is not positive semi-definite");
      }
      check_time(t_odom, e.t, name, n, "odom_delta");
      log.increments.push_back(e);
    } else if (kind == "gps") {
      p.count(f, 4, 4, "t,x,y");
      GpsEvent e{p.number(f[1], "t"), p.number(f[2], "x"), p.number(f[3], "y")};
      check_time(t_gps, e.t, name, n, "gps");
      log.gps.push_back(e);
    } else if (kind == "meas") {
      p.count(f, 4, 8, "t,range,bearing[,label[,sigma_range,sigma_bearing[,rho]]]");
      if (f.size() == 6) fail(name, n, "'meas' gives both sigma_range and sigma_bearing, or neither");
      MeasEvent e{p.number(f[1], "t"), p.number(f[2], "range"), p.number(f[3], "bearing"), "", -1, -1};
      if (!(e.range > 0)) fail(name, n, "range: must be positive, not " + f[2]);
      if (std::abs(e.bearing) > 3.2) fail(name, n, "bearing: must be in [-pi, pi] rad, not " + f[3]);
      if (f.size() >= 5) e.label = f[4];
      if (f.size() >= 7) {
        e.sigma_range = p.sigma(f[5], "sigma_range", false);  // R must be positive definite
        e.sigma_bearing = p.sigma(f[6], "sigma_bearing", false);
      }
      if (f.size() == 8) {
        e.rho = p.number(f[7], "rho");
        if (!(std::abs(e.rho) < 1))
          fail(name, n, "rho: a correlation in (-1, 1) expected (R positive definite), not " + f[7]);
      }
      if (e.label.empty()) {
        if (unlabelled++ == 0) first_unlabelled = n;
      } else if (labelled++ == 0) {
        first_labelled = n;
      }
      check_time(t_meas, e.t, name, n, "meas and scan");
      log.measurements.push_back(e);
    } else if (kind == "scan") {
      p.count(f, 2, 2, "t");
      const double t = p.number(f[1], "t");
      check_time(t_meas, t, name, n, "meas and scan");
      log.empty_scans.push_back(t);
    } else if (kind == "truth") {
      p.count(f, 5, 5, "t,x,y,theta");
      mrclam::PoseSample s{p.number(f[1], "t"), p.number(f[2], "x"), p.number(f[3], "y"), p.number(f[4], "theta")};
      check_time(t_truth, s.t, name, n, "truth");
      log.truth.push_back(s);
    } else if (kind == "landmark") {
      p.count(f, 4, 4, "label,x,y");
      if (f[1].empty() || f[1] == kClutterLabel)
        fail(name, n, "landmark: a label other than '' and 'clutter' expected");
      for (const LandmarkEvent& l : log.landmarks)
        if (l.label == f[1]) fail(name, n, "landmark '" + f[1] + "' given twice");
      log.landmarks.push_back({f[1], p.number(f[2], "x"), p.number(f[3], "y")});
    } else if (kind == "meta") {
      p.count(f, 3, 3, "key,value");
      const auto& k = meta_keys();
      if (std::find(k.begin(), k.end(), f[1]) == k.end()) fail(name, n, "unknown meta key '" + f[1] + "'");
      log.meta[f[1]] = p.number(f[2], f[1].c_str());
    } else if (kind == "geojcbb_log") {
      p.count(f, 2, 2, "version");
      if (f[1] != "1") fail(name, n, "format version " + f[1] + " not supported (1 expected)");
    } else {
      fail(name, n,
           "unknown line kind '" + kind + "' (odom, odom_delta, meas, scan, truth, gps, landmark, meta expected)");
    }
  }
  if (in.bad()) throw std::runtime_error(name + ": read error");
  if (labelled > 0 && unlabelled > 0) {
    fail(name, first_unlabelled,
         "a measurement without a label, while line " + std::to_string(first_labelled) +
             " has one: label every measurement (clutter: 'clutter') or none");
  }
  return log;
}

EventLog read_event_log(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open");
  return read_event_log(f, path);
}

void write_event_log(const EventLog& log, std::ostream& out, const std::string& comment) {
  out << "# geojcbb log (docs/replay.md)\n";
  if (!comment.empty()) {
    std::istringstream c(comment);
    for (std::string l; std::getline(c, l);) out << "# " << l << '\n';
  }
  out << "geojcbb_log,1\n";
  for (const auto& [k, v] : log.meta) out << "meta," << k << ',' << fmt(v) << '\n';
  for (const LandmarkEvent& l : log.landmarks)
    out << "landmark," << l.label << ',' << fmt(l.x) << ',' << fmt(l.y) << '\n';
  for (const mrclam::PoseSample& s : log.truth)
    out << "truth," << fmt(s.t) << ',' << fmt(s.x) << ',' << fmt(s.y) << ',' << fmt(s.theta) << '\n';
  for (const GpsEvent& g : log.gps) out << "gps," << fmt(g.t) << ',' << fmt(g.x) << ',' << fmt(g.y) << '\n';
  // odom (or odom_delta), meas and scan lines merged in time order (meas before odom at equal
  // times: a scan ends the interval that the odom line at its time starts; odom_delta before meas:
  // an increment ends at its time).
  std::size_t i = 0, j = 0, k = 0, d = 0;
  const auto& o = log.odometry;
  const auto& m = log.measurements;
  const auto& e = log.empty_scans;
  const auto& inc = log.increments;
  while (i < o.size() || j < m.size() || k < e.size() || d < inc.size()) {
    const double to = i < o.size() ? o[i].t : INFINITY, tm = j < m.size() ? m[j].t : INFINITY,
                 te = k < e.size() ? e[k] : INFINITY, td = d < inc.size() ? inc[d].t : INFINITY;
    if (d < inc.size() && td <= tm && td <= te) {
      const OdomDeltaEvent& u = inc[d++];
      out << "odom_delta," << fmt(u.t) << ',' << fmt(u.dx) << ',' << fmt(u.dy) << ',' << fmt(u.dtheta);
      if (u.has_cov)
        for (const double c : u.cov) out << ',' << fmt(c);
      out << '\n';
    } else if (tm <= to && tm <= te && j < m.size()) {
      const MeasEvent& z = m[j++];
      out << "meas," << fmt(z.t) << ',' << fmt(z.range) << ',' << fmt(z.bearing);
      if (!z.label.empty() || z.sigma_range > 0) out << ',' << z.label;
      if (z.sigma_range > 0) out << ',' << fmt(z.sigma_range) << ',' << fmt(z.sigma_bearing);
      if (z.sigma_range > 0 && z.rho != 0) out << ',' << fmt(z.rho);
      out << '\n';
    } else if (te <= to && k < e.size()) {
      out << "scan," << fmt(e[k++]) << '\n';
    } else {
      const OdomEvent& u = o[i++];
      out << "odom," << fmt(u.t) << ',' << fmt(u.v) << ',' << fmt(u.w);
      if (u.sigma_v >= 0) out << ',' << fmt(u.sigma_v) << ',' << fmt(u.sigma_w);
      out << '\n';
    }
  }
  if (!out) throw std::runtime_error("cannot write the log");
}

namespace {

// The log as MRCLAM structures, so the MRCLAM noise estimators apply: landmark k is subject
// kSubject0 + k, clutter subject 0.
constexpr int kSubject0 = 1000;

void as_mrclam(const EventLog& log, mrclam::Dataset& ds, mrclam::RobotLog& robot) {
  for (std::size_t k = 0; k < log.landmarks.size(); ++k)
    ds.landmarks.push_back({kSubject0 + static_cast<int>(k), log.landmarks[k].x, log.landmarks[k].y, 0, 0});
  robot.robot = 1;
  for (const OdomEvent& o : log.odometry) robot.odometry.push_back({o.t, o.v, o.w});
  robot.truth = log.truth;
  const std::map<std::string, int> index = log.label_indices();
  for (const MeasEvent& m : log.measurements) {
    const auto it = index.find(m.label);
    const int idx = it == index.end() ? -1 : it->second;
    robot.scans.push_back({m.t, {{m.t, m.range, m.bearing, 0, idx >= 0 ? kSubject0 + idx : 0}}});
  }
}

}  // namespace

LogNoise estimate_noise(const EventLog& log, double inflation) {
  if (!log.labelled()) throw std::runtime_error("noise from the data needs labelled measurements");
  if (log.truth.empty()) throw std::runtime_error("noise from the data needs ground-truth (truth) lines");
  if (log.landmarks.empty())
    throw std::runtime_error("noise from the data needs the landmark positions (landmark lines)");
  mrclam::Dataset ds;
  mrclam::RobotLog robot;
  as_mrclam(log, ds, robot);
  const std::vector<mrclam::RobotLog> robots{robot};
  const mrclam::MeasurementNoise m = mrclam::estimate_measurement_noise(ds, robots);
  const mrclam::OdometryNoise o = mrclam::estimate_odometry_noise(robots, 1.0);
  if (m.count < 10)
    throw std::runtime_error("noise from the data: fewer than 10 landmark measurements with a true pose");
  if (o.windows < 5)
    throw std::runtime_error("noise from the data: fewer than 5 one-second odometry windows with truth");
  LogNoise n;
  n.sigma_range_m = inflation * m.range.robust_std;
  n.sigma_bearing_rad = inflation * m.bearing.robust_std;
  n.sigma_v_mps = inflation * o.v.robust_std;
  n.sigma_w_radps = inflation * o.w.robust_std;
  if (!(n.sigma_range_m > 0 && n.sigma_bearing_rad > 0 && n.sigma_v_mps > 0 && n.sigma_w_radps > 0)) {
    throw std::runtime_error("noise from the data: a spread came out zero (too few distinct residuals)");
  }
  return n;
}

LogSource::LogSource(const EventLog& log, const LogNoise& noise) {
  const auto& o = log.odometry;
  const auto& inc = log.increments;
  if (o.empty() && inc.empty()) throw std::runtime_error("the log has no odom or odom_delta line");
  auto meta = [&](const char* k, double dflt) {
    const auto it = log.meta.find(k);
    return it == log.meta.end() ? dflt : it->second;
  };
  sensor = SensorModel{meta("min_range_m", 0.0),
                       meta("max_range_m", 30.0),
                       meta("fov_rad", 2 * kPi<double>),
                       meta("sigma_bearing_rad", noise.sigma_bearing_rad > 0 ? noise.sigma_bearing_rad : 0.0175),
                       meta("sensor_x_m", 0.0),
                       meta("sensor_y_m", 0.0),
                       meta("sensor_theta_rad", 0.0)};
  const std::vector<std::string> labels = log.landmark_labels();
  true_landmarks = labels.size();
  const double tol = meta("scan_tolerance_s", 0.0);
  const double t0 = o.empty() ? inc.front().t : o.front().t;
  mrclam::PoseSample p0{t0, 0, 0, 0};
  if (log.meta.count("start_x_m") || log.meta.count("start_y_m") || log.meta.count("start_theta_rad")) {
    p0 = {t0, meta("start_x_m", 0), meta("start_y_m", 0), meta("start_theta_rad", 0)};
  } else if (!log.truth.empty() && !mrclam::interpolate_truth(log.truth, t0, p0)) {
    throw std::runtime_error(
        "no start pose: the truth lines do not cover the first odom line's time (give meta "
        "start_x_m, start_y_m, start_theta_rad)");
  }
  x0 = Pose2<double>{p0.x, p0.y, p0.theta};
  P0 = Eigen::Matrix3d::Identity() * meta("start_var", 1e-6);

  // Scans: measurements and empty scans merged in time order, grouped by the tolerance.
  struct ScanAt {
    double t;
    std::vector<const MeasEvent*> z;
  };
  std::vector<ScanAt> scans;
  {
    std::size_t j = 0, k = 0;
    const auto& m = log.measurements;
    const auto& e = log.empty_scans;
    while (j < m.size() || k < e.size()) {
      const bool meas = j < m.size() && (k >= e.size() || m[j].t <= e[k]);
      const double t = meas ? m[j].t : e[k];
      if (scans.empty() || !(t - scans.back().t <= tol) || (!meas && !scans.back().z.empty())) scans.push_back({t, {}});
      if (meas) {
        scans.back().z.push_back(&m[j++]);
      } else {
        ++k;
      }
    }
  }
  const double last_t = scans.empty() ? t0 : std::max(t0, scans.back().t);
  std::size_t i = 0;
  double t = t0;
  auto advance = [&](double to) {  // predict from t to `to` with the command of line i
    if (!(to > t)) return;
    const double dt = to - t;
    const OdomEvent& u = o[i];
    RunInput in;
    in.v_mps = u.v;
    in.w_radps = u.w;
    in.dt_s = dt;
    in.t_s = t;
    if (u.sigma_v >= 0) {
      const double end = i + 1 < o.size() ? o[i + 1].t : last_t;
      const double T = end - u.t;
      const double f = (T == dt || !(T > dt)) ? 1.0 : std::sqrt(T / dt);
      in.sigma_v_mps = u.sigma_v * f;
      in.sigma_w_radps = u.sigma_w * f;
    } else {
      if (!(noise.sigma_v_mps > 0 && noise.sigma_w_radps > 0)) {
        throw std::runtime_error(
            "odom line at t = " + fmt(u.t) +
            " has no sigma_v, sigma_w and none is given (--sigma-v, --sigma-w, or --noise-from-data)");
      }
      const double k = 1.0 / std::sqrt(std::max(dt, 1e-6));
      in.sigma_v_mps = noise.sigma_v_mps * k;
      in.sigma_w_radps = noise.sigma_w_radps * k;
    }
    inputs_.push_back(std::move(in));
    t = to;
  };
  const Eigen::Matrix2d R_const =
      Eigen::Vector2d(noise.sigma_range_m * noise.sigma_range_m, noise.sigma_bearing_rad * noise.sigma_bearing_rad)
          .asDiagonal();
  const std::map<std::string, int> index = log.label_indices();
  // Pose increments: each applied whole, in time order, before the scans at or after its time.
  std::size_t d = 0;
  double t_inc = t0;
  auto increment = [&]() {
    const OdomDeltaEvent& u = inc[d++];
    RunInput in;
    in.increment = true;
    in.dx_m = u.dx;
    in.dy_m = u.dy;
    in.dtheta_rad = u.dtheta;
    in.t_s = u.t;
    in.dt_s = u.t - t_inc;
    if (u.has_cov) {
      in.increment_cov = u.covariance();
    } else if (in.dt_s == 0) {  // the first line: the start, no time for noise to act
      in.increment_cov.setZero();
    } else if (noise.sigma_v_mps > 0 && noise.sigma_w_radps > 0) {
      in.increment_cov = Eigen::Vector3d(noise.sigma_v_mps * noise.sigma_v_mps * in.dt_s, 0,
                                         noise.sigma_w_radps * noise.sigma_w_radps * in.dt_s)
                             .asDiagonal();
    } else {
      throw std::runtime_error("odom_delta line at t = " + fmt(u.t) +
                               " has no covariance and none is given (--sigma-v, --sigma-w)");
    }
    t_inc = u.t;
    inputs_.push_back(std::move(in));
  };
  for (const ScanAt& scan : scans) {
    if (scan.t < t) continue;  // before the first odom line
    if (inc.empty()) {
      while (i + 1 < o.size() && o[i + 1].t <= scan.t) {
        advance(o[i + 1].t);
        ++i;
      }
      advance(scan.t);
    } else {
      while (d < inc.size() && inc[d].t <= scan.t) increment();
    }
    RunInput in;
    in.scan = true;
    for (const MeasEvent* z : scan.z) {
      const auto it = index.find(z->label);
      SimObservation so{Eigen::Vector2d(z->range, z->bearing), it == index.end() ? -1 : it->second, R_const};
      if (z->sigma_range > 0) {
        so.R = z->R();
      } else if (!(noise.sigma_range_m > 0 && noise.sigma_bearing_rad > 0)) {
        throw std::runtime_error("meas line at t = " + fmt(z->t) +
                                 " has no sigma_range, sigma_bearing and none is given (--sigma-range, "
                                 "--sigma-bearing, or --noise-from-data)");
      }
      in.observations.push_back(so);
    }
    mrclam::PoseSample pt{};
    in.have_truth = !log.truth.empty() && mrclam::interpolate_truth(log.truth, scan.t, pt);
    in.true_pose = Pose2<double>{pt.x, pt.y, pt.theta};
    in.t_s = scan.t;
    inputs_.push_back(std::move(in));
  }
  while (d < inc.size()) increment();  // the motion after the last scan (the trace's end)
}

EventLog mrclam_to_log(const mrclam::Dataset& ds, const mrclam::RobotLog& robot, const MrclamModel& model,
                       bool drop_other_robots) {
  MrclamSource src(ds, robot, model, drop_other_robots);
  EventLog log;
  log.meta["min_range_m"] = src.sensor.min_range_m;
  log.meta["max_range_m"] = src.sensor.max_range_m;
  log.meta["fov_rad"] = src.sensor.fov_rad;
  log.meta["sigma_bearing_rad"] = src.sensor.sigma_bearing_rad;
  log.meta["scan_tolerance_s"] = 0;
  log.meta["start_x_m"] = src.x0.x;
  log.meta["start_y_m"] = src.x0.y;
  log.meta["start_theta_rad"] = src.x0.theta;
  log.meta["start_var"] = src.P0(0, 0);
  for (const mrclam::Landmark& l : ds.landmarks) log.landmarks.push_back({std::to_string(l.subject), l.x, l.y});
  double first = INFINITY, last = -INFINITY;
  for (const RunInput& in : src.inputs()) {
    first = std::min(first, in.t_s);
    last = std::max(last, in.t_s + (in.scan ? 0.0 : in.dt_s));
    if (!in.scan) {
      log.odometry.push_back({in.t_s, in.v_mps, in.w_radps, in.sigma_v_mps, in.sigma_w_radps});
      continue;
    }
    if (in.observations.empty()) log.empty_scans.push_back(in.t_s);
    for (const SimObservation& z : in.observations) {
      const std::string label = z.truth >= 0 ? std::to_string(ds.landmarks[static_cast<std::size_t>(z.truth)].subject)
                                             : std::string(kClutterLabel);
      if (z.R(0, 1) != 0 || z.R(1, 0) != 0) throw std::runtime_error("mrclam_to_log: R is not diagonal");
      log.measurements.push_back({in.t_s, z.z(0), z.z(1), label, std::sqrt(z.R(0, 0)), std::sqrt(z.R(1, 1))});
    }
  }
  // The truth samples that bracket the replayed stretch (interpolation needs the neighbours).
  for (std::size_t k = 0; k < robot.truth.size(); ++k) {
    const bool before = k + 1 < robot.truth.size() && robot.truth[k + 1].t < first;
    const bool after = k > 0 && robot.truth[k - 1].t > last;
    if (!before && !after) log.truth.push_back(robot.truth[k]);
  }
  return log;
}

EventLog mrclam_raw_log(const mrclam::Dataset& ds, const mrclam::RobotLog& robot) {
  EventLog log;
  log.meta["min_range_m"] = 0.9;  // mrclam_sensor
  log.meta["max_range_m"] = 9.3;
  log.meta["fov_rad"] = 1.2;
  log.meta["scan_tolerance_s"] = mrclam::kScanTolerance_s;
  for (const mrclam::Landmark& l : ds.landmarks) log.landmarks.push_back({std::to_string(l.subject), l.x, l.y});
  for (const mrclam::OdometrySample& o : robot.odometry) log.odometry.push_back({o.t, o.v, o.w});
  for (const mrclam::Scan& s : robot.scans)
    for (const mrclam::Measurement& m : s.z)
      log.measurements.push_back({m.t, m.range, m.bearing,
                                  ds.is_landmark(m.subject) ? std::to_string(m.subject) : std::string(kClutterLabel)});
  log.truth = robot.truth;
  return log;
}

mrclam::RobotLog truncate(const mrclam::RobotLog& log, double seconds) {
  if (log.odometry.empty()) return log;
  const double end = log.odometry.front().t + seconds;
  mrclam::RobotLog r;
  r.robot = log.robot;
  for (const auto& o : log.odometry)
    if (o.t <= end) r.odometry.push_back(o);
  for (const auto& s : log.scans)
    if (s.t <= end) r.scans.push_back(s);
  for (const auto& p : log.truth)
    if (p.t <= end + 1.0) r.truth.push_back(p);
  return r;
}

std::vector<int> landmark_groups(const std::vector<Eigen::Vector2d>& l, double radius_m) {
  const std::size_t n = l.size();
  std::vector<int> g(n);
  for (std::size_t a = 0; a < n; ++a) g[a] = static_cast<int>(a);
  for (bool changed = true; changed;) {  // connected components: merge until stable (<= n passes)
    changed = false;
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = 0; b < n; ++b)
        if ((l[a] - l[b]).norm() <= radius_m && g[b] > g[a]) {
          g[b] = g[a];
          changed = true;
        }
  }
  return g;
}

std::vector<Eigen::Vector2d> landmark_positions(const EventLog& log) {
  std::vector<Eigen::Vector2d> p;
  for (const LandmarkEvent& l : log.landmarks) p.emplace_back(l.x, l.y);
  return p;
}

}  // namespace geojcbb::host::replay
