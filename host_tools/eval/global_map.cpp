// host_tools/eval: the global map of sequential map joining (include/geojcbb_host/global_map.hpp).
#include "geojcbb_host/global_map.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "geojcbb/associate.hpp"
#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/core/math.hpp"
#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/core/strategy.hpp"

namespace geojcbb::host {

namespace {

/// The join's association capacity: the local map's landmarks that have a compatible global one
/// (at most 127, the observation index's range) against the global landmarks near them.
using JoinBounds = Bounds<127, 256, 5, 200000, 256>;

/// Range and bearing of a point d (in the base's frame) and their Jacobian with respect to d.
Eigen::Vector2d range_bearing_of(const Eigen::Vector2d& d, Eigen::Matrix2d& J) {
  const double r2 = std::max(d.squaredNorm(), 1e-12), r = std::sqrt(r2);
  J << d.x() / r, d.y() / r, -d.y() / r2, d.x() / r2;
  return {r, std::atan2(d.y(), d.x())};
}

Eigen::Matrix2d rotation(double theta) {
  Eigen::Matrix2d R;
  R << std::cos(theta), -std::sin(theta), std::sin(theta), std::cos(theta);
  return R;
}

/// Landmarks `g` (indices: rows 3 + 2 g of x) in the frame of the pose at x's first three rows,
/// R(theta)^T (l - p), and the Jacobian of those with respect to x.
void in_frame(const Eigen::VectorXd& x, const std::vector<int>& g, Eigen::VectorXd& c, Eigen::MatrixXd& H) {
  const int s = static_cast<int>(g.size());
  const Eigen::Matrix2d Rt = rotation(x(2)).transpose();
  c.resize(2 * s);
  H = Eigen::MatrixXd::Zero(2 * s, x.size());
  for (int k = 0; k < s; ++k) {
    const int r = 3 + 2 * g[static_cast<std::size_t>(k)];
    const Eigen::Vector2d d = Rt * (x.segment<2>(r) - x.head<2>());
    c.segment<2>(2 * k) = d;
    H.block<2, 2>(2 * k, 0) = -Rt;
    H.block<2, 1>(2 * k, 2) << d.y(), -d.x();
    H.block<2, 2>(2 * k, r) = Rt;
  }
}

/// The columns of A that hold a nonzero: a Jacobian with respect to the global state touches only
/// the base and a few landmarks, so A P is A(:, nz) P(nz, :), O(rows x nz x P's size) instead of
/// O(rows x P's size^2).
std::vector<Eigen::Index> nonzero_columns(const Eigen::MatrixXd& A) {
  std::vector<Eigen::Index> nz;
  for (Eigen::Index c = 0; c < A.cols(); ++c)
    if ((A.col(c).array() != 0.0).any()) nz.push_back(c);
  return nz;
}

/// P = (P + P^T) / 2 in place, tile by tile: the same values as the expression (the sum is
/// commutative) without a second matrix of the global map's size (docs/submaps.md, "How the host's
/// join scales").
void symmetrize(Eigen::MatrixXd& P) {
  constexpr Eigen::Index kTile = 64;
  const Eigen::Index n = P.rows();
  for (Eigen::Index c0 = 0; c0 < n; c0 += kTile) {
    for (Eigen::Index r0 = 0; r0 <= c0; r0 += kTile) {
      const Eigen::Index c1 = std::min(n, c0 + kTile), r1 = std::min(n, r0 + kTile);
      for (Eigen::Index c = c0; c < c1; ++c) {
        for (Eigen::Index r = r0; r < std::min(r1, c); ++r) {
          const double v = 0.5 * (P(r, c) + P(c, r));
          P(r, c) = v;
          P(c, r) = v;
        }
      }
    }
  }
}

/// in_frame's landmarks and their covariance H P H^T, from the rows of the pose and of those
/// landmarks alone: O(s^2) for s landmarks (the seed's, every scan), not O(dim^2).
void in_frame_cov(const Eigen::VectorXd& x, const Eigen::MatrixXd& P, const std::vector<int>& g, Eigen::VectorXd& c,
                  Eigen::MatrixXd& C) {
  std::vector<int> rows = {0, 1, 2}, at(g.size());
  for (std::size_t k = 0; k < g.size(); ++k) {
    at[k] = static_cast<int>(k);
    rows.push_back(3 + 2 * g[k]);
    rows.push_back(4 + 2 * g[k]);
  }
  const Eigen::VectorXd xs = x(rows);
  Eigen::MatrixXd H;
  in_frame(xs, at, c, H);
  C = H * P(rows, rows) * H.transpose();
  C = (0.5 * (C + C.transpose())).eval();
}

}  // namespace

struct GlobalMap::Association {
  AssociationConfig<double, JoinBounds> cfg;
  AssociationWorkspace<double, JoinBounds> ws;
  Observations<double, JoinBounds> obs;
  Prediction<double, JoinBounds> pred;
  geojcbb::Association<double, JoinBounds> out;
  double gate = 0;  ///< the individual gate
};

GlobalMap::GlobalMap(const JoinOptions& options) : opt_(options), assoc_(std::make_unique<Association>()) {
  x_ = Eigen::VectorXd::Zero(3);  // the first map's frame is the world's: the base is exact
  P_ = Eigen::MatrixXd::Zero(3, 3);
  StepSettings<double> s;
  apply_preset(opt_.preset, s);
  s.confidence = opt_.confidence;
  s.ambiguity_margin = opt_.margin_d2;
  s.local_radius_m = 1e6;  // the candidates are chosen here, near the new landmarks
  s.relocalise = s.loop_check = false;
  if (make_strategy(s.strategy, s, assoc_->cfg) != Status::kOk)
    throw std::runtime_error("join: bad association options");
  if (chi2_inv(opt_.confidence, 2, assoc_->gate) != Status::kOk) throw std::runtime_error("join: bad confidence");
}

GlobalMap::~GlobalMap() = default;

void GlobalMap::to_global(const Pose2<double>& local, const Eigen::Matrix3d& P_local, Pose2<double>& global,
                          Eigen::Matrix3d& P_global) const {
  const double th = x_(2), c = std::cos(th), s = std::sin(th);
  global.x = x_(0) + c * local.x - s * local.y;
  global.y = x_(1) + s * local.x + c * local.y;
  global.theta = wrap_angle(th + local.theta);
  Eigen::Matrix3d Jb = Eigen::Matrix3d::Identity();
  Jb(0, 2) = -s * local.x - c * local.y;
  Jb(1, 2) = c * local.x - s * local.y;
  Eigen::Matrix3d Jl = Eigen::Matrix3d::Identity();
  Jl.topLeftCorner<2, 2>() = rotation(th);
  P_global = Jb * P_.topLeftCorner<3, 3>() * Jb.transpose() + Jl * P_local * Jl.transpose();
}

int GlobalMap::index_of_first(FeatureId first) const {
  for (std::size_t k = 0; k < first_id_.size(); ++k)
    if (first_id_[k] == first) return static_cast<int>(k);
  return -1;
}

int GlobalMap::global_index(FeatureId local) const {
  const auto it = global_of_.find(local);
  return it == global_of_.end() ? -1 : index_of_first(it->second);
}

JoinResult GlobalMap::join(const Submap& m) {
  JoinResult res;
  const int n = m.landmarks();
  res.landmarks = n;
  if (m.x.size() != 3 + 2 * n || m.P.rows() != m.x.size() || m.P.cols() != m.x.size() ||
      m.confirmed.size() != m.ids.size() || m.exist_nats.size() != m.ids.size() ||
      (!m.carried.empty() && m.carried.size() != m.ids.size())) {
    throw std::runtime_error("join: a local map whose state and covariance do not match its landmarks");
  }
  // The landmarks the map shares with the global one: carried over from the previous map, or
  // seeded from the global map (the same ids). The prior the map began with on them: the previous
  // map's estimate in its last pose's frame, and the seed (the two uncorrelated, as the device holds
  // them).
  std::vector<int> shared, target, prev_row, seed_row;  // index in m, global index; row in the prior's source
  std::vector<bool> is_shared(static_cast<std::size_t>(n), false);
  for (int i = 0; i < n; ++i) {
    const FeatureId id = m.ids[static_cast<std::size_t>(i)];
    const int g = global_index(id);
    if (g < 0) continue;
    const auto s_it = std::find(seed_ids_.begin(), seed_ids_.end(), id);
    const auto p_it =
        prev_ ? std::find(prev_->ids.begin(), prev_->ids.end(), id) : std::vector<FeatureId>::const_iterator();
    if (s_it != seed_ids_.end()) {
      seed_row.push_back(static_cast<int>(s_it - seed_ids_.begin()));
      prev_row.push_back(-1);
    } else if (prev_ && p_it != prev_->ids.end()) {
      prev_row.push_back(static_cast<int>(p_it - prev_->ids.begin()));
      seed_row.push_back(-1);
    } else {
      continue;
    }
    shared.push_back(i);
    target.push_back(g);
    is_shared[static_cast<std::size_t>(i)] = true;
  }
  res.shared = static_cast<int>(shared.size());
  // Seeds the map took (and with remove_carried, landmarks it was born with, carried over) that it no
  // longer holds: it removed them by their evidence (missed where they were expected, from the global
  // map's log-odds on), so the global map removes them too.
  std::vector<bool> gone(first_id_.size(), false);
  std::vector<FeatureId> taken = seed_ids_;
  if (opt_.remove_carried) taken.insert(taken.end(), carried_ids_.begin(), carried_ids_.end());
  for (FeatureId id : taken) {
    if (std::find(m.ids.begin(), m.ids.end(), id) != m.ids.end()) continue;
    const int g = global_index(id);
    if (g >= 0 && !gone[static_cast<std::size_t>(g)]) {
      gone[static_cast<std::size_t>(g)] = true;
      ++res.removed;
    }
  }
  if (!shared.empty()) {
    const int s = static_cast<int>(shared.size());
    Eigen::VectorXd m0 = Eigen::VectorXd::Zero(2 * s);
    Eigen::MatrixXd P0 = Eigen::MatrixXd::Zero(2 * s, 2 * s);
    std::vector<int> carried, seeded;  // positions in shared
    for (int k = 0; k < s; ++k) (prev_row[static_cast<std::size_t>(k)] >= 0 ? carried : seeded).push_back(k);
    if (!carried.empty()) {  // the previous map's landmarks in its last pose's frame
      std::vector<int> from, out;
      for (int k : carried) {
        from.push_back(prev_row[static_cast<std::size_t>(k)]);
        out.push_back(2 * k);
        out.push_back(2 * k + 1);
      }
      Eigen::VectorXd d;
      Eigen::MatrixXd J;
      in_frame(prev_->x, from, d, J);
      m0(out) = d;
      P0(out, out) = J * prev_->P * J.transpose();
    }
    if (!seeded.empty()) {
      std::vector<int> from, out;
      for (int k : seeded) {
        const int r = seed_row[static_cast<std::size_t>(k)];
        from.push_back(2 * r);
        from.push_back(2 * r + 1);
        out.push_back(2 * k);
        out.push_back(2 * k + 1);
      }
      m0(out) = seed_.x(from);
      P0(out, out) = seed_.P(from, from);
    }
    if (!carried.empty() && !seeded.empty()) {  // the seeded ones alone, reported (docs/submaps.md)
      std::vector<int> sh, tg, rows;
      for (int k : seeded) {
        sh.push_back(shared[static_cast<std::size_t>(k)]);
        tg.push_back(target[static_cast<std::size_t>(k)]);
        rows.push_back(2 * k);
        rows.push_back(2 * k + 1);
      }
      res.seeded_d2 = shared_update(m, sh, tg, m0(rows), P0(rows, rows), false, res.seeded_dof);
    }
    res.shared_d2 = shared_update(m, shared, target, m0, P0, true, res.shared_dof);
    if (carried.empty()) {
      res.seeded_d2 = res.shared_d2;
      res.seeded_dof = res.shared_dof;
    }
    for (std::size_t k = 0; k < shared.size(); ++k)  // it began from the global map's: its evidence is the latest
      exist_[static_cast<std::size_t>(target[k])] = m.exist_nats[static_cast<std::size_t>(shared[k])];
  }
  // The association, in the base's frame: the map's other landmarks as range-bearing observations
  // from the base, the global landmarks (but the shared ones' targets) as predictions from it.
  const int N = landmarks();
  const double th = x_(2);
  const Eigen::Matrix2d Rt = rotation(th).transpose();
  std::vector<Eigen::Vector2d> h(static_cast<std::size_t>(N));
  std::vector<Eigen::Matrix<double, 2, 5>> H(static_cast<std::size_t>(N));  // d h / d [base, landmark]
  for (int j = 0; j < N; ++j) {
    const Eigen::Vector2d d = Rt * (x_.segment<2>(3 + 2 * j) - x_.head<2>());
    Eigen::Matrix2d Jd;
    h[static_cast<std::size_t>(j)] = range_bearing_of(d, Jd);
    Eigen::Matrix<double, 2, 5> Dd;  // d d / d [bx, by, btheta, gx, gy]
    Dd.block<2, 2>(0, 0) = -Rt;
    Dd.col(2) << d.y(), -d.x();
    Dd.block<2, 2>(0, 3) = Rt;
    H[static_cast<std::size_t>(j)] = Jd * Dd;
  }
  auto block_cov = [&](int a, int b) {  // H_a P_[base, a],[base, b] H_b^T
    const int ra = 3 + 2 * a, rb = 3 + 2 * b;
    Eigen::Matrix<double, 5, 5> Pab;
    Pab.block<3, 3>(0, 0) = P_.block<3, 3>(0, 0);
    Pab.block<3, 2>(0, 3) = P_.block<3, 2>(0, rb);
    Pab.block<2, 3>(3, 0) = P_.block<2, 3>(ra, 0);
    Pab.block<2, 2>(3, 3) = P_.block<2, 2>(ra, rb);
    const Eigen::Matrix2d B = H[static_cast<std::size_t>(a)] * Pab * H[static_cast<std::size_t>(b)].transpose();
    return a == b ? Eigen::Matrix2d(0.5 * (B + B.transpose())) : B;
  };
  std::vector<Eigen::Vector2d> z(static_cast<std::size_t>(n));
  std::vector<Eigen::Matrix2d> R(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix2d J;
    z[static_cast<std::size_t>(i)] = range_bearing_of(m.x.segment<2>(3 + 2 * i), J);
    const Eigen::Matrix2d Ri = J * m.P.block<2, 2>(3 + 2 * i, 3 + 2 * i) * J.transpose();
    R[static_cast<std::size_t>(i)] = 0.5 * (Ri + Ri.transpose());
  }
  std::vector<bool> is_target = gone;  // not a candidate: removed, or shared (the target of one)
  for (int g : target) is_target[static_cast<std::size_t>(g)] = true;
  std::vector<Eigen::Matrix2d> Cjj(static_cast<std::size_t>(N));
  for (int j = 0; j < N; ++j) Cjj[static_cast<std::size_t>(j)] = block_cov(j, j);
  std::vector<int> obs_of, cand_of;
  std::vector<bool> cand_used(static_cast<std::size_t>(N), false);
  for (int i = 0; i < n; ++i) {
    if (is_shared[static_cast<std::size_t>(i)]) continue;
    bool any = false;
    for (int j = 0; j < N; ++j) {
      if (is_target[static_cast<std::size_t>(j)]) continue;
      const Eigen::Matrix2d S = Cjj[static_cast<std::size_t>(j)] + R[static_cast<std::size_t>(i)];
      const Eigen::Vector2d nu = innovation(z[static_cast<std::size_t>(i)], h[static_cast<std::size_t>(j)]);
      if (nu.dot(S.ldlt().solve(nu)) < assoc_->gate) {
        any = true;
        cand_used[static_cast<std::size_t>(j)] = true;
      }
    }
    if (any) obs_of.push_back(i);
  }
  for (int j = 0; j < N; ++j)
    if (cand_used[static_cast<std::size_t>(j)]) cand_of.push_back(j);
  auto nearer = [](const std::vector<Eigen::Vector2d>& v) {
    return [&v](int a, int b) { return v[static_cast<std::size_t>(a)].x() < v[static_cast<std::size_t>(b)].x(); };
  };
  std::sort(obs_of.begin(), obs_of.end(), nearer(z));
  std::sort(cand_of.begin(), cand_of.end(), nearer(h));
  if (obs_of.size() > static_cast<std::size_t>(JoinBounds::kMaxObservations))
    obs_of.resize(JoinBounds::kMaxObservations);
  if (cand_of.size() > static_cast<std::size_t>(JoinBounds::kMaxCandidates)) cand_of.resize(JoinBounds::kMaxCandidates);
  res.offered = static_cast<int>(obs_of.size());
  std::vector<std::pair<int, int>> pairs;                           // (local landmark, global landmark)
  std::vector<bool> ambiguous(static_cast<std::size_t>(n), false);  // declined: neither paired nor new
  bool compatible = true;
  if (!obs_of.empty() && !cand_of.empty()) {
    Association& a = *assoc_;
    a.obs.clear();
    for (int i : obs_of) {
      if (a.obs.push(z[static_cast<std::size_t>(i)], R[static_cast<std::size_t>(i)]) != Status::kOk)
        throw std::runtime_error("join: observations over capacity");
    }
    const int nc = static_cast<int>(cand_of.size());
    Eigen::MatrixXd C(2 * nc, 2 * nc);
    a.pred.count = nc;
    for (int p = 0; p < nc; ++p) {
      a.pred.id[static_cast<std::size_t>(p)] = cand_of[static_cast<std::size_t>(p)];
      a.pred.h[static_cast<std::size_t>(p)] = h[static_cast<std::size_t>(cand_of[static_cast<std::size_t>(p)])];
      for (int q = 0; q <= p; ++q) {
        const Eigen::Matrix2d B = block_cov(cand_of[static_cast<std::size_t>(p)], cand_of[static_cast<std::size_t>(q)]);
        C.block<2, 2>(2 * p, 2 * q) = B;
        C.block<2, 2>(2 * q, 2 * p) = B.transpose();
      }
    }
    Status st = a.pred.C.assign_dense(C);
    if (st == Status::kOk) st = associate(a.obs, a.pred, a.cfg, a.ws, a.out);
    if (st != Status::kOk) throw std::runtime_error(std::string("join: associate: ") + to_string(st));
    for (int k = 0; k < a.out.count; ++k) {
      const FeatureId f = a.out.feature[static_cast<std::size_t>(k)];
      if (f >= 0) pairs.emplace_back(obs_of[static_cast<std::size_t>(k)], static_cast<int>(f));
      if (f == kUnmatched) {
        ++res.declined;
        ambiguous[static_cast<std::size_t>(obs_of[static_cast<std::size_t>(k)])] = true;
      }
    }
    compatible = a.out.jointly_compatible;
  }
  // The map's other landmarks and its last pose into the global frame, given the shared ones.
  const int D0 = 3 + 2 * N;
  std::vector<int> u = {0, 1, 2};  // the map's rows that are added: its pose, then each landmark not shared
  for (int i = 0; i < n; ++i) {
    if (is_shared[static_cast<std::size_t>(i)]) continue;
    u.push_back(3 + 2 * i);
    u.push_back(4 + 2 * i);
  }
  Eigen::VectorXd X;
  Eigen::MatrixXd P;
  augment(m, u, shared, target, X, P);
  std::vector<int> row_of(static_cast<std::size_t>(n), -1);  // landmark i's row in X (not shared)
  for (std::size_t k = 3; k < u.size(); k += 2)
    row_of[static_cast<std::size_t>((u[k] - 3) / 2)] = D0 + static_cast<int>(k);
  // The pairs' constraints l_new - l_global = 0 fused as one update, unless the association's answer
  // is not jointly compatible; their d2 with the full covariance is reported.
  std::vector<bool> drop(static_cast<std::size_t>(n), false);
  if (!pairs.empty()) {
    const int k = static_cast<int>(pairs.size());
    const int D = static_cast<int>(X.size());
    Eigen::MatrixXd HP(2 * k, D);  // H P, H = [.. -I (global) .. +I (new) ..]
    Eigen::VectorXd nu(2 * k);
    Eigen::MatrixXd S(2 * k, 2 * k);
    for (int p = 0; p < k; ++p) {
      const int rl = row_of[static_cast<std::size_t>(pairs[static_cast<std::size_t>(p)].first)];
      const int rg = 3 + 2 * pairs[static_cast<std::size_t>(p)].second;
      HP.middleRows<2>(2 * p) = P.middleRows<2>(rl) - P.middleRows<2>(rg);
      nu.segment<2>(2 * p) = X.segment<2>(rg) - X.segment<2>(rl);
    }
    for (int p = 0; p < k; ++p) {
      const int rl = row_of[static_cast<std::size_t>(pairs[static_cast<std::size_t>(p)].first)];
      const int rg = 3 + 2 * pairs[static_cast<std::size_t>(p)].second;
      S.middleCols<2>(2 * p) = HP.middleCols<2>(rl) - HP.middleCols<2>(rg);
    }
    S = (0.5 * (S + S.transpose()) + opt_.constraint_var_m2 * Eigen::MatrixXd::Identity(2 * k, 2 * k)).eval();
    // The largest jointly compatible subset, with the full covariance (the association's test
    // leaves out the local map's own correlations): the pair whose removal lowers d2 most goes,
    // until the rest pass chi2(confidence, 2 pairs).  O(k^5) at worst, k pairs.
    std::vector<int> in(static_cast<std::size_t>(k));
    for (int p = 0; p < k; ++p) in[static_cast<std::size_t>(p)] = p;
    auto rows_of = [](const std::vector<int>& v) {
      std::vector<int> r;
      for (int p : v) {
        r.push_back(2 * p);
        r.push_back(2 * p + 1);
      }
      return r;
    };
    auto d2_of = [&](const std::vector<int>& v) {
      if (v.empty()) return 0.0;
      const std::vector<int> r = rows_of(v);
      const Eigen::LLT<Eigen::MatrixXd> l(S(r, r));
      const Eigen::VectorXd e = nu(r);
      return l.info() == Eigen::Success ? e.dot(l.solve(e)) : std::numeric_limits<double>::infinity();
    };
    auto limit_of = [&](std::size_t pairs_in) {
      double q = 0;
      if (chi2_inv(opt_.confidence, 2 * static_cast<int>(pairs_in), q) != Status::kOk)
        throw std::runtime_error("join: chi2");
      return q;
    };
    res.joint_d2 = d2_of(in);
    double d2 = res.joint_d2;
    while (opt_.joint_check && !in.empty() && !(d2 <= limit_of(in.size()))) {
      std::size_t worst = 0;
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t q = 0; q < in.size(); ++q) {
        std::vector<int> v = in;
        v.erase(v.begin() + static_cast<std::ptrdiff_t>(q));
        const double e = d2_of(v);
        if (e < best) {
          best = e;
          worst = q;
        }
      }
      in.erase(in.begin() + static_cast<std::ptrdiff_t>(worst));
      ++res.pruned;
      d2 = best;
    }
    res.refused = !compatible || !std::isfinite(d2);
    if (!res.refused && !in.empty()) {
      const std::vector<int> r = rows_of(in);
      const Eigen::LLT<Eigen::MatrixXd> llt(S(r, r));
      const Eigen::MatrixXd HPi = HP(r, Eigen::indexing::all);
      const Eigen::MatrixXd K = llt.solve(HPi).transpose();  // P H^T S^-1
      X += K * nu(r);
      P.noalias() -= K * HPi;
      symmetrize(P);
      for (int q : in) {
        const auto& pr = pairs[static_cast<std::size_t>(q)];
        drop[static_cast<std::size_t>(pr.first)] = true;
        exist_[static_cast<std::size_t>(pr.second)] +=
            m.exist_nats[static_cast<std::size_t>(pr.first)];  // two maps' evidence
        const FeatureId first = first_id_[static_cast<std::size_t>(pr.second)];
        res.pairs.emplace_back(m.ids[static_cast<std::size_t>(pr.first)], first);
        global_of_[m.ids[static_cast<std::size_t>(pr.first)]] = first;
      }
      res.fused = static_cast<int>(in.size());
    }
  }
  // The new state [end, G, the new landmarks]: the old base and the fused duplicates marginalised.
  std::vector<int> keep = {D0, D0 + 1, D0 + 2};
  std::vector<FeatureId> first_ids;
  std::vector<double> exist;
  for (int g = 0; g < N; ++g) {
    if (gone[static_cast<std::size_t>(g)]) continue;
    keep.push_back(3 + 2 * g);
    keep.push_back(4 + 2 * g);
    first_ids.push_back(first_id_[static_cast<std::size_t>(g)]);
    exist.push_back(exist_[static_cast<std::size_t>(g)]);
  }
  for (int i = 0; i < n; ++i) {
    if (is_shared[static_cast<std::size_t>(i)] || drop[static_cast<std::size_t>(i)]) continue;
    // Tentative and not fused: not evidence enough. Declined (compatible with global landmarks,
    // left out as ambiguous): as the step does with such an observation, neither paired nor mapped
    // anew (kUnmatched), so a re-observed landmark is not made again beside its rivals.
    if (!m.confirmed[static_cast<std::size_t>(i)] || ambiguous[static_cast<std::size_t>(i)]) {
      ++res.dropped;
      continue;
    }
    keep.push_back(row_of[static_cast<std::size_t>(i)]);
    keep.push_back(row_of[static_cast<std::size_t>(i)] + 1);
    first_ids.push_back(m.ids[static_cast<std::size_t>(i)]);
    exist.push_back(m.exist_nats[static_cast<std::size_t>(i)]);
    global_of_[m.ids[static_cast<std::size_t>(i)]] = m.ids[static_cast<std::size_t>(i)];
  }
  first_id_ = std::move(first_ids);
  exist_ = std::move(exist);
  x_ = X(keep);
  x_(2) = wrap_angle(x_(2));
  P_ = P(keep, keep);
  prev_ = std::make_unique<Submap>(m);
  seed_ = Seed{};
  seed_ids_.clear();
  seed_refused_.clear();
  carried_ids_.clear();
  for (std::size_t i = 0; i < m.carried.size(); ++i) {
    if (m.carried[i]) carried_ids_.push_back(m.ids[i]);
  }
  ++maps_;
  return res;
}

