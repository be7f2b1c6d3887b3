#include "geojcbb_host/sim.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "geojcbb/ekf/motion.hpp"

namespace geojcbb::host {

namespace {
std::vector<Eigen::Vector2d> points(const nlohmann::json& a, const std::string& what) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : a) {
    if (!p.is_array() || p.size() != 2) throw std::runtime_error(what + ": expected [x, y] pairs");
    out.emplace_back(p[0].get<double>(), p[1].get<double>());
  }
  return out;
}

// Landmarks: an explicit list, {"random": {"count", "min_x", "max_x", "min_y", "max_y",
// "min_separation_m", "seed"}}, or {"grid": {"min_x", "max_x", "min_y", "max_y", "spacing_m"}} (a
// regular lattice, every landmark alike; optional "keep_out": [[min_x, max_x, min_y, max_y], ...]
// rectangles left empty).
std::vector<Eigen::Vector2d> landmarks(const nlohmann::json& j) {
  if (j.is_array()) return points(j, "landmarks");
  if (j.contains("grid")) {
    const auto& g = j.at("grid");
    const double x0 = g.at("min_x").get<double>(), x1 = g.at("max_x").get<double>();
    const double y0 = g.at("min_y").get<double>(), y1 = g.at("max_y").get<double>();
    const double step = g.at("spacing_m").get<double>();
    if (!(step > 0) || !(x1 >= x0) || !(y1 >= y0)) throw std::runtime_error("landmarks.grid: bad extent or spacing");
    std::vector<std::array<double, 4>> out_rects;
    for (const auto& r : g.value("keep_out", nlohmann::json::array())) {
      if (!r.is_array() || r.size() != 4)
        throw std::runtime_error("landmarks.grid.keep_out: [min_x, max_x, min_y, max_y]");
      out_rects.push_back({r[0].get<double>(), r[1].get<double>(), r[2].get<double>(), r[3].get<double>()});
    }
    std::vector<Eigen::Vector2d> out;
    for (double x = x0; x <= x1 + 1e-9; x += step) {
      for (double y = y0; y <= y1 + 1e-9; y += step) {
        const bool kept_out = std::any_of(out_rects.begin(), out_rects.end(), [&](const std::array<double, 4>& r) {
          return x >= r[0] && x <= r[1] && y >= r[2] && y <= r[3];
        });
        if (!kept_out) out.emplace_back(x, y);
      }
    }
    return out;
  }
  const auto& r = j.at("random");
  std::mt19937_64 rng(r.value("seed", 1ULL));
  std::uniform_real_distribution<double> ux(r.at("min_x").get<double>(), r.at("max_x").get<double>());
  std::uniform_real_distribution<double> uy(r.at("min_y").get<double>(), r.at("max_y").get<double>());
  const int n = r.at("count").get<int>();
  const double sep = r.value("min_separation_m", 0.0);
  std::vector<Eigen::Vector2d> out;
  for (int tries = 0; static_cast<int>(out.size()) < n && tries < 1000 * n; ++tries) {
    const Eigen::Vector2d l(ux(rng), uy(rng));
    if (std::all_of(out.begin(), out.end(), [&](const Eigen::Vector2d& o) { return (o - l).norm() >= sep; })) {
      out.push_back(l);
    }
  }
  return out;
}
// Movers: [{"index", "vx_mps", "vy_mps", "period_s"} (out and back) or {"index", "legs": [[x, y,
// speed_mps, dwell_s], ...]} (walk and stand)], each landmark at most once.
std::vector<Scenario::Mover> movers(const nlohmann::json& a, std::size_t landmarks) {
  std::vector<Scenario::Mover> out;
  std::vector<bool> taken(landmarks, false);
  for (const auto& m : a) {
    Scenario::Mover mv;
    mv.index = m.at("index").get<int>();
    if (mv.index < 0 || mv.index >= static_cast<int>(landmarks) || taken[static_cast<std::size_t>(mv.index)]) {
      throw std::runtime_error("movers: an index is out of range or taken twice");
    }
    taken[static_cast<std::size_t>(mv.index)] = true;
    for (const auto& l : m.value("legs", nlohmann::json::array())) {
      if (!l.is_array() || l.size() != 4) throw std::runtime_error("movers.legs: expected [x, y, speed_mps, dwell_s]");
      Scenario::Mover::Leg leg;
      leg.to = Eigen::Vector2d(l[0].get<double>(), l[1].get<double>());
      leg.speed_mps = l[2].get<double>();
      leg.dwell_s = l[3].get<double>();
      if (!leg.to.allFinite() || !(leg.speed_mps > 0) || !(leg.dwell_s >= 0) || !std::isfinite(leg.dwell_s)) {
        throw std::runtime_error("movers.legs: a speed or dwell is out of range");
      }
      mv.legs.push_back(leg);
    }
    if (mv.legs.empty()) {
      mv.v = Eigen::Vector2d(m.value("vx_mps", 0.0), m.value("vy_mps", 0.0));
      mv.period_s = m.at("period_s").get<double>();
      if (!mv.v.allFinite() || !(mv.period_s > 0)) throw std::runtime_error("movers: a period is out of range");
    }
    out.push_back(mv);
  }
  return out;
}

