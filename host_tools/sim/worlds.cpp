#include "geojcbb_host/worlds.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace geojcbb::host {

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

// The families; the ranges are the ones draw_world uses (keep them in step).
const std::vector<WorldFamily> kFamilies{
    {"rows", "a lattice of look-alike landmarks (spacing 4-8 m, 40-60 m square), driven around twice just outside it"},
    {"corridor",
     "landmark pairs every 4-8 m on both walls (5-7 m from the centre) of a 60-120 m corridor, driven out and back "
     "twice at 1.5 m/s"},
    {"drift_loop",
     "a square loop of side 80-240 m, landmarks only within 12 m of the path (one per 8 m), odometry noise 2-4x the "
     "defaults (v and w drawn apart), two laps"},
    {"blind",
     "a 100 x 70 m loop through a random field (one landmark per 50-80 m^2) with no landmark within 25 m of a 30-80 m "
     "stretch of it, two laps"},
    {"clutter", "60 landmarks in a 60 m square, 3-10 clutter returns per scan, two laps"},
    {"kidnap_reset",
     "60 landmarks in a 60 m square; at 30-60 s the robot is carried 5-20 m and turned 30-180 degrees, and the pose "
     "covariance is reset to 15 m / 180 degrees, two laps"},
    {"kidnap_silent",
     "60 landmarks in a 60 m square; at 30-60 s the robot is carried 5-20 m and turned 30-180 degrees, and the filter "
     "is not told, two laps"},
    {"clutter_burst",
     "60 landmarks in a 60 m square; from 10-30 s on, for 3-8 s of every 20-40 s, 10-25 more clutter returns per scan "
     "within a 30-degree sector, two laps"},
    {"movers",
     "60 landmarks in a 60 m square, 4-10 of them moving out and back at 0.05-0.3 m/s over a period of 20-80 s, and "
     "4-8 more walking like people: legs at 0.05-1.5 m/s, standing 0-20 s after each; a wanderer walks 2-20 s in a "
     "random direction, a crosser (the first, then half the others) walks across the robot's path to a point 3-8 m "
     "beyond it, leg after leg; two laps"},
    {"small", "15-30 landmarks in a 40 m square, two laps"},
    {"far",
     "40-60 trees in a 160-220 m square (at least 10 m apart), diameters 0.2-1.0 m, seen by a laser of range 40-50 m "
     "with 0.5-degree beams: p_D 0, 0.2, 0.5, 0.8, 0.9 at 0, 1, 2, 3, 4+ beams covered (2 atan(d / 2r) / 0.5 "
     "degrees), a square path of half the square's side, two laps"},
    {"large", "150-300 landmarks at one per 64 m^2 (a 100-140 m square), two laps"},
};

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL;
  for (const char c : s) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  return h;
}

struct Draw {
  std::mt19937_64 rng;
  double u(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
  int i(int a, int b) { return std::uniform_int_distribution<int>(a, b)(rng); }
};

// The common sensor and robot (the papers' platform, env2's values).
Scenario base(const std::string& family, std::uint64_t seed) {
  Scenario s;
  s.name = "world " + family + " " + std::to_string(seed);
  s.laps = 2;
  s.speed_mps = 3.0;
  s.dt_s = 0.025;
  s.observe_every = 8;
  s.sigma_v_mps = 0.3;
  s.sigma_w_radps = 0.04;
  s.sigma_range_m = 0.1;
  s.sigma_bearing_rad = 1.0 * kDeg;
  s.detection_probability = 0.95;
  s.clutter_per_scan = 0.5;
  s.max_turn_rate_radps = 0.6;
  s.turn_gain = 2.0;
  s.waypoint_radius_m = 2.0;
  s.max_range_m = 20.0;
  s.fov_rad = 180 * kDeg;
  return s;
}

// n landmarks uniformly in [x0, x1] x [y0, y1], at least `sep` apart.
std::vector<Eigen::Vector2d> field(Draw& d, int n, double x0, double x1, double y0, double y1, double sep) {
  std::vector<Eigen::Vector2d> out;
  for (int tries = 0; static_cast<int>(out.size()) < n && tries < 1000 * n; ++tries) {
    const Eigen::Vector2d p(d.u(x0, x1), d.u(y0, y1));
    if (std::all_of(out.begin(), out.end(), [&](const Eigen::Vector2d& q) { return (q - p).norm() >= sep; })) {
      out.push_back(p);
    }
  }
  return out;
}

std::vector<Eigen::Vector2d> square(double half) {
  return {{-half, -half}, {half, -half}, {half, half}, {-half, half}};
}

double distance_to_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - p).norm();
}