double GlobalMap::shared_update(const Submap& m, const std::vector<int>& shared, const std::vector<int>& target,
                                const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0, bool apply, int& dof) {
  dof = 0;
  const int s = static_cast<int>(shared.size());
  std::vector<int> rows;
  for (int i : shared) {
    rows.push_back(3 + 2 * i);
    rows.push_back(4 + 2 * i);
  }
  const Eigen::VectorXd xc = m.x(rows);
  const Eigen::MatrixXd Pc = m.P(rows, rows);
  // What the map's own scans add on them: information Pc^-1 - P0^-1 (the prior divided out).
  const Eigen::LDLT<Eigen::MatrixXd> lc(Pc), l0(P0);
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(2 * s, 2 * s);
  Eigen::MatrixXd L = lc.solve(I) - l0.solve(I);
  L = (0.5 * (L + L.transpose())).eval();
  const Eigen::VectorXd b = lc.solve(xc) - l0.solve(m0);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(L);
  const double top = eig.eigenvalues().maxCoeff();
  // The shared landmarks in the base's frame, as functions of the global state.
  const int D0 = static_cast<int>(x_.size());
  Eigen::VectorXd c;
  Eigen::MatrixXd Hc;
  in_frame(x_, target, c, Hc);
  // One measurement per direction the scans informed (eigenvalue > 0): v^T c = v^T b / lambda,
  // noise 1 / lambda.
  std::vector<int> dirs;
  for (int e = 0; e < 2 * s; ++e)
    if (top > 0 && eig.eigenvalues()(e) > 1e-9 * top) dirs.push_back(e);
  if (dirs.empty()) return 0;
  const int r = static_cast<int>(dirs.size());
  Eigen::MatrixXd Hm(r, D0);
  Eigen::VectorXd nu(r), noise(r);
  for (int q = 0; q < r; ++q) {
    const Eigen::VectorXd v = eig.eigenvectors().col(dirs[static_cast<std::size_t>(q)]);
    const double lambda = eig.eigenvalues()(dirs[static_cast<std::size_t>(q)]);
    Hm.row(q) = v.transpose() * Hc;
    nu(q) = v.dot(b) / lambda - v.dot(c);
    noise(q) = 1 / lambda;
  }
  const std::vector<Eigen::Index> nz = nonzero_columns(Hm);
  const Eigen::MatrixXd Hnz = Hm(Eigen::indexing::all, nz);
  const Eigen::MatrixXd HP = Hnz * P_(nz, Eigen::indexing::all);
  Eigen::MatrixXd S = HP(Eigen::indexing::all, nz) * Hnz.transpose();
  S = (0.5 * (S + S.transpose())).eval();
  S.diagonal() += noise;
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) throw std::runtime_error("join: the shared landmarks' update is not definite");
  dof = r;
  const double d2 = nu.dot(llt.solve(nu));
  if (!apply) return d2;
  const Eigen::MatrixXd K = llt.solve(HP).transpose();
  x_ += K * nu;
  x_(2) = wrap_angle(x_(2));
  P_.noalias() -= K * HP;
  symmetrize(P_);
  return d2;
}