// "detection": {"model": "beams", "beam_deg", "p_by_beams"} with "landmark_diameters_m" (a number for
// every landmark, or one per landmark); "model": "constant" (the default) keeps detection_probability.
void detection(const nlohmann::json& j, Scenario& s) {
  if (!j.contains("detection")) return;
  const auto& d = j.at("detection");
  const std::string model = d.value("model", std::string("constant"));
  if (model == "constant") return;
  if (model != "beams") throw std::runtime_error("detection.model: \"constant\" or \"beams\"");
  s.detection_by_beams = true;
  s.beam_rad = d.value("beam_deg", s.beam_rad * 180 / kPi<double>) * kPi<double> / 180;
  s.p_by_beams = d.value("p_by_beams", s.p_by_beams);
  const auto& dia = j.at("landmark_diameters_m");
  s.diameters_m =
      dia.is_number() ? std::vector<double>(s.landmarks.size(), dia.get<double>()) : dia.get<std::vector<double>>();
  const auto bad = [](double v) { return !(v >= 0 && v <= 1); };
  if (!(s.beam_rad > 0) || s.p_by_beams.empty() || std::any_of(s.p_by_beams.begin(), s.p_by_beams.end(), bad) ||
      s.diameters_m.size() != s.landmarks.size() ||
      std::any_of(s.diameters_m.begin(), s.diameters_m.end(), [](double v) { return !(v > 0) || !std::isfinite(v); })) {
    throw std::runtime_error("detection: beam_deg, p_by_beams or landmark_diameters_m out of range");
  }
}
}  // namespace

Scenario load_scenario(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  Scenario s;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    s.name = j.value("name", path);
    s.landmarks = landmarks(j.at("landmarks"));
    s.waypoints = points(j.at("waypoints"), "waypoints");
    if (s.waypoints.size() < 2) throw std::runtime_error("waypoints: need at least two");
    s.laps = j.value("laps", s.laps);
    s.duration_s = j.value("duration_s", s.duration_s);
    s.speed_mps = j.value("speed_mps", s.speed_mps);
    s.max_turn_rate_radps = j.value("max_turn_rate_radps", s.max_turn_rate_radps);
    s.turn_gain = j.value("turn_gain", s.turn_gain);
    s.waypoint_radius_m = j.value("waypoint_radius_m", s.waypoint_radius_m);
    s.dt_s = j.value("dt_s", s.dt_s);
    s.observe_every = j.value("observe_every", s.observe_every);
    s.sigma_v_mps = j.value("sigma_v_mps", s.sigma_v_mps);
    s.sigma_w_radps = j.value("sigma_w_radps", s.sigma_w_radps);
    s.max_range_m = j.value("max_range_m", s.max_range_m);
    s.min_range_m = j.value("min_range_m", s.min_range_m);
    s.fov_rad = j.value("fov_deg", s.fov_rad * 180 / kPi<double>) * kPi<double> / 180;
    s.sigma_range_m = j.value("sigma_range_m", s.sigma_range_m);
    s.sigma_bearing_rad = j.value("sigma_bearing_deg", s.sigma_bearing_rad * 180 / kPi<double>) * kPi<double> / 180;
    s.detection_probability = j.value("detection_probability", s.detection_probability);
    s.clutter_per_scan = j.value("clutter_per_scan", s.clutter_per_scan);
    s.noise_scale = j.value("noise_scale", s.noise_scale);
    s.odometry_increments = j.value("odometry_increments", s.odometry_increments);
    if (j.contains("sensor_mount")) {  // {"x_m", "y_m", "theta_deg"}
      const auto& m = j.at("sensor_mount");
      s.sensor_x_m = m.value("x_m", 0.0);
      s.sensor_y_m = m.value("y_m", 0.0);
      s.sensor_theta_rad = m.value("theta_deg", 0.0) * kPi<double> / 180;
    }
    if (j.contains("kidnap")) {  // {"t_s", "dx_m", "dy_m", "dtheta_deg", "sigma_xy_m", "sigma_theta_deg"}
      const auto& k = j.at("kidnap");
      s.kidnap_t_s = k.at("t_s").get<double>();
      s.kidnap_move =
          Eigen::Vector3d(k.value("dx_m", 0.0), k.value("dy_m", 0.0), k.value("dtheta_deg", 0.0) * kPi<double> / 180);
      s.kidnap_sigma_xy_m = k.value("sigma_xy_m", s.kidnap_sigma_xy_m);
      s.kidnap_sigma_theta_rad =
          k.value("sigma_theta_deg", s.kidnap_sigma_theta_rad * 180 / kPi<double>) * kPi<double> / 180;
      s.kidnap_told = k.value("told", true);
    }
    if (j.contains("clutter_burst")) {  // {"t_s", "duration_s", "every_s", "per_scan"}
      const auto& b = j.at("clutter_burst");
      s.burst_t_s = b.at("t_s").get<double>();
      s.burst_duration_s = b.at("duration_s").get<double>();
      s.burst_every_s = b.value("every_s", 0.0);
      s.burst_per_scan = b.at("per_scan").get<double>();
    }
    s.movers = movers(j.value("movers", nlohmann::json::array()), s.landmarks.size());
    detection(j, s);
  } catch (const std::exception& e) {  // JSON errors and our own field checks, with the path
    throw std::runtime_error(path + ": " + e.what());
  }
  if (!(s.dt_s > 0) || s.observe_every < 1 || s.laps < 1 || !(s.duration_s >= 0) || !(s.speed_mps > 0) ||
      !(s.max_range_m > 0) || !(s.min_range_m >= 0 && s.min_range_m < s.max_range_m) || s.detection_probability < 0 ||
      s.detection_probability > 1 || s.clutter_per_scan < 0 || s.noise_scale < 0 || !s.kidnap_move.allFinite() ||
      !(s.kidnap_sigma_xy_m > 0) || !(s.kidnap_sigma_theta_rad > 0) || !(s.burst_t_s >= 0) ||
      !(s.burst_duration_s >= 0) || !(s.burst_every_s >= 0) || !(s.burst_per_scan >= 0)) {
    throw std::runtime_error(path + ": a parameter is out of range");
  }
  return s;
}

