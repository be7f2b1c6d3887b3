#include "geojcbb_host/gps.hpp"

#include <algorithm>
#include <cmath>

namespace geojcbb::host {

Eigen::Vector2d antenna_at(const Pose2<double>& x, const GpsOptions& o) {
  return {x.x + std::cos(x.theta) * o.antenna_x_m - std::sin(x.theta) * o.antenna_y_m,
          x.y + std::sin(x.theta) * o.antenna_x_m + std::cos(x.theta) * o.antenna_y_m};
}

std::vector<replay::GpsEvent> screen_gps(const std::vector<replay::GpsEvent>& fixes, const GpsOptions& o,
                                         GpsScore& counts) {
  std::vector<replay::GpsEvent> kept;
  counts.fixes = static_cast<int>(fixes.size());
  for (std::size_t k = 0; k < fixes.size(); ++k) {
    if (k == 0) {  // nothing to check it against; the first fix of a log is where the run starts
      kept.push_back(fixes[k]);
      continue;
    }
    const replay::GpsEvent& a = fixes[k - 1];
    const replay::GpsEvent& b = fixes[k];
    if (b.t - a.t > o.max_gap_s) {
      ++counts.after_gap;
    } else if (std::hypot(b.x - a.x, b.y - a.y) > o.max_jump_m) {
      ++counts.jumps;
    } else {
      kept.push_back(b);
    }
  }
  return kept;
}

GpsScore score_gps(const std::vector<TracePoint>& trace, const std::vector<replay::GpsEvent>& fixes,
                   const GpsOptions& o) {
  GpsScore s;
  const std::vector<replay::GpsEvent> kept = screen_gps(fixes, o, s);
  double sum2 = 0;
  for (const replay::GpsEvent& g : kept) {
    // The first estimate at or after the fix, and the one before it.
    const auto it =
        std::lower_bound(trace.begin(), trace.end(), g.t, [](const TracePoint& p, double t) { return p.t_s < t; });
    if (it == trace.end() || (it == trace.begin() && it->t_s != g.t)) {
      ++s.unmatched;
      continue;
    }
    const TracePoint& b = *it;
    const TracePoint& a = it == trace.begin() ? b : *(it - 1);
    if (b.t_s - a.t_s > o.max_dt_s) {
      ++s.unmatched;
      continue;
    }
    const double f = b.t_s > a.t_s ? (g.t - a.t_s) / (b.t_s - a.t_s) : 0.0;
    const Pose2<double> x{a.pose.x + f * (b.pose.x - a.pose.x), a.pose.y + f * (b.pose.y - a.pose.y),
                          a.pose.theta + f * wrap_angle(b.pose.theta - a.pose.theta)};
    const double e = (antenna_at(x, o) - Eigen::Vector2d(g.x, g.y)).norm();
    sum2 += e * e;
    if (e > s.max_m) {
      s.max_m = e;
      s.max_at_s = g.t;
    }
    s.t.push_back(g.t);
    s.error_m.push_back(e);
    ++s.used;
  }
  s.rmse_m = s.used > 0 ? std::sqrt(sum2 / s.used) : NAN;
  return s;
}

}  // namespace geojcbb::host