void GlobalMap::augment(const Submap& m, const std::vector<int>& u, const std::vector<int>& shared,
                        const std::vector<int>& target, Eigen::VectorXd& X, Eigen::MatrixXd& P) const {
  const int D0 = static_cast<int>(x_.size()), Du = static_cast<int>(u.size()), s = static_cast<int>(shared.size());
  // Given the shared landmarks c (in the base's frame), the rest of the map: u | c ~ N(x_u + B (c - x_c),
  // P_uu - B P_cu), B = P_uc P_cc^-1; c from the global state (c = R^T (g - b)).
  std::vector<int> rows;
  for (int i : shared) {
    rows.push_back(3 + 2 * i);
    rows.push_back(4 + 2 * i);
  }
  Eigen::VectorXd xu = m.x(u);
  Eigen::MatrixXd Pu = m.P(u, u);
  const double th = x_(2);
  const Eigen::Matrix2d Rb = rotation(th);
  Eigen::MatrixXd Fu = Eigen::MatrixXd::Zero(Du, D0);  // d u_local / d global state, through c
  if (s > 0) {
    const Eigen::MatrixXd Pcc = m.P(rows, rows), Puc = m.P(u, rows);
    const Eigen::MatrixXd B = Pcc.ldlt().solve(Puc.transpose()).transpose();
    Eigen::VectorXd c;
    Eigen::MatrixXd Hc;
    in_frame(x_, target, c, Hc);
    xu += B * (c - m.x(rows));
    Pu -= B * Puc.transpose();
    Pu = (0.5 * (Pu + Pu.transpose())).eval();
    Fu = B * Hc;
  }
  // u_global = base (+) u_local: the pose composed, each landmark transformed.
  Eigen::VectorXd v(Du);
  Eigen::MatrixXd Jb = Eigen::MatrixXd::Zero(Du, 3), Jy = Eigen::MatrixXd::Zero(Du, Du);
  Eigen::Matrix2d dRb;
  dRb << -std::sin(th), -std::cos(th), std::cos(th), -std::sin(th);
  for (int r = 0; r < Du; r += (r == 0 ? 3 : 2)) {  // the pose's position at 0, then each landmark
    const Eigen::Vector2d l = xu.segment<2>(r);
    v.segment<2>(r) = x_.head<2>() + Rb * l;
    Jb.block<2, 2>(r, 0).setIdentity();
    Jb.block<2, 1>(r, 2) = dRb * l;
    Jy.block<2, 2>(r, r) = Rb;
  }
  v(2) = wrap_angle(th + xu(2));
  Jb(2, 2) = 1;
  Jy(2, 2) = 1;
  Eigen::MatrixXd F = Jy * Fu;  // d u_global / d global state
  F.leftCols(3) += Jb;
  const int D = D0 + Du;
  X.resize(D);
  X << x_, v;
  P.resize(D, D);
  P.topLeftCorner(D0, D0) = P_;
  const std::vector<Eigen::Index> nz = nonzero_columns(F);
  const Eigen::MatrixXd Fnz = F(Eigen::indexing::all, nz);
  const Eigen::MatrixXd cross = Fnz * P_(nz, Eigen::indexing::all);  // Du x D0
  P.bottomLeftCorner(Du, D0) = cross;
  P.topRightCorner(D0, Du) = cross.transpose();
  const Eigen::MatrixXd Puu = cross(Eigen::indexing::all, nz) * Fnz.transpose() + Jy * Pu * Jy.transpose();
  P.bottomRightCorner(Du, Du) = 0.5 * (Puu + Puu.transpose());
}