namespace {
// Where a walk-and-stand mover is at t: leg after leg from `from`, each walked at its speed, then
// stood for its dwell; after the last, standing.
Eigen::Vector2d walk_at(const Scenario::Mover& m, Eigen::Vector2d from, double t_s) {
  for (const Scenario::Mover::Leg& l : m.legs) {  // <= legs
    const double walk_s = (l.to - from).norm() / l.speed_mps;
    if (t_s < walk_s) return from + (l.to - from) * (t_s / walk_s);
    t_s -= walk_s + l.dwell_s;
    from = l.to;
    if (t_s < 0) return from;
  }
  return from;
}
}  // namespace

Eigen::Vector2d landmark_at(const Scenario& s, std::size_t j, double t_s) {
  const int k = mover_of(s, j);
  if (k < 0) return s.landmarks[j];
  const Scenario::Mover& m = s.movers[static_cast<std::size_t>(k)];
  if (!m.legs.empty()) return walk_at(m, s.landmarks[j], t_s);
  const double phase = std::fmod(t_s, m.period_s) / m.period_s;  // out for the first half, back for the second
  return s.landmarks[j] + m.v * (m.period_s * (phase < 0.5 ? phase : 1 - phase));
}

int mover_of(const Scenario& s, std::size_t j) {
  for (std::size_t k = 0; k < s.movers.size(); ++k)
    if (static_cast<std::size_t>(s.movers[k].index) == j) return static_cast<int>(k);
  return -1;
}

double detection_probability_at(const Scenario& s, std::size_t j, double range_m) {
  if (!s.detection_by_beams) return s.detection_probability;
  const double n = 2 * std::atan(s.diameters_m[j] / (2 * range_m)) / s.beam_rad;  // beams covered
  const std::vector<double>& p = s.p_by_beams;
  const auto last = static_cast<double>(p.size() - 1);
  if (n >= last) return p.back();
  const auto k = static_cast<std::size_t>(n);
  const double f = n - static_cast<double>(k);
  return (1 - f) * p[k] + f * p[k + 1];
}

Simulator::Simulator(const Scenario& s, std::uint64_t seed) : s_(s), rng_(seed) {
  const Eigen::Vector2d d = s_.waypoints[1] - s_.waypoints[0];
  x_ = {s_.waypoints[0].x(), s_.waypoints[0].y(), std::atan2(d.y(), d.x())};
  for (std::size_t j = 0; j < s_.landmarks.size(); ++j) mover_of_.push_back(mover_of(s_, j));
}