// The kidnap families' world: 60 landmarks in a 60 m square, carried 5-20 m and turned 30-180
// degrees at 30-60 s.
void kidnap(Draw& d, Scenario& s) {
  s.landmarks = field(d, 60, -30, 30, -30, 30, 4);
  s.waypoints = square(20);
  s.waypoint_radius_m = 6;
  const double dist = d.u(5, 20), dir = d.u(-180, 180) * kDeg;
  s.kidnap_t_s = d.u(30, 60);
  s.kidnap_move =
      Eigen::Vector3d(dist * std::cos(dir), dist * std::sin(dir), d.u(30, 180) * kDeg * (d.u(0, 1) < 0.5 ? -1 : 1));
}

// The people of the movers family walk this long, leg after leg, and then stand (two laps of the
// 40 m square take about 110 s).
constexpr double kWalkHorizon_s = 400;

// The next leg of a person standing at `here`: its speed and the standing after it drawn; a crosser
// walks across one side of the robot's path (from a to along * len) to a point 3-8 m beyond it, near
// where it crossed last (`at`, flipping `side`); a wanderer 2-20 s in a random direction, within
// the field (half: its half side).
struct Walk {
  Eigen::Vector2d a, along, across;
  double len = 0, at = 0, side = 1, half = 0;
  bool crosser = false;
  Scenario::Mover::Leg next(Draw& d, const Eigen::Vector2d& here) {
    Scenario::Mover::Leg l;
    l.speed_mps = d.u(0.05, 1.5);
    l.dwell_s = d.u(0, 20);
    if (crosser) {
      side = -side;
      at = std::clamp(at + d.u(-4, 4), 0.1 * len, 0.9 * len);
      l.to = a + at * along + side * d.u(3, 8) * across;
    } else {
      const double dir = d.u(-180, 180) * kDeg, walk_s = d.u(2, 20);
      l.to = (here + Eigen::Vector2d(std::cos(dir), std::sin(dir)) * (l.speed_mps * walk_s)).cwiseMax(-half);
      l.to = l.to.cwiseMin(half);
    }
    return l;
  }
};

// A person (Walk), walking leg after leg for kWalkHorizon_s from `start` (drawn here: beside the
// path for a crosser, anywhere in the field for a wanderer).
Scenario::Mover person(Draw& d, bool crosser, const std::vector<Eigen::Vector2d>& path, double half,
                       Eigen::Vector2d& start) {
  Walk w;
  w.crosser = crosser;
  w.half = half;
  const int edge = d.i(0, static_cast<int>(path.size()) - 1);
  w.a = path[static_cast<std::size_t>(edge)];
  const Eigen::Vector2d& b = path[(static_cast<std::size_t>(edge) + 1) % path.size()];
  w.len = (b - w.a).norm();
  w.along = (b - w.a) / w.len;
  w.across = Eigen::Vector2d(-w.along.y(), w.along.x());
  w.at = d.u(0.2, 0.8) * w.len;
  w.side = d.u(0, 1) < 0.5 ? -1 : 1;
  start = crosser ? Eigen::Vector2d(w.a + w.at * w.along + w.side * d.u(3, 8) * w.across)
                  : Eigen::Vector2d(d.u(-half, half), d.u(-half, half));
  Scenario::Mover m;
  Eigen::Vector2d here = start;
  for (double t = 0; t < kWalkHorizon_s && m.legs.size() < 1000;) {  // <= 1000 legs
    const Scenario::Mover::Leg l = w.next(d, here);
    t += (l.to - here).norm() / l.speed_mps + l.dwell_s;
    here = l.to;
    m.legs.push_back(l);
  }
  return m;
}

// The movers family: 60 landmarks in a 60 m square; 4-10 go out and back slowly (the landmarks
// 0..n-1: the field's order is random), 4-8 more walk like people (the next ones, moved to where
// each person starts).
void movers(Draw& d, Scenario& s) {
  s.landmarks = field(d, 60, -30, 30, -30, 30, 4);
  s.waypoints = square(20);
  const int n = d.i(4, 10);
  for (int k = 0; k < n; ++k) {
    Scenario::Mover m;
    m.index = k;
    const double speed = d.u(0.05, 0.3), dir = d.u(-180, 180) * kDeg;
    m.v = Eigen::Vector2d(speed * std::cos(dir), speed * std::sin(dir));
    m.period_s = d.u(20, 80);
    s.movers.push_back(m);
  }
  const int people = d.i(4, 8);
  for (int q = 0; q < people && n + q < static_cast<int>(s.landmarks.size()); ++q) {
    const bool crosser = q == 0 || d.u(0, 1) < 0.5;
    Eigen::Vector2d start;
    Scenario::Mover m = person(d, crosser, s.waypoints, 29, start);
    m.index = n + q;
    s.landmarks[static_cast<std::size_t>(m.index)] = start;
    s.movers.push_back(m);
  }
}