Seed GlobalMap::seed(const Eigen::Vector2d& center, double radius_m, int max_count,
                     const std::vector<FeatureId>& held) const {
  std::vector<bool> taken(static_cast<std::size_t>(landmarks()), false);
  auto take = [&](int g) {
    if (g >= 0) taken[static_cast<std::size_t>(g)] = true;
  };
  for (FeatureId id : held) take(global_index(id));
  for (FeatureId first : seed_.first_ids) take(index_of_first(first));
  for (FeatureId first : seed_refused_) take(index_of_first(first));
  std::vector<std::pair<double, int>> near;
  for (int k = 0; k < landmarks(); ++k) {
    const double d = (landmark(k) - center).norm();
    if (!taken[static_cast<std::size_t>(k)] && d < radius_m) near.emplace_back(d, k);
  }
  std::sort(near.begin(), near.end());
  // Each near landmark in the base's frame, with its marginal covariance there.
  const std::size_t m = near.size();
  std::vector<Eigen::Vector2d> c(m);
  std::vector<Eigen::Matrix2d> Pc(m);
  for (std::size_t a = 0; a < m; ++a) {
    Eigen::VectorXd ca;
    Eigen::MatrixXd Ca;
    in_frame_cov(x_, P_, {near[a].second}, ca, Ca);
    c[a] = ca;
    Pc[a] = Ca;
  }
  auto compatible = [&](const Eigen::Vector2d& e, const Eigen::Matrix2d& S) {
    return e.dot(S.ldlt().solve(e)) < assoc_->gate;
  };
  std::vector<std::size_t> given;
  Seed s;
  for (std::size_t a = 0; a < m && static_cast<int>(given.size()) < max_count; ++a) {  // nearest first
    // A seed is a loop closure the step does not check: only one that no other landmark near it
    // could be taken for (their gates apart) is given; the rest are left to the join.
    bool skip = false;
    for (std::size_t b = 0; b < m && !skip; ++b) skip = b != a && compatible(c[a] - c[b], Pc[a] + Pc[b]);
    if (skip) continue;
    given.push_back(a);
    s.first_ids.push_back(first_id_[static_cast<std::size_t>(near[a].second)]);
    s.exist_nats.push_back(exist_[static_cast<std::size_t>(near[a].second)]);
  }
  const auto k = static_cast<Eigen::Index>(given.size());
  s.x = Eigen::VectorXd::Zero(2 * k);
  s.P = Eigen::MatrixXd::Zero(2 * k, 2 * k);
  for (Eigen::Index q = 0; q < k; ++q) {
    s.x.segment<2>(2 * q) = c[given[static_cast<std::size_t>(q)]];
    s.P.block<2, 2>(2 * q, 2 * q) = Pc[given[static_cast<std::size_t>(q)]];
  }
  return s;
}

