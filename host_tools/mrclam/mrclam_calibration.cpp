// host_tools/mrclam: per-robot calibration of camera and drive (mrclam_calibration.hpp).
#include "geojcbb_host/mrclam_calibration.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace geojcbb::host::mrclam {

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  return v[m];
}

double mad_std(const std::vector<double>& v) { return residual_stats(v).robust_std; }

// Command integrals with each sample held until the next: F(t) = integral of get() from the first
// sample to t. Gaps longer than kMaxTruthGap_s are flagged so windows across them can be skipped.
class HeldIntegral {
 public:
  HeldIntegral(const std::vector<OdometrySample>& o, double (*get)(const OdometrySample&)) : o_(o), get_(get) {
    c_.resize(o.size(), 0.0);
    for (std::size_t k = 1; k < o.size(); ++k) c_[k] = c_[k - 1] + get(o[k - 1]) * (o[k].t - o[k - 1].t);
  }
  double at(double t) const {
    const std::size_t k = index(t);
    return c_[k] + get_(o_[k]) * (t - o_[k].t);
  }
  /// True when [a, b] lies inside the log and no sample interval over it is longer than the gap limit.
  bool covered(double a, double b) const {
    if (a < o_.front().t || b > o_.back().t) return false;
    for (std::size_t k = index(a); k + 1 < o_.size() && o_[k].t < b; ++k) {
      if (o_[k + 1].t - o_[k].t > kMaxTruthGap_s) return false;
    }
    return true;
  }

 private:
  std::size_t index(double t) const {
    const auto it =
        std::upper_bound(o_.begin(), o_.end(), t, [](double v, const OdometrySample& s) { return v < s.t; });
    return it == o_.begin() ? 0 : static_cast<std::size_t>(it - o_.begin()) - 1;
  }
  const std::vector<OdometrySample>& o_;
  double (*get_)(const OdometrySample&);
  std::vector<double> c_;
};

// Least squares y ~ X beta with beta >= 0: every subset of the columns is tried (at most 3 columns,
// 7 subsets), the best feasible fit wins.
Eigen::VectorXd nonnegative_least_squares(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) {
  const int n = static_cast<int>(X.cols());
  Eigen::VectorXd best = Eigen::VectorXd::Zero(n);
  double best_cost = (y).squaredNorm();
  for (int mask = 1; mask < (1 << n); ++mask) {
    std::vector<int> cols;
    for (int c = 0; c < n; ++c)
      if (mask & (1 << c)) cols.push_back(c);
    Eigen::MatrixXd A(X.rows(), static_cast<int>(cols.size()));
    for (std::size_t k = 0; k < cols.size(); ++k) A.col(static_cast<int>(k)) = X.col(cols[k]);
    const Eigen::VectorXd b = A.colPivHouseholderQr().solve(y);
    if ((b.array() < 0).any()) continue;
    const double cost = (A * b - y).squaredNorm();
    if (cost < best_cost) {
      best_cost = cost;
      best.setZero();
      for (std::size_t k = 0; k < cols.size(); ++k) best[cols[k]] = b[static_cast<int>(k)];
    }
  }
  return best;
}

}  // namespace