// The far family: few trees, most seen beyond 20 m, each detected by the beams it covers.
void far(Draw& d, Scenario& s) {
  const int n = d.i(40, 60);
  const double half = 0.5 * d.u(160, 220);
  s.landmarks = field(d, n, -half, half, -half, half, 10);
  s.waypoints = square(0.5 * half);
  s.max_range_m = d.u(40, 50);
  s.detection_by_beams = true;
  s.beam_rad = 0.5 * kDeg;
  s.p_by_beams = {0.0, 0.2, 0.5, 0.8, 0.9};
  for (std::size_t k = 0; k < s.landmarks.size(); ++k) s.diameters_m.push_back(d.u(0.2, 1.0));
}

}  // namespace

const std::vector<WorldFamily>& world_families() { return kFamilies; }

Scenario draw_world(const std::string& family, std::uint64_t seed) {
  Draw d{std::mt19937_64(seed * 0x9E3779B97F4A7C15ULL ^ fnv1a(family))};
  Scenario s = base(family, seed);
  if (family == "rows") {
    const double sp = d.u(4, 8), half = 0.5 * d.u(40, 60);
    for (double x = -half; x <= half + 1e-9; x += sp)
      for (double y = -half; y <= half + 1e-9; y += sp) s.landmarks.emplace_back(x, y);
    s.waypoints = square(half + 4);
    s.max_range_m = 15;
  } else if (family == "corridor") {
    const double period = d.u(4, 8), length = d.u(60, 120), wall = d.u(5, 7);
    for (double x = 0; x <= length + 1e-9; x += period) {
      s.landmarks.emplace_back(x, -wall);
      s.landmarks.emplace_back(x, wall);
    }
    s.waypoints = {{0, -2}, {length, -2}, {length, 2}, {0, 2}};
    s.speed_mps = 1.5;
    s.max_turn_rate_radps = 1.0;
    s.max_range_m = 15;
  } else if (family == "drift_loop") {
    const double side = d.u(80, 240), half = 0.5 * side;
    s.waypoints = square(half);
    const int n = static_cast<int>(4 * side / 8);
    for (int tries = 0; static_cast<int>(s.landmarks.size()) < n && tries < 1000 * n; ++tries) {
      const int edge = d.i(0, 3);
      const Eigen::Vector2d a = s.waypoints[static_cast<std::size_t>(edge)];
      const Eigen::Vector2d b = s.waypoints[static_cast<std::size_t>((edge + 1) % 4)];
      const Eigen::Vector2d along = (b - a).normalized(), across(-along.y(), along.x());
      const double off = d.u(2, 12) * (d.u(0, 1) < 0.5 ? -1 : 1);
      const Eigen::Vector2d p = a + d.u(0, side) * along + off * across;
      if (std::all_of(s.landmarks.begin(), s.landmarks.end(),
                      [&](const Eigen::Vector2d& q) { return (q - p).norm() >= 3; })) {
        s.landmarks.push_back(p);
      }
    }
    s.sigma_v_mps *= d.u(2, 4);
    s.sigma_w_radps *= d.u(2, 4);
    s.max_range_m = 25;
  } else if (family == "blind") {
    s.waypoints = {{-50, -35}, {50, -35}, {50, 35}, {-50, 35}};
    const double area_per = d.u(50, 80);
    const int n = static_cast<int>(130.0 * 100.0 / area_per);
    std::vector<Eigen::Vector2d> all = field(d, n, -65, 65, -50, 50, 4);
    const int edge = d.i(0, 3);
    const Eigen::Vector2d a = s.waypoints[static_cast<std::size_t>(edge)];
    const Eigen::Vector2d b = s.waypoints[static_cast<std::size_t>((edge + 1) % 4)];
    const double len = (b - a).norm(), gap = std::min(d.u(30, 80), len);
    const double start = d.u(0, len - gap);
    const Eigen::Vector2d g0 = a + (b - a) * (start / len), g1 = a + (b - a) * ((start + gap) / len);
    for (const Eigen::Vector2d& p : all)
      if (distance_to_segment(p, g0, g1) > 25) s.landmarks.push_back(p);
  } else if (family == "clutter") {
    s.landmarks = field(d, 60, -30, 30, -30, 30, 4);
    s.waypoints = square(20);
    s.clutter_per_scan = d.u(3, 10);
  } else if (family == "kidnap_reset") {
    kidnap(d, s);
    s.kidnap_sigma_xy_m = 15;
    s.kidnap_sigma_theta_rad = 180 * kDeg;
  } else if (family == "kidnap_silent") {
    kidnap(d, s);
    s.kidnap_told = false;
  } else if (family == "clutter_burst") {
    s.landmarks = field(d, 60, -30, 30, -30, 30, 4);
    s.waypoints = square(20);
    s.burst_t_s = d.u(10, 30);
    s.burst_duration_s = d.u(3, 8);
    s.burst_every_s = d.u(20, 40);
    s.burst_per_scan = d.u(10, 25);
  } else if (family == "movers") {
    movers(d, s);
  } else if (family == "small") {
    s.landmarks = field(d, d.i(15, 30), -20, 20, -20, 20, 4);
    s.waypoints = square(12);
  } else if (family == "far") {
    far(d, s);
  } else if (family == "large") {
    const int n = d.i(150, 300);
    const double half = 0.5 * std::sqrt(64.0 * n);
    s.landmarks = field(d, n, -half, half, -half, half, 4);
    s.waypoints = square(half - 10);
    s.max_range_m = 25;
  } else {
    std::string names;
    for (const WorldFamily& f : kFamilies) names += std::string(names.empty() ? "" : ", ") + f.name;
    throw std::invalid_argument("unknown world family '" + family + "' (" + names + ")");
  }
  return s;
}