void GlobalMap::seeded(const Seed& s, const std::vector<FeatureId>& local_ids) {
  if (local_ids.size() != s.first_ids.size() || s.exist_nats.size() != s.first_ids.size())
    throw std::runtime_error("seeded: one answer per seed");
  std::vector<Eigen::Index> took;
  for (std::size_t k = 0; k < local_ids.size(); ++k) {
    if (local_ids[k] >= 0) {
      took.push_back(static_cast<Eigen::Index>(k));
      seed_.first_ids.push_back(s.first_ids[k]);
      seed_.exist_nats.push_back(s.exist_nats[k]);
      seed_ids_.push_back(local_ids[k]);
      global_of_[local_ids[k]] = s.first_ids[k];
    } else if (local_ids[k] == kUnmatched) {
      seed_refused_.push_back(s.first_ids[k]);
    }
  }
  const Eigen::Index a = seed_.x.size(), b = 2 * static_cast<Eigen::Index>(took.size());
  Eigen::VectorXd x(a + b);
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(a + b, a + b);
  x.head(a) = seed_.x;
  P.topLeftCorner(a, a) = seed_.P;
  for (std::size_t q = 0; q < took.size(); ++q) {  // each seed's own block: they are uncorrelated
    const Eigen::Index to = a + 2 * static_cast<Eigen::Index>(q), from = 2 * took[q];
    x.segment<2>(to) = s.x.segment<2>(from);
    P.block<2, 2>(to, to) = s.P.block<2, 2>(from, from);
  }
  seed_.x = std::move(x);
  seed_.P = std::move(P);
}

Eigen::Vector2d GlobalMap::to_global(const Eigen::Vector2d& local) const {
  return x_.head<2>() + rotation(x_(2)) * local;
}

}  // namespace geojcbb::host
