// host_tools/mrclam: the UTIAS MRCLAM reader (each file read whole, then parsed with strtod/strtol:
// about 40 ms for one robot's three files in Release) and the noise estimates against ground
// truth. See mrclam.hpp.
#include "geojcbb_host/mrclam.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <utility>

#ifndef GEOJCBB_MRCLAM_DEFAULT_DIR
#define GEOJCBB_MRCLAM_DEFAULT_DIR "../shared/data/mrclam"
#endif

namespace geojcbb::host::mrclam {

namespace {

constexpr double kPi = 3.14159265358979323846;

// To (-pi, pi].
double wrap(double a) {
  a = std::fmod(a + kPi, 2 * kPi);
  if (a < 0) a += 2 * kPi;
  return a == 0 ? kPi : a - kPi;
}

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Calls on_line(line_number, fields) for every data line of a file, where fields holds the line's
// numbers; `n` numbers are required, those flagged in `integer` must be whole numbers.
class TableReader {
 public:
  TableReader(std::string path, int n, std::vector<bool> integer)
      : path_(std::move(path)), n_(n), integer_(std::move(integer)) {
    std::ifstream in(path_, std::ios::binary);
    if (!in) throw std::runtime_error(path_ + ": cannot open");
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    in.seekg(0, std::ios::beg);
    if (size < 0) throw std::runtime_error(path_ + ": cannot read");
    text_.resize(static_cast<std::size_t>(size));
    if (!in.read(text_.data(), size)) throw std::runtime_error(path_ + ": cannot read");
  }

  template <class F>
  void for_each(F&& on_line) {
    std::vector<double> f(static_cast<std::size_t>(n_));
    const char* p = text_.data();
    const char* const end = p + text_.size();
    for (long line = 1; p < end; ++line) {
      const char* e = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
      if (e == nullptr) e = end;
      const char* q = p;
      while (q < e && is_blank(*q)) ++q;
      if (q < e && *q != '#') {
        parse(q, e, line, f);
        on_line(line, f);
      }
      p = e + 1;
    }
  }

  [[noreturn]] void fail(long line, const std::string& why) const {
    throw std::runtime_error(path_ + ":" + std::to_string(line) + ": " + why);
  }

 private:
  void parse(const char* p, const char* e, long line, std::vector<double>& f) const {
    int k = 0;
    while (true) {
      while (p < e && is_blank(*p)) ++p;
      if (p == e) break;
      if (k == n_) fail(line, "more than " + std::to_string(n_) + " fields");
      // The token starts with a non-blank character, so strtod/strtol cannot run past the line.
      char* stop = nullptr;
      errno = 0;
      bool out_of_int = false;  // the callers convert integer fields to int
      if (integer_[static_cast<std::size_t>(k)]) {
        const long v = std::strtol(p, &stop, 10);
        out_of_int = v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max();
        f[static_cast<std::size_t>(k)] = static_cast<double>(v);
      } else {
        f[static_cast<std::size_t>(k)] = std::strtod(p, &stop);
      }
      if (stop == p || (stop < e && !is_blank(*stop)) || errno == ERANGE || out_of_int ||
          !std::isfinite(f[static_cast<std::size_t>(k)])) {
        const char* t = p;
        while (t < e && !is_blank(*t)) ++t;
        fail(line, "field " + std::to_string(k + 1) + " '" + std::string(p, t) + "' is not " +
                       (integer_[static_cast<std::size_t>(k)] ? "an integer" : "a number"));
      }
      p = stop;
      ++k;
    }
    if (k < n_) fail(line, "expected " + std::to_string(n_) + " fields, found " + std::to_string(k));
  }