void save_scenario(const Scenario& s, const std::string& path) {
  nlohmann::json j;
  j["name"] = s.name;
  j["laps"] = s.laps;
  if (s.duration_s > 0) j["duration_s"] = s.duration_s;
  j["speed_mps"] = s.speed_mps;
  j["max_turn_rate_radps"] = s.max_turn_rate_radps;
  j["turn_gain"] = s.turn_gain;
  j["waypoint_radius_m"] = s.waypoint_radius_m;
  j["dt_s"] = s.dt_s;
  j["observe_every"] = s.observe_every;
  j["sigma_v_mps"] = s.sigma_v_mps;
  j["sigma_w_radps"] = s.sigma_w_radps;
  j["max_range_m"] = s.max_range_m;
  j["min_range_m"] = s.min_range_m;
  j["fov_deg"] = s.fov_rad / kDeg;
  j["sigma_range_m"] = s.sigma_range_m;
  j["sigma_bearing_deg"] = s.sigma_bearing_rad / kDeg;
  j["detection_probability"] = s.detection_probability;
  j["clutter_per_scan"] = s.clutter_per_scan;
  j["noise_scale"] = s.noise_scale;
  j["odometry_increments"] = s.odometry_increments;
  if (s.sensor_x_m != 0 || s.sensor_y_m != 0 || s.sensor_theta_rad != 0) {
    j["sensor_mount"] = {{"x_m", s.sensor_x_m}, {"y_m", s.sensor_y_m}, {"theta_deg", s.sensor_theta_rad / kDeg}};
  }
  if (s.kidnap_t_s > 0) {
    j["kidnap"] = {{"t_s", s.kidnap_t_s},
                   {"dx_m", s.kidnap_move.x()},
                   {"dy_m", s.kidnap_move.y()},
                   {"dtheta_deg", s.kidnap_move.z() / kDeg},
                   {"sigma_xy_m", s.kidnap_sigma_xy_m},
                   {"sigma_theta_deg", s.kidnap_sigma_theta_rad / kDeg},
                   {"told", s.kidnap_told}};
  }
  if (s.burst_per_scan > 0) {
    j["clutter_burst"] = {{"t_s", s.burst_t_s},
                          {"duration_s", s.burst_duration_s},
                          {"every_s", s.burst_every_s},
                          {"per_scan", s.burst_per_scan}};
  }
  if (!s.movers.empty()) {
    nlohmann::json mv = nlohmann::json::array();
    for (const Scenario::Mover& m : s.movers) {
      if (m.legs.empty()) {
        mv.push_back({{"index", m.index}, {"vx_mps", m.v.x()}, {"vy_mps", m.v.y()}, {"period_s", m.period_s}});
        continue;
      }
      nlohmann::json legs = nlohmann::json::array();
      for (const Scenario::Mover::Leg& l : m.legs) legs.push_back({l.to.x(), l.to.y(), l.speed_mps, l.dwell_s});
      mv.push_back({{"index", m.index}, {"legs", legs}});
    }
    j["movers"] = mv;
  }
  if (s.detection_by_beams) {
    j["detection"] = {{"model", "beams"}, {"beam_deg", s.beam_rad / kDeg}, {"p_by_beams", s.p_by_beams}};
    j["landmark_diameters_m"] = s.diameters_m;
  }
  nlohmann::json lm = nlohmann::json::array(), wp = nlohmann::json::array();
  for (const Eigen::Vector2d& p : s.landmarks) lm.push_back({p.x(), p.y()});
  for (const Eigen::Vector2d& p : s.waypoints) wp.push_back({p.x(), p.y()});
  j["landmarks"] = lm;
  j["waypoints"] = wp;
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write");
  out << j.dump(1) << '\n';
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace geojcbb::host