bool Simulator::step(SimStep& out) {
  if (lap_ >= s_.laps) return false;
  if (s_.duration_s > 0 && static_cast<double>(k_) * s_.dt_s >= s_.duration_s) return false;
  std::normal_distribution<double> g(0, 1);  // two draws: no value cached into observe_landmarks' own
  // Steer toward the current waypoint.
  const Eigen::Vector2d to = s_.waypoints[target_] - Eigen::Vector2d(x_.x, x_.y);
  const double err = wrap_angle(std::atan2(to.y(), to.x()) - x_.theta);
  const double w = std::clamp(s_.turn_gain * err, -s_.max_turn_rate_radps, s_.max_turn_rate_radps);
  out.kidnapped = false;
  if (s_.kidnap_t_s > 0 && !kidnap_done_ && static_cast<double>(k_ + 1) * s_.dt_s >= s_.kidnap_t_s) {
    kidnap_done_ = true;
    out.kidnapped = true;
    x_ = {x_.x + s_.kidnap_move.x(), x_.y + s_.kidnap_move.y(), wrap_angle(x_.theta + s_.kidnap_move.z())};
  }
  x_ = ekf::move(x_, ekf::Odometry<double>{s_.speed_mps, w, s_.dt_s, 0, 0});
  if ((s_.waypoints[target_] - Eigen::Vector2d(x_.x, x_.y)).norm() < s_.waypoint_radius_m) {
    if (target_ == 0) ++lap_;  // back at the start: a lap is done
    target_ = (target_ + 1) % s_.waypoints.size();
  }
  ++k_;
  out.t_s = static_cast<double>(k_) * s_.dt_s;
  out.true_pose = x_;
  const double k = s_.noise_scale;
  out.v_mps = s_.speed_mps + k * s_.sigma_v_mps * g(rng_);
  out.w_radps = w + k * s_.sigma_w_radps * g(rng_);
  out.scan = k_ % s_.observe_every == 0;
  out.observations.clear();
  if (!out.scan) return true;
  const Eigen::Matrix2d R =
      Eigen::Vector2d(s_.sigma_range_m * s_.sigma_range_m, s_.sigma_bearing_rad * s_.sigma_bearing_rad).asDiagonal();
  observe_landmarks(out, R);
  add_clutter(out, R);
  std::shuffle(out.observations.begin(), out.observations.end(), rng_);
  return true;
}

void Simulator::observe_landmarks(SimStep& out, const Eigen::Matrix2d& R) {
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> u(0, 1);
  const double k = s_.noise_scale;
  for (std::size_t j = 0; j < s_.landmarks.size(); ++j) {
    const Vec2<double> z = observe(x_, Mount<double>{s_.sensor_x_m, s_.sensor_y_m, s_.sensor_theta_rad},
                                   Vec2<double>(landmark_at(s_, j, out.t_s)));
    if (z.x() > s_.max_range_m || z.x() < s_.min_range_m || std::abs(z.y()) > 0.5 * s_.fov_rad) continue;
    if (u(rng_) >= detection_probability_at(s_, j, z.x())) continue;
    const int mover = mover_of_[j];  // a mover is not a landmark: labelled as its own, truth -1
    out.observations.push_back({Eigen::Vector2d(z.x() + k * s_.sigma_range_m * g(rng_),
                                                wrap_angle(z.y() + k * s_.sigma_bearing_rad * g(rng_))),
                                mover < 0 ? static_cast<int>(j) : -1, R, mover});
  }
}

void Simulator::add_clutter(SimStep& out, const Eigen::Matrix2d& R) {
  std::uniform_real_distribution<double> u(0, 1);
  std::poisson_distribution<int> clutter(s_.clutter_per_scan);
  for (int c = clutter(rng_); c > 0; --c) {
    // Uniform over the annulus sector between min and max range.
    const double r0 = s_.min_range_m, r1 = s_.max_range_m;
    const double r = std::sqrt(r0 * r0 + (r1 * r1 - r0 * r0) * u(rng_));
    out.observations.push_back({Eigen::Vector2d(r, (u(rng_) - 0.5) * s_.fov_rad), -1, R});
  }
  const double since = out.t_s - s_.burst_t_s;
  if (!(s_.burst_per_scan > 0 && since >= 0)) return;
  const long burst = s_.burst_every_s > 0 ? static_cast<long>(since / s_.burst_every_s) : 0;
  const double into = s_.burst_every_s > 0 ? since - static_cast<double>(burst) * s_.burst_every_s : since;
  if (into >= s_.burst_duration_s) return;
  if (burst != burst_) {  // a new burst: its sector
    burst_ = burst;
    burst_bearing_ = (u(rng_) - 0.5) * (s_.fov_rad - 30 * kPi<double> / 180);
  }
  std::poisson_distribution<int> more(s_.burst_per_scan);
  for (int c = more(rng_); c > 0; --c) {
    const double r = s_.min_range_m + (s_.max_range_m - s_.min_range_m) * u(rng_);
    const double b = burst_bearing_ + (u(rng_) - 0.5) * 30 * kPi<double> / 180;
    out.observations.push_back({Eigen::Vector2d(r, b), -1, R});
  }
}

}  // namespace geojcbb::host