  std::string path_;
  int n_;
  std::vector<bool> integer_;
  std::string text_;
};

// Time-stamped rows: calls on_row(line, fields) and checks that column 0 never decreases.
template <class F>
void read_timed(const std::string& path, int n, std::vector<bool> integer, F&& on_row) {
  TableReader r(path, n, std::move(integer));
  double last = -std::numeric_limits<double>::infinity();
  r.for_each([&](long line, const std::vector<double>& f) {
    if (f[0] < last) r.fail(line, "time goes backwards");
    last = f[0];
    on_row(line, f);
  });
}

// The mean of a piecewise-constant signal (each sample's value held until the next) over [a, b].
template <class Get>
double held_mean(const std::vector<OdometrySample>& o, double a, double b, Get get) {
  auto it = std::upper_bound(o.begin(), o.end(), a, [](double t, const OdometrySample& s) { return t < s.t; });
  std::size_t k = it == o.begin() ? 0 : static_cast<std::size_t>(it - o.begin()) - 1;
  double sum = 0, t = a;
  for (; k < o.size() && t < b; ++k) {
    const double next = k + 1 < o.size() ? std::min(o[k + 1].t, b) : b;
    if (next > t) sum += get(o[k]) * (next - t);
    t = std::max(t, next);
  }
  return sum / (b - a);
}

}  // namespace

ResidualStats residual_stats(std::vector<double> x) {
  ResidualStats s;
  if (x.empty()) return s;
  const double n = static_cast<double>(x.size());
  double sum = 0;
  for (double v : x) sum += v;
  s.mean = sum / n;
  double ss = 0;
  for (double v : x) ss += (v - s.mean) * (v - s.mean);
  s.std = x.size() > 1 ? std::sqrt(ss / (n - 1)) : 0;
  const auto median = [](std::vector<double>& v) {
    const std::size_t m = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
    const double hi = v[m];
    if (v.size() % 2 == 1) return hi;
    return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m)));
  };
  const double med = median(x);
  for (double& v : x) v = std::abs(v - med);
  s.robust_std = 1.4826 * median(x);
  return s;
}

int Dataset::subject_of(int barcode) const {
  const auto it = barcode_to_subject.find(barcode);
  return it == barcode_to_subject.end() ? 0 : it->second;
}

bool Dataset::is_landmark(int subject) const { return landmark(subject) != nullptr; }

const Landmark* Dataset::landmark(int subject) const {
  const auto it = std::lower_bound(landmarks.begin(), landmarks.end(), subject,
                                   [](const Landmark& l, int s) { return l.subject < s; });
  return it != landmarks.end() && it->subject == subject ? &*it : nullptr;
}

Dataset load_dataset(const std::string& dir) {
  Dataset ds;
  ds.dir = dir;
  {
    const std::string path = dir + "/Barcodes.dat";
    TableReader r(path, 2, {true, true});
    std::map<int, int> seen_subject;
    r.for_each([&](long line, const std::vector<double>& f) {
      const int subject = static_cast<int>(f[0]), barcode = static_cast<int>(f[1]);
      if (subject < 1) r.fail(line, "subject must be positive");
      if (!ds.barcode_to_subject.emplace(barcode, subject).second) r.fail(line, "barcode listed twice");
      if (!seen_subject.emplace(subject, barcode).second) r.fail(line, "subject listed twice");
    });
  }
  {
    const std::string path = dir + "/Landmark_Groundtruth.dat";
    TableReader r(path, 5, {true, false, false, false, false});
    r.for_each([&](long line, const std::vector<double>& f) {
      const int subject = static_cast<int>(f[0]);
      if (subject <= kRobots) r.fail(line, "subject " + std::to_string(subject) + " is a robot");
      ds.landmarks.push_back({subject, f[1], f[2], f[3], f[4]});
    });
    std::sort(ds.landmarks.begin(), ds.landmarks.end(),
              [](const Landmark& a, const Landmark& b) { return a.subject < b.subject; });
    for (std::size_t i = 1; i < ds.landmarks.size(); ++i) {
      if (ds.landmarks[i].subject == ds.landmarks[i - 1].subject) {
        throw std::runtime_error(path + ": subject " + std::to_string(ds.landmarks[i].subject) + " listed twice");
      }
    }
  }
  return ds;
}

RobotLog load_robot(const Dataset& ds, int robot, double scan_tolerance_s) {
  if (robot < 1 || robot > kRobots) throw std::invalid_argument("mrclam: robot must be 1.." + std::to_string(kRobots));
  RobotLog log;
  log.robot = robot;
  const std::string stem = ds.dir + "/Robot" + std::to_string(robot) + "_";
  log.odometry.reserve(70000);
  read_timed(stem + "Odometry.dat", 3, {false, false, false}, [&](long, const std::vector<double>& f) {
    log.odometry.push_back({f[0], f[1], f[2]});
  });
  log.truth.reserve(70000);
  read_timed(stem + "Groundtruth.dat", 4, {false, false, false, false}, [&](long, const std::vector<double>& f) {
    log.truth.push_back({f[0], f[1], f[2], f[3]});
  });
  read_timed(stem + "Measurement.dat", 4, {false, true, false, false}, [&](long, const std::vector<double>& f) {
    const int barcode = static_cast<int>(f[1]);
    const Measurement m{f[0], f[2], f[3], barcode, ds.subject_of(barcode)};
    if (log.scans.empty() || m.t - log.scans.back().t > scan_tolerance_s) log.scans.push_back({m.t, {}});
    log.scans.back().z.push_back(m);
  });
  return log;
}

