// tests/fuzz: libFuzzer target for associate() and the EKF's public calls (ekf::Slam: reset,
// predict, predict_local, update, augment, add_known_landmark, review) with fuzzed numbers: NaN,
// Inf, huge, tiny, denormal, nearly singular covariances, counts at and over capacity, in float and
// double. Each call gives a Status or a valid answer: on error its outputs (and the filter) are
// byte for byte as before (memcmp of a copy); on kOk the answer is checked (counts, candidate
// indices, ids, mutual exclusion) and the filter stays finite with positive definite pose and
// landmark blocks. Under the fuzz preset ASan and UBSan watch for UB. Violation: __builtin_trap.
// corpus_runner.cpp runs it over corpus_associate/ as a plain test.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

#include <Eigen/Cholesky>

#include "fuzz_bytes.hpp"
#include "geojcbb/associate.hpp"
#include "geojcbb/core/strategy.hpp"
#include "geojcbb/ekf/slam.hpp"

namespace {

using namespace geojcbb;
using FB = Bounds<6, 8, 3, 300, 10>;  // small, so capacities are reached

using fuzz::require;

/// The fuzzer's bytes (fuzz_bytes.hpp) and this target's numbers from them.
struct Input : fuzz::Bytes {
  using Bytes::Bytes;
  /// Mostly near `nominal`; sometimes NaN, Inf, huge, tiny, denormal, raw bits.
  template <typename T>
  T f(T nominal) {
    using L = std::numeric_limits<T>;
    const std::uint8_t s = u8();
    switch (s & 15) {
      case 0: return L::quiet_NaN();
      case 1: return s & 16 ? L::infinity() : -L::infinity();
      case 2: return s & 16 ? L::max() / T(4) : -L::max() / T(4);
      case 3: return L::denorm_min() * T(u8());
      case 4: return s & 16 ? T(0) : -T(0);
      case 5: return L::min() * T(u8());
      case 6: {
        const std::uint64_t bits = u64();
        T v;
        std::memcpy(&v, &bits, sizeof v);
        return v;
      }
      case 7: return -nominal;
      case 8: return nominal * (T(1) + L::epsilon() * T(static_cast<int>(u8()) - 128));
      case 9:
      case 10: return nominal * T(u8()) / T(64);
      default: return nominal;
    }
  }
};

/// A copy of an object's bytes (its object representation, read, never written back), to prove an
/// output untouched.
template <class O>
struct Snapshot {
  explicit Snapshot(const O& o) { std::memcpy(bytes.data(), static_cast<const void*>(&o), sizeof(O)); }
  bool same(const O& o) const { return std::memcmp(bytes.data(), &o, sizeof(O)) == 0; }
  std::array<unsigned char, sizeof(O)> bytes;
};

template <class O>
void poison(O& o) {
  std::memset(static_cast<void*>(&o), 0xA5, sizeof(O));
}

template <typename T>
Mat2<T> cov2(Input& in, T a, T d) {
  // Nearly singular on request: [a, rho sqrt(ad); rho sqrt(ad), d] with rho near 1.
  const std::uint8_t k = in.u8();
  T rho = T(0);
  if (k & 1) rho = T(1) - T(std::ldexp(1.0, -static_cast<int>(in.u8() % 60)));
  if (k & 2) rho = -rho;
  Mat2<T> R;
  const T aa = in.f(a), dd = in.f(d);
  const T off = (k & 4) ? in.f(T(0.001)) : rho * std::sqrt(std::fabs(aa * dd));
  R << aa, off, off, dd;
  return R;
}

/// Positive definite, tested on the correlation matrix D^-1/2 P D^-1/2 so that huge or tiny (but
/// finite) entries cannot overflow the test itself.
bool positive_definite(const Eigen::Matrix3d& P) {
  for (int i = 0; i < 3; ++i)
    if (!(P(i, i) > 0)) return false;
  Eigen::Matrix3d Q;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Q(r, c) = P(r, c) / (std::sqrt(P(r, r)) * std::sqrt(P(c, c)));
  return Eigen::LLT<Eigen::Matrix3d>(Q).info() == Eigen::Success;
}

template <typename T, class B>
void check_filter(const ekf::Slam<T, B>& s) {
  const int n = s.landmarks();
  require(n >= 0 && n <= B::kMaxLandmarks && s.dim() == 3 + 2 * n);
  for (int i = 0; i < s.dim(); ++i) require(std::isfinite(s.x(i)));
  for (int r = 0; r < s.dim(); ++r)
    for (int c = 0; c < s.dim(); ++c) require(std::isfinite(s.cov(r, c)));
  Eigen::Matrix3d Prr;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Prr(r, c) = double(s.cov(r, c));
  require(positive_definite(Prr));
  for (int j = 0; j < n; ++j) {  // <= kMaxLandmarks
    const int l = 3 + 2 * j;
    const double a = s.cov(l, l), b = s.cov(l, l + 1), d = s.cov(l + 1, l + 1);
    require(a > 0 && d > 0 && std::fabs(b) < std::sqrt(a) * std::sqrt(d));  // |correlation| < 1, no overflow
  }
}

/// associate(): kOk with a consistent answer, or an error with `out` untouched.
template <typename T, class B>
Status check_associate(const Observations<T, B>& obs, const Prediction<T, B>& pred, const AssociationConfig<T, B>& cfg,
                       AssociationWorkspace<T, B>& ws, Association<T, B>& out) {
  poison(out);
  const Snapshot<Association<T, B>> before(out);
  const Status st = associate(obs, pred, cfg, ws, out);
  if (st != Status::kOk) {
    require(before.same(out));
    return st;
  }
  require(obs.count >= 0 && obs.count <= B::kMaxObservations && out.count == obs.count);
  int pairings = 0;
  std::array<int, B::kMaxCandidates> used{};
  for (int i = 0; i < out.count; ++i) {  // <= kMaxObservations
    const int c = out.candidate[i];
    require(c >= -1 && c < pred.count);
    if (c >= 0) {
      ++pairings;
      ++used[c];
      require(out.feature[i] == pred.id[c]);
      require(!(out.d2[i] < T(0)));
    } else {
      require(out.feature[i] == kNewFeature || out.feature[i] == kUnmatched);
    }
  }
  require(pairings == out.pairings);
  if (cfg.mutual_exclusion) {
    for (int j = 0; j < pred.count; ++j) require(used[j] <= 1);  // <= kMaxCandidates
  }
  return st;
}

template <typename T>
void run(Input& in) {
  using B = FB;
  struct State {
    ekf::Slam<T, B> slam;
    ekf::SlamWorkspace<T, B> ews;
    AssociationWorkspace<T, B> ws;
    Observations<T, B> obs;
    Prediction<T, B> pred;
    Association<T, B> assoc;
    AssociationConfig<T, B> cfg;
  };
  static std::unique_ptr<State> g;  // one per scalar type; the filter is reset below
  if (!g) g = std::make_unique<State>();
  State& s = *g;
  s.slam = ekf::Slam<T, B>{};
  s.obs.clear();
  s.pred.count = 0;
  require(s.pred.C.resize(0) == Status::kOk);
  s.assoc = Association<T, B>{};
  bool filter_ready = false;

  // A configuration: one of the strategies with fuzzed parameters (or the default on refusal).
  {
    StepSettings<T> p;
    const std::uint8_t k = in.u8();
    p.local_radius_m = T(10);
    if (k & 1) p.confidence = in.f(0.99);
    if (k & 2) p.local_radius_m = in.f(T(10));
    if (k & 4) p.groups = static_cast<int>(in.u8() % 6) - 1;
    if (k & 8) p.node_budget = static_cast<NodeCount>(static_cast<int>(in.u16() % 400) - 20);  // wraps: huge = refused
    if (k & 16) p.dbscan_eps_m = in.f(T(1.5));
    p.condition_groups = k & 32;
    if (k & 64) p.ambiguity_margin = in.f(1.0);
    p.new_if_candidates_taken = k & 128;
    AssociationConfig<T, B> c;
    poison(c);
    const Snapshot<AssociationConfig<T, B>> before(c);
    const Status st = make_strategy(static_cast<Strategy>(in.u8() % kStrategyCount), p, c);
    if (st == Status::kOk) {
      s.cfg = c;
    } else {
      require(before.same(c));
      require(make_strategy(Strategy::kJcbb, StepSettings<T>{}, s.cfg) == Status::kOk);
    }
  }

  for (int ops = 0; in.more() && ops < 64; ++ops) {  // <= 64 ops
    const std::uint8_t op = in.u8();
    const Snapshot<ekf::Slam<T, B>> filter_before(s.slam);
    Status st = Status::kOk;
    bool mutates = true;
    switch (op % 9) {
      case 0: {  // reset
        const Pose2<T> x0{in.f(T(1)), in.f(T(2)), in.f(T(0.3))};
        Mat3<T> P = Mat3<T>::Identity() * T(0.01);
        if (op & 0x10) {
          for (int r = 0; r < 3; ++r)
            for (int c = r; c < 3; ++c) P(r, c) = P(c, r) = in.f(P(r, c) == T(0) ? T(0.001) : P(r, c));
        }
        ekf::FilterOptions o;
        o.first_estimates_jacobians = op & 0x20;
        st = s.slam.reset(x0, P, o);
        if (st == Status::kOk) filter_ready = true;
        break;
      }
      case 1: {  // predict
        const ekf::Odometry<T> u{in.f(T(0.5)), in.f(T(0.1)), in.f(T(0.1)), in.f(T(0.05)), in.f(T(0.01))};
        st = s.slam.predict(u);
        break;
      }
      case 2: {  // predict_local
        mutates = false;
        Prediction<T, B> out;
        poison(out);
        ekf::LocalMapStats ls;
        poison(ls);
        const Snapshot<Prediction<T, B>> pb(out);
        const Snapshot<ekf::LocalMapStats> lb(ls);
        st = s.slam.predict_local(in.f(T(12)), s.ews, out, ls);
        if (st != Status::kOk) {
          require(pb.same(out) && lb.same(ls));
        } else {
          require(out.count >= 0 && out.count <= B::kMaxCandidates && out.count <= s.slam.landmarks());
          require(out.C.rows() == 2 * out.count && out.C.cols() == 2 * out.count);
          s.pred = out;
        }
        break;
      }
      case 3: {  // observations: a count at, under or over capacity, fuzzed values
        mutates = false;
        s.obs.clear();
        const int m = in.u8() % (B::kMaxObservations + 2);
        for (int i = 0; i < m; ++i) {                         // <= kMaxObservations + 1
          const T range = in.f(T(0.5) + T(in.u8()) / T(25));  // one statement each: a fixed read order
          const T bearing = in.f((T(in.u8()) - T(128)) / T(41));
          const Mat2<T> R = cov2(in, T(0.01), T(3e-4));
          const Status ps = s.obs.push(Vec2<T>(range, bearing), R);
          require((ps == Status::kOk) == (i < B::kMaxObservations));
        }
        if (op & 0x10) s.obs.count = static_cast<int>(in.u8() % 10) - 2;  // out of range on purpose
        break;
      }
      case 4: {  // a prediction of its own: ids, h, and C = J J^T (+ fuzzed entries), nearly singular
        mutates = false;
        const int n = in.u8() % (B::kMaxCandidates + 1);
        s.pred.count = n;
        for (int j = 0; j < n; ++j) {                                            // <= kMaxCandidates
          s.pred.id[j] = (op & 0x10) ? static_cast<FeatureId>(in.u8() % 4) : j;  // duplicates on request
          const T range = in.f(T(0.5) + T(in.u8()) / T(25));
          const T bearing = in.f((T(in.u8()) - T(128)) / T(41));
          s.pred.h[j] = Vec2<T>(range, bearing);
        }
        Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * B::kMaxCandidates, 2 * B::kMaxCandidates> J(2 * n,
                                                                                                            2 * n);
        for (int r = 0; r < 2 * n; ++r)
          for (int c = 0; c < 2 * n; ++c) J(r, c) = (r == c) ? T(0.1) : T(static_cast<int>(in.u8()) - 128) / T(2000);
        Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * B::kMaxCandidates, 2 * B::kMaxCandidates> D =
            J * J.transpose();
        if (op & 0x20 && n > 0) {
          const int r = in.u8() % (2 * n), c = in.u8() % (2 * n);
          D(r, c) = in.f(D(r, c));
          if (op & 0x40) D(c, r) = D(r, c);
        }
        // The dense boundary (packed covariance: C is packed): an asymmetric cross entry
        // is refused there, and the prediction's C is left as it was.
        const Snapshot<JointCovariance<T, B>> cb(s.pred.C);
        const Status cs = s.pred.C.assign_dense(D);
        require(cs == Status::kOk || (cs == Status::kNotSymmetric && cb.same(s.pred.C)));
        if (op & 0x80) s.pred.count = static_cast<int>(in.u8() % 12) - 2;  // out of range on purpose
        break;
      }
      case 5: {  // associate
        mutates = false;
        Association<T, B> out;
        st = check_associate(s.obs, s.pred, s.cfg, s.ws, out);
        if (st == Status::kOk) s.assoc = out;
        break;
      }
      case 6:  // update with the last association (or a fuzzed one)
        if (op & 0x10) {
          s.assoc.count = s.obs.count;
          for (int i = 0; i < B::kMaxObservations; ++i) {
            s.assoc.feature[i] = static_cast<FeatureId>(static_cast<int>(in.u8() % 16) - 2);
            s.assoc.candidate[i] = static_cast<std::int16_t>(static_cast<int>(in.u8() % 10) - 1);
          }
        }
        st = s.slam.update(s.obs, s.assoc, s.ews);
        break;
      case 7: {  // augment or add_known_landmark
        FeatureId id = 0x5A5A5A5A;
        const T range = in.f(T(3));
        const T bearing = in.f(T(0.4));
        const Vec2<T> z(range, bearing);
        const Mat2<T> R = cov2(in, T(0.01), T(3e-4));
        st = (op & 0x10) ? s.slam.add_known_landmark(z, R, id) : s.slam.augment(z, R, id);
        if (st != Status::kOk) {
          require(id == 0x5A5A5A5A);
        } else {
          require(id >= 0 && s.slam.index_of(id) == s.slam.landmarks() - 1);
        }
        break;
      }
      default: {                                                               // review
        ekf::Visibility<T> view{in.f(T(0)), in.f(T(10)), in.f(T(1.5)), T(0)};  // braces: read in order
        if (op & 0x10) view.occlusion_rad = in.f(T(0.05));
        ekf::LandmarkPolicy pol;
        if (op & 0x20) {
          pol.confirm_nats = in.f(10.0f);
          pol.delete_nats = -in.f(10.0f);
          pol.reserve_nats = in.f(5.0f);
          pol.max_tentative_reviews = static_cast<int>(in.u8() % 12) - 1;
          pol.p_detect = in.f(1.0f);
          pol.clutter_density = in.f(0.01f);
          pol.static_gate_d2 = in.f(9.0f);
        }
        ekf::ReviewStats rs;
        poison(rs);
        const Snapshot<ekf::ReviewStats> rb(rs);
        st = s.slam.review(s.obs, s.pred, s.assoc, view, pol, rs);
        if (st != Status::kOk) {
          require(rb.same(rs));
        } else {
          require(rs.removed >= 0 && rs.removed <= B::kMaxLandmarks && rs.paired <= rs.expected + B::kMaxObservations);
        }
        break;
      }
    }
#ifdef GEOJCBB_FUZZ_TRACE  // -DGEOJCBB_FUZZ_TRACE: each op, its status and the landmarks' blocks
    std::fprintf(stderr, "op %d status %d landmarks %d pose P [%g %g %g; %g %g; %g]\n", op % 9, static_cast<int>(st),
                 s.slam.landmarks(), double(s.slam.cov(0, 0)), double(s.slam.cov(0, 1)), double(s.slam.cov(0, 2)),
                 double(s.slam.cov(1, 1)), double(s.slam.cov(1, 2)), double(s.slam.cov(2, 2)));
    for (int j = 0; j < s.slam.landmarks(); ++j) {
      const int l = 3 + 2 * j;
      std::fprintf(stderr, "  l%d (%g %g) P [%g %g; %g]\n", j, double(s.slam.x(l)), double(s.slam.x(l + 1)),
                   double(s.slam.cov(l, l)), double(s.slam.cov(l, l + 1)), double(s.slam.cov(l + 1, l + 1)));
    }
#endif
    if (mutates && st != Status::kOk) require(filter_before.same(s.slam));  // no state change on error
    if (filter_ready) check_filter(s.slam);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 2048) return 0;
  Input in(data, size);
  if (in.u8() & 1) {
    run<double>(in);
  } else {
    run<float>(in);
  }
  return 0;
}