RobotCalibration calibrate_robot(const Dataset& ds, const RobotLog& log, const CalibrationOptions& opt) {
  RobotCalibration cal;
  cal.robot = log.robot;
  // --- camera -----------------------------------------------------------------------------------
  std::vector<double> rt, br, rr, eb;  // true range, raw bearing, raw range, bearing residual
  for (const Scan& s : log.scans) {
    for (const Measurement& m : s.z) {
      const Landmark* l = ds.landmark(m.subject);
      PoseSample p;
      if (l == nullptr || !interpolate_truth(log.truth, m.t, p)) continue;
      const double r = std::hypot(l->x - p.x, l->y - p.y);
      const double b = wrap_angle(std::atan2(l->y - p.y, l->x - p.x) - p.theta);
      const double e = wrap_angle(m.bearing - b);
      ++cal.measurements;
      if (std::abs(m.range - r) > kOutlierRange_m || std::abs(e) > kOutlierBearing_rad || !(r > 0)) {
        ++cal.outliers;
        continue;
      }
      rt.push_back(r);
      br.push_back(m.bearing);
      rr.push_back(m.range);
      eb.push_back(e);
    }
  }
  if (rt.size() < 100) throw std::runtime_error("calibrate_robot: fewer than 100 landmark measurements");
  const double b0 = median(eb);
  const int n = static_cast<int>(rt.size());
  Eigen::MatrixXd X(n, 3);
  Eigen::VectorXd y(n), w = Eigen::VectorXd::Ones(n);
  for (int i = 0; i < n; ++i) {
    const double b = br[static_cast<std::size_t>(i)] - b0;
    X.row(i) << 1.0, b, b * b;
    y[i] = rr[static_cast<std::size_t>(i)] / rt[static_cast<std::size_t>(i)] - 1.0;
  }
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  std::vector<double> res(static_cast<std::size_t>(n));
  for (int it = 0; it < 10; ++it) {  // Huber IRLS, threshold 1.5 robust sigma
    const Eigen::MatrixXd Xw = w.asDiagonal() * X;
    c = (Xw.transpose() * X).ldlt().solve(Xw.transpose() * y);
    for (int i = 0; i < n; ++i) res[static_cast<std::size_t>(i)] = y[i] - X.row(i).dot(c);
    const double s = std::max(mad_std(res), 1e-6);
    for (int i = 0; i < n; ++i) w[i] = 1.0 / std::max(1.0, std::abs(res[static_cast<std::size_t>(i)]) / (1.5 * s));
  }
  std::vector<double> eb0 = eb;
  for (double& e : eb0) e -= b0;
  cal.sensor.range_rel_bias0 = c[0];
  cal.sensor.range_rel_bias1_per_rad = c[1];
  cal.sensor.range_rel_bias2_per_rad2 = c[2];
  cal.sensor.bearing_bias_rad = b0;
  cal.sensor.sigma_range_m = opt.sigma_range_floor_m;
  cal.sensor.sigma_range_rel = mad_std(res);
  cal.sensor.sigma_bearing_rad = mad_std(eb0);

  // --- drive ------------------------------------------------------------------------------------
  const auto& o = log.odometry;
  if (o.size() < 2) throw std::runtime_error("calibrate_robot: no odometry");
  const HeldIntegral Fv(o, [](const OdometrySample& s) { return s.v; });
  const HeldIntegral Fw(o, [](const OdometrySample& s) { return s.w; });
  const HeldIntegral Fvv(o, [](const OdometrySample& s) { return s.v * s.v; });
  const HeldIntegral Fww(o, [](const OdometrySample& s) { return s.w * s.w; });
  struct Window {
    double dd, dth, cv, cw, vv, ww, T;
  };
  auto windows = [&](double T, double lag) {
    std::vector<Window> out;
    for (double a = o.front().t + lag; a + T <= o.back().t + lag; a += T) {
      const double b = a + T;
      PoseSample p0, p1;
      if (!Fv.covered(a - lag, b - lag) || !interpolate_truth(log.truth, a, p0) ||
          !interpolate_truth(log.truth, b, p1)) {
        continue;
      }
      const double dth = wrap_angle(p1.theta - p0.theta);
      const double h = p0.theta + 0.5 * dth;
      const double dd = (p1.x - p0.x) * std::cos(h) + (p1.y - p0.y) * std::sin(h);
      out.push_back({dd, dth, Fv.at(b - lag) - Fv.at(a - lag), Fw.at(b - lag) - Fw.at(a - lag),
                     Fvv.at(b - lag) - Fvv.at(a - lag), Fww.at(b - lag) - Fww.at(a - lag), T});
    }
    return out;
  };
  double best_cost = std::numeric_limits<double>::infinity();
  for (double lag = 0; lag <= opt.max_latency_s + 1e-9; lag += 0.01) {  // heading over 0.25 s windows
    double cost = 0;
    const std::vector<Window> ws = windows(0.25, lag);
    for (const Window& x : ws) cost += (x.dth - x.cw) * (x.dth - x.cw);
    cost /= static_cast<double>(std::max<std::size_t>(ws.size(), 1));
    if (cost < best_cost) {
      best_cost = cost;
      cal.latency_s = lag;
    }
  }
  const std::vector<Window> ws = windows(opt.fit_window_s, cal.latency_s);
  if (ws.size() < 100) throw std::runtime_error("calibrate_robot: fewer than 100 drive windows");
  cal.windows = static_cast<long>(ws.size());
  double svn = 0, svd = 0, swn = 0, swd = 0;
  for (const Window& x : ws) {
    svn += x.cv * x.dd;
    svd += x.cv * x.cv;
    swn += x.cw * x.dth;
    swd += x.cw * x.cw;
  }
  const double sv = svd > 0 ? svn / svd : 1.0, sw = swd > 0 ? swn / swd : 1.0;
  const int m = static_cast<int>(ws.size());
  Eigen::MatrixXd Xd(m, 2), Xt(m, 3);
  Eigen::VectorXd yd(m), yt(m);
  for (int i = 0; i < m; ++i) {
    const Window& x = ws[static_cast<std::size_t>(i)];
    const double ed = x.dd - sv * x.cv, et = x.dth - sw * x.cw;
    Xd.row(i) << sv * sv * x.vv, x.T;
    yd[i] = ed * ed;
    Xt.row(i) << sw * sw * x.ww, sv * sv * x.vv, x.T;
    yt[i] = et * et;
  }
  const Eigen::VectorXd bd = nonnegative_least_squares(Xd, yd);
  const Eigen::VectorXd bt = nonnegative_least_squares(Xt, yt);
  cal.drive.scale_v = sv;
  cal.drive.scale_w = sw;
  cal.drive.alpha_v_sqrt_s = std::sqrt(bd[0]);
  cal.drive.q_v_m2ps = bd[1];
  cal.drive.alpha_w_sqrt_s = std::sqrt(bt[0]);
  cal.drive.alpha_wv_rad_sqrt_s_pm = std::sqrt(bt[1]);
  cal.drive.q_w_rad2ps = bt[2];
  return cal;
}

std::string describe(const RobotCalibration& c) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "robot %d: camera range x(1 %+.4f %+.4f b %+.3f b^2), bearing bias %+.4f rad, sigma_range %.3f m + "
                "%.4f r, sigma_bearing %.4f rad (%ld measurements, %ld outliers); drive latency %.2f s, scale v %.3f "
                "w %.3f, alpha_v %.3f, q_v %.2e, alpha_w %.3f, alpha_wv %.3f, q_w %.2e (%ld windows)",
                c.robot, c.sensor.range_rel_bias0, c.sensor.range_rel_bias1_per_rad, c.sensor.range_rel_bias2_per_rad2,
                c.sensor.bearing_bias_rad, c.sensor.sigma_range_m, c.sensor.sigma_range_rel, c.sensor.sigma_bearing_rad,
                c.measurements, c.outliers, c.latency_s, c.drive.scale_v, c.drive.scale_w, c.drive.alpha_v_sqrt_s,
                c.drive.q_v_m2ps, c.drive.alpha_w_sqrt_s, c.drive.alpha_wv_rad_sqrt_s_pm, c.drive.q_w_rad2ps,
                c.windows);
  return buf;
}

}  // namespace geojcbb::host::mrclam