bool interpolate_truth(const std::vector<PoseSample>& truth, double t, PoseSample& out) {
  if (truth.empty() || !(t >= truth.front().t) || !(t <= truth.back().t)) return false;
  const auto it =
      std::lower_bound(truth.begin(), truth.end(), t, [](const PoseSample& s, double v) { return s.t < v; });
  if (it->t == t) {
    out = *it;
    out.theta = wrap(out.theta);
    return true;
  }
  const PoseSample& a = *(it - 1);
  const PoseSample& b = *it;
  if (b.t - a.t > kMaxTruthGap_s) return false;
  const double u = (t - a.t) / (b.t - a.t);
  out = {t, a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), wrap(a.theta + u * wrap(b.theta - a.theta))};
  return true;
}

std::string default_data_dir() {
  const char* env = std::getenv("GEOJCBB_MRCLAM_DIR");
  if (env != nullptr && *env != '\0') return env;
  return GEOJCBB_MRCLAM_DEFAULT_DIR;
}

std::string dataset_dir(int number, const std::string& root) {
  return root + "/MRCLAM_Dataset" + std::to_string(number);
}

MeasurementNoise estimate_measurement_noise(const Dataset& ds, const std::vector<RobotLog>& robots) {
  MeasurementNoise n;
  std::vector<double> dr, db;
  for (const RobotLog& log : robots) {
    for (const Scan& s : log.scans) {
      for (const Measurement& m : s.z) {
        const Landmark* l = ds.landmark(m.subject);
        if (l == nullptr) continue;
        PoseSample p;
        if (!interpolate_truth(log.truth, m.t, p)) {
          ++n.skipped;
          continue;
        }
        const double r = std::hypot(l->x - p.x, l->y - p.y);
        const double b = wrap(std::atan2(l->y - p.y, l->x - p.x) - p.theta);
        dr.push_back(m.range - r);
        db.push_back(wrap(m.bearing - b));
        if (std::abs(dr.back()) > kOutlierRange_m || std::abs(db.back()) > kOutlierBearing_rad) ++n.outliers;
      }
    }
  }
  n.count = static_cast<long>(dr.size());
  n.outlier_fraction = n.count > 0 ? static_cast<double>(n.outliers) / static_cast<double>(n.count) : 0;
  n.range = residual_stats(std::move(dr));
  n.bearing = residual_stats(std::move(db));
  return n;
}

OdometryNoise estimate_odometry_noise(const std::vector<RobotLog>& robots, double window_s) {
  if (!(window_s > 0)) throw std::invalid_argument("mrclam: the odometry window must be positive");
  OdometryNoise n;
  n.window_s = window_s;
  std::vector<double> dv, dw;
  for (const RobotLog& log : robots) {
    const auto& o = log.odometry;
    if (o.empty()) continue;
    std::size_t k = 0;  // the first odometry sample after the window's start
    for (double a = o.front().t; a + window_s <= o.back().t; a += window_s) {
      const double b = a + window_s;
      while (k < o.size() && o[k].t <= a) ++k;  // k >= 1: o.front().t <= a
      bool gap = false;  // the sample in effect at a, and every one up to b, is followed soon enough
      for (std::size_t j = k - 1; j + 1 < o.size() && o[j].t < b && !gap; ++j)
        gap = o[j + 1].t - o[j].t > kMaxTruthGap_s;
      PoseSample p0, p1;
      if (gap || !interpolate_truth(log.truth, a, p0) || !interpolate_truth(log.truth, b, p1)) {
        ++n.skipped;
        continue;
      }
      const double dtheta = wrap(p1.theta - p0.theta);
      const double heading = p0.theta + 0.5 * dtheta;
      const double forward = (p1.x - p0.x) * std::cos(heading) + (p1.y - p0.y) * std::sin(heading);
      dv.push_back(held_mean(o, a, b, [](const OdometrySample& s) { return s.v; }) - forward / window_s);
      dw.push_back(held_mean(o, a, b, [](const OdometrySample& s) { return s.w; }) - dtheta / window_s);
    }
  }
  n.windows = static_cast<long>(dv.size());
  n.v = residual_stats(std::move(dv));
  n.w = residual_stats(std::move(dw));
  return n;
}

}  // namespace geojcbb::host::mrclam
