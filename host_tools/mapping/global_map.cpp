// host_tools/mapping: the global map of sequential map joining (include/geojcbb_host/global_map.hpp).
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
#include "geojcbb/ekf/motion.hpp"
#include "geojcbb_host/fusion.hpp"

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
  if (opt_.solver == JoinOptions::Solver::kGraph) {
    graph_ = std::make_unique<FactorGraph>();
    base_frame_ = graph_->add_frame(Eigen::Vector3d::Zero());
    P_.resize(0, 0);
  }
}

GlobalMap::~GlobalMap() = default;

Eigen::Matrix3d GlobalMap::base_covariance() const {
  return graph_ ? base_cov_ : Eigen::Matrix3d(P_.topLeftCorner<3, 3>());
}

Eigen::Matrix2d GlobalMap::landmark_covariance(int k) const {
  if (!graph_) return P_.block<2, 2>(3 + 2 * k, 3 + 2 * k);
  cache_joint({k});
  return joint_.at(k).bottomRightCorner<2, 2>();
}

Eigen::MatrixXd GlobalMap::landmarks_covariance() const {
  const int N = landmarks();
  if (!graph_) return P_.bottomRightCorner(2 * N, 2 * N);
  return graph_->marginal({}, var_of_);
}

Eigen::MatrixXd GlobalMap::joint_marginal(const std::vector<int>& gs) const {
  std::vector<int> rows = {0, 1, 2}, vars;
  for (int g : gs) {
    rows.push_back(3 + 2 * g);
    rows.push_back(4 + 2 * g);
    if (graph_) vars.push_back(var_of_.at(static_cast<std::size_t>(g)));
  }
  return graph_ ? graph_->marginal({base_frame_}, vars) : Eigen::MatrixXd(P_(rows, rows));
}

void GlobalMap::cache_joint(const std::vector<int>& gs) const {
  std::vector<int> need, vars;
  for (int g : gs) {
    if (joint_.count(g) != 0 || std::find(need.begin(), need.end(), g) != need.end()) continue;
    need.push_back(g);
    vars.push_back(var_of_[static_cast<std::size_t>(g)]);
  }
  if (need.empty()) return;
  const Eigen::MatrixXd S = graph_->marginal({base_frame_}, vars);
  for (std::size_t k = 0; k < need.size(); ++k) {
    const auto r = 3 + 2 * static_cast<Eigen::Index>(k);
    Eigen::Matrix<double, 5, 5> J;
    J.topLeftCorner<3, 3>() = S.topLeftCorner<3, 3>();
    J.topRightCorner<3, 2>() = S.block<3, 2>(0, r);
    J.bottomLeftCorner<2, 3>() = S.block<2, 3>(r, 0);
    J.bottomRightCorner<2, 2>() = S.block<2, 2>(r, r);
    joint_[need[k]] = J;
  }
}

void compose(const Eigen::Vector3d& o, const Eigen::Matrix3d& P_o, const Pose2<double>& local,
             const Eigen::Matrix3d& P_local, Pose2<double>& global, Eigen::Matrix3d& P_global) {
  Eigen::Matrix3d Jo, Jl;
  global = ekf::compose(Pose2<double>{o(0), o(1), o(2)}, ekf::PoseIncrement<double>{local.x, local.y, local.theta}, &Jo,
                        &Jl);
  P_global = Jo * P_o * Jo.transpose() + Jl * P_local * Jl.transpose();
}

void GlobalMap::to_global(const Pose2<double>& local, const Eigen::Matrix3d& P_local, Pose2<double>& global,
                          Eigen::Matrix3d& P_global) const {
  compose(x_.head<3>(), base_covariance(), local, P_local, global, P_global);
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

GlobalMap::Shared GlobalMap::find_shared(const Submap& m, JoinResult& res) const {
  // The landmarks the map shares with the global one: carried over from the previous map, or
  // seeded from the global map (the same ids). The prior the map began with on them: the previous
  // map's estimate in its last pose's frame, and the seed (the two uncorrelated, as the device holds
  // them).
  Shared sh;
  const int n = m.landmarks();
  std::vector<int> prev_row, seed_row;  // row in the prior's source
  sh.is_shared.assign(static_cast<std::size_t>(n), false);
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
    sh.shared.push_back(i);
    sh.target.push_back(g);
    sh.is_shared[static_cast<std::size_t>(i)] = true;
  }
  res.shared = static_cast<int>(sh.shared.size());
  // Seeds the map took (and with remove_carried, landmarks it was born with, carried over) that it no
  // longer holds: it removed them by their evidence (missed where they were expected, from the global
  // map's log-odds on), so the global map removes them too.
  sh.gone.assign(first_id_.size(), false);
  std::vector<FeatureId> taken = seed_ids_;
  if (opt_.remove_carried) taken.insert(taken.end(), carried_ids_.begin(), carried_ids_.end());
  for (FeatureId id : taken) {
    if (std::find(m.ids.begin(), m.ids.end(), id) != m.ids.end()) continue;
    const int g = global_index(id);
    if (g >= 0 && !sh.gone[static_cast<std::size_t>(g)]) {
      sh.gone[static_cast<std::size_t>(g)] = true;
      ++res.removed;
    }
  }
  const int s = static_cast<int>(sh.shared.size());
  Eigen::VectorXd m0 = Eigen::VectorXd::Zero(2 * s);
  Eigen::MatrixXd P0 = Eigen::MatrixXd::Zero(2 * s, 2 * s);
  for (int k = 0; k < s; ++k) (prev_row[static_cast<std::size_t>(k)] >= 0 ? sh.carried : sh.seeded).push_back(k);
  if (!sh.carried.empty()) {  // the previous map's landmarks in its last pose's frame
    std::vector<int> from, out;
    from.reserve(sh.carried.size());
    out.reserve(2 * sh.carried.size());
    for (int k : sh.carried) {
      from.push_back(prev_row[static_cast<std::size_t>(k)]);
      out.push_back(2 * k);
      out.push_back(2 * k + 1);
    }
    Eigen::VectorXd d;
    Eigen::MatrixXd J;
    in_frame(prev_->x, from, d, J);
    const Eigen::MatrixXd C = J * prev_->P * J.transpose();
    for (std::size_t a = 0; a < out.size(); ++a) {
      m0(out[a]) = d(static_cast<Eigen::Index>(a));
      for (std::size_t b = 0; b < out.size(); ++b)
        P0(out[a], out[b]) = C(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
    }
  }
  if (!sh.seeded.empty()) {
    std::vector<int> from, out;
    from.reserve(2 * sh.seeded.size());
    out.reserve(2 * sh.seeded.size());
    for (int k : sh.seeded) {
      const int r = seed_row[static_cast<std::size_t>(k)];
      from.push_back(2 * r);
      from.push_back(2 * r + 1);
      out.push_back(2 * k);
      out.push_back(2 * k + 1);
    }
    for (std::size_t a = 0; a < out.size(); ++a) {
      m0(out[a]) = seed_.x(from[a]);
      for (std::size_t b = 0; b < out.size(); ++b) P0(out[a], out[b]) = seed_.P(from[a], from[b]);
    }
  }
  sh.m0 = std::move(m0);
  sh.P0 = std::move(P0);
  return sh;
}

GlobalMap::View GlobalMap::open_view(const Submap& m, const Shared& sh) {
  View v;
  const int N = landmarks();
  if (!graph_) {  // the whole state
    v.g.resize(static_cast<std::size_t>(N));
    for (int g = 0; g < N; ++g) v.g[static_cast<std::size_t>(g)] = g;
    v.x = std::move(x_);
    v.P = std::move(P_);
    return v;
  }
  // The shared ones' targets, and every landmark that could pass the association's gate with one of
  // the map's other landmarks: with e the two in the world's frame apart, Cov(e) <= 2 (Sigma_i +
  // Sigma_j) (their cross-covariance left out), Sigma_j at most the landmark's marginal when last
  // computed (information only grows) and the gate widened a hundredfold in its tail.
  std::vector<bool> in(static_cast<std::size_t>(N), false);
  for (int g : sh.target) in[static_cast<std::size_t>(g)] = true;
  double wide = 0;
  if (chi2_inv(1 - (1 - opt_.confidence) / 100, 2, wide) != Status::kOk) throw std::runtime_error("join: chi2");
  const double th = x_(2);
  const Eigen::Matrix2d Rb = rotation(th);
  Eigen::Matrix2d dRb;
  dRb << -std::sin(th), -std::cos(th), std::cos(th), -std::sin(th);
  double own_max = 0;
  for (int g = 0; g < N; ++g) own_max = std::max(own_max, own_cov_[static_cast<std::size_t>(g)].trace());
  for (int i = 0; i < m.landmarks(); ++i) {
    if (sh.is_shared[static_cast<std::size_t>(i)]) continue;
    const Eigen::Vector2d l = m.x.segment<2>(3 + 2 * i);
    const Eigen::Vector2d p = x_.head<2>() + Rb * l;
    Eigen::Matrix<double, 2, 3> Jb;
    Jb << 1, 0, 0, 0, 1, 0;
    Jb.col(2) = dRb * l;
    const Eigen::Matrix2d Si =
        Jb * base_cov_ * Jb.transpose() + Rb * m.P.block<2, 2>(3 + 2 * i, 3 + 2 * i) * Rb.transpose();
    const double reach2 = wide * 2 * (Si.trace() + own_max);  // |e|^2 beyond it fails the bound's test
    for (int g = 0; g < N; ++g) {
      if (in[static_cast<std::size_t>(g)] || sh.gone[static_cast<std::size_t>(g)]) continue;
      const Eigen::Vector2d e = landmark(g) - p;
      if (e.squaredNorm() > reach2) continue;
      const Eigen::Matrix2d S = 2 * (Si + own_cov_[static_cast<std::size_t>(g)]);
      in[static_cast<std::size_t>(g)] = e.dot(S.ldlt().solve(e)) < wide;
    }
  }
  std::vector<int> vars;
  for (int g = 0; g < N; ++g) {
    if (!in[static_cast<std::size_t>(g)]) continue;
    v.g.push_back(g);
    vars.push_back(var_of_[static_cast<std::size_t>(g)]);
  }
  const auto q = static_cast<Eigen::Index>(v.g.size());
  v.x.resize(3 + 2 * q);
  v.x.head<3>() = x_.head<3>();
  for (Eigen::Index k = 0; k < q; ++k) v.x.segment<2>(3 + 2 * k) = landmark(v.g[static_cast<std::size_t>(k)]);
  v.P = graph_->marginal({base_frame_}, vars);
  for (Eigen::Index k = 0; k < q; ++k)
    own_cov_[static_cast<std::size_t>(v.g[static_cast<std::size_t>(k)])] = v.P.block<2, 2>(3 + 2 * k, 3 + 2 * k);
  return v;
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
  const Shared sh = find_shared(m, res);
  const int N = landmarks();
  View v = open_view(m, sh);
  std::vector<int> view_of(static_cast<std::size_t>(N), -1), target_view;
  for (std::size_t k = 0; k < v.g.size(); ++k) view_of[static_cast<std::size_t>(v.g[k])] = static_cast<int>(k);
  for (int g : sh.target) target_view.push_back(view_of[static_cast<std::size_t>(g)]);
  update_shared(m, sh, target_view, v, res);
  for (std::size_t k = 0; k < sh.shared.size(); ++k)  // it began from the global map's: its evidence is the latest
    exist_[static_cast<std::size_t>(sh.target[k])] = m.exist_nats[static_cast<std::size_t>(sh.shared[k])];
  const Pairing pr = associate_map(m, sh, v, target_view, res);
  // The map's other landmarks and its last pose into the global frame, given the shared ones.
  const int D0 = static_cast<int>(v.x.size());
  std::vector<int> u = {0, 1, 2};  // the map's rows that are added: its pose, then each landmark not shared
  for (int i = 0; i < n; ++i) {
    if (sh.is_shared[static_cast<std::size_t>(i)]) continue;
    u.push_back(3 + 2 * i);
    u.push_back(4 + 2 * i);
  }
  Eigen::VectorXd X;
  Eigen::MatrixXd P;
  augment(m, u, sh.shared, target_view, v, X, P);
  std::vector<int> row_of(static_cast<std::size_t>(n), -1);  // landmark i's row in X (not shared)
  for (std::size_t k = 3; k < u.size(); k += 2)
    row_of[static_cast<std::size_t>((u[k] - 3) / 2)] = D0 + static_cast<int>(k);
  const std::vector<int> in = fuse(pr.pairs, row_of, pr.compatible, X, P, res);
  // Per local landmark, the global landmark it is (-1: none): shared, fused, or new.
  std::vector<int> global(static_cast<std::size_t>(n), -1);
  for (std::size_t k = 0; k < sh.shared.size(); ++k) global[static_cast<std::size_t>(sh.shared[k])] = sh.target[k];
  for (int q : in) {
    const auto& p = pr.pairs[static_cast<std::size_t>(q)];
    const int g = v.g[static_cast<std::size_t>(p.second)];
    global[static_cast<std::size_t>(p.first)] = g;
    exist_[static_cast<std::size_t>(g)] += m.exist_nats[static_cast<std::size_t>(p.first)];  // two maps' evidence
    const FeatureId first = first_id_[static_cast<std::size_t>(g)];
    res.pairs.emplace_back(m.ids[static_cast<std::size_t>(p.first)], first);
    global_of_[m.ids[static_cast<std::size_t>(p.first)]] = first;
  }
  res.fused = static_cast<int>(in.size());
  // The new global map: the landmarks not removed, then the map's new ones.
  std::vector<int> survivors, fresh;
  for (int g = 0; g < N; ++g)
    if (!sh.gone[static_cast<std::size_t>(g)]) survivors.push_back(g);
  for (int i = 0; i < n; ++i) {
    if (global[static_cast<std::size_t>(i)] >= 0) continue;
    // Tentative and not fused: not evidence enough. Declined (compatible with global landmarks,
    // left out as ambiguous): as the step does with such an observation, neither paired nor mapped
    // anew (kUnmatched), so a re-observed landmark is not made again beside its rivals.
    if (!m.confirmed[static_cast<std::size_t>(i)] || pr.ambiguous[static_cast<std::size_t>(i)]) {
      ++res.dropped;
      continue;
    }
    fresh.push_back(i);
  }
  std::vector<FeatureId> first_ids;
  std::vector<double> exist;
  for (int g : survivors) {
    first_ids.push_back(first_id_[static_cast<std::size_t>(g)]);
    exist.push_back(exist_[static_cast<std::size_t>(g)]);
  }
  for (int i : fresh) {
    first_ids.push_back(m.ids[static_cast<std::size_t>(i)]);
    exist.push_back(m.exist_nats[static_cast<std::size_t>(i)]);
    global_of_[m.ids[static_cast<std::size_t>(i)]] = m.ids[static_cast<std::size_t>(i)];
  }
  if (!graph_) {  // the new state [end, the landmarks kept, the new ones]: the old base and the fused duplicates marginalised
    std::vector<int> keep = {D0, D0 + 1, D0 + 2};
    for (int g : survivors) {
      keep.push_back(3 + 2 * g);
      keep.push_back(4 + 2 * g);
    }
    for (int i : fresh) {
      keep.push_back(row_of[static_cast<std::size_t>(i)]);
      keep.push_back(row_of[static_cast<std::size_t>(i)] + 1);
    }
    x_ = X(keep);
    x_(2) = wrap_angle(x_(2));
    P_ = P(keep, keep);
  } else {  // the map as a factor, its new landmarks and end frame as variables, all solved again
    std::vector<int> var(static_cast<std::size_t>(n), -1), vars;
    for (int i = 0; i < n; ++i) {
      const int g = global[static_cast<std::size_t>(i)];
      if (g >= 0) var[static_cast<std::size_t>(i)] = var_of_[static_cast<std::size_t>(g)];
    }
    std::vector<Eigen::Matrix2d> own;
    for (int g : survivors) {
      vars.push_back(var_of_[static_cast<std::size_t>(g)]);
      own.push_back(own_cov_[static_cast<std::size_t>(g)]);
    }
    std::vector<int> fresh_vars;
    for (int i : fresh) {
      const int r = row_of[static_cast<std::size_t>(i)];
      var[static_cast<std::size_t>(i)] = graph_->add_landmark(X.segment<2>(r));
      vars.push_back(var[static_cast<std::size_t>(i)]);
      fresh_vars.push_back(var[static_cast<std::size_t>(i)]);
      own.push_back(P.block<2, 2>(r, r));
    }
    add_factor(m, sh, var, X.segment<3>(D0));
    var_of_ = std::move(vars);
    own_cov_ = std::move(own);
    if (opt_.solver_window > 0) {
      last_solve_ = graph_->solve_window(opt_.solver_iterations);
      graph_->settle(opt_.solver_window);
    } else {
      last_solve_ = graph_->solve(opt_.solver_iterations);
    }
    x_.resize(3 + 2 * static_cast<Eigen::Index>(var_of_.size()));
    x_.head<3>() = graph_->frame(base_frame_);
    for (std::size_t k = 0; k < var_of_.size(); ++k)
      x_.segment<2>(3 + 2 * static_cast<Eigen::Index>(k)) = graph_->landmark(var_of_[k]);
    const Eigen::MatrixXd S = graph_->marginal({base_frame_}, fresh_vars);  // the base's, and the new ones'
    base_cov_ = S.topLeftCorner<3, 3>();
    for (std::size_t k = 0; k < fresh.size(); ++k) {
      const auto r = 3 + 2 * static_cast<Eigen::Index>(k);
      own_cov_[survivors.size() + k] = S.block<2, 2>(r, r);
    }
    joint_.clear();
  }
  first_id_ = std::move(first_ids);
  exist_ = std::move(exist);
  prev_ = std::make_unique<Submap>(m);
  seed_ = Seed{};
  seed_ids_.clear();
  seed_refused_.clear();
  carried_ids_.clear();
  for (std::size_t i = 0; i < m.carried.size(); ++i) {
    if (m.carried[i]) carried_ids_.push_back(m.ids[i]);
  }
  ++maps_;
  frame_of_map_.push_back(base_frame_);
  return res;
}

void GlobalMap::origins(std::vector<Eigen::Vector3d>& o, std::vector<Eigen::Matrix3d>& P) const {
  if (!graph_) throw std::logic_error("origins: a dense global map does not keep its maps' origins");
  o.clear();
  P.clear();
  const Eigen::MatrixXd S = graph_->marginal(frame_of_map_, {});
  for (std::size_t k = 0; k < frame_of_map_.size(); ++k) {
    const auto r = 3 * static_cast<Eigen::Index>(k);
    o.push_back(graph_->frame(frame_of_map_[k]));
    P.emplace_back(S.block<3, 3>(r, r));
  }
}

Eigen::Vector3d GlobalMap::origin(int k) const {
  if (k < 0 || k > maps_) throw std::out_of_range("origin: no such local map");
  if (!graph_) throw std::logic_error("origin: a dense global map does not keep its maps' origins");
  return graph_->frame(frame_of_map_[static_cast<std::size_t>(k)]);
}

void GlobalMap::add_factor(const Submap& m, const Shared& sh, const std::vector<int>& var, const Eigen::Vector3d& end) {
  // The map's information on y = [end pose, landmarks] less the prior it began with on the shared
  // ones (conditionally independent maps: the prior is the previous map's or the global map's, and
  // is counted there). With delta = y - x_m: cost 1/2 delta^T L delta + g^T delta, L = P^-1 - E P0^-1 E^T,
  // g = -E P0^-1 (x_c - m0).
  const auto d = m.x.size();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(d, d);
  const Eigen::MatrixXd posterior = m.P.ldlt().solve(I);
  Eigen::MatrixXd L = posterior;
  Eigen::VectorXd g = Eigen::VectorXd::Zero(d);
  if (!sh.shared.empty()) {
    std::vector<int> rows;
    for (int i : sh.shared) {
      rows.push_back(3 + 2 * i);
      rows.push_back(4 + 2 * i);
    }
    const Eigen::LDLT<Eigen::MatrixXd> l0(sh.P0);
    L(rows, rows) -= l0.solve(Eigen::MatrixXd::Identity(sh.P0.rows(), sh.P0.cols()));
    g(rows) = -l0.solve(m.x(rows) - sh.m0);
  }
  // The landmarks the global map does not keep, marginalised out of the factor (Schur complement).
  std::vector<int> keep = {0, 1, 2}, drop;
  MapFactor f;
  f.from = base_frame_;
  f.to = graph_->add_frame(end);
  for (int i = 0; i < m.landmarks(); ++i) {
    std::vector<int>& to = var[static_cast<std::size_t>(i)] >= 0 ? keep : drop;
    to.push_back(3 + 2 * i);
    to.push_back(4 + 2 * i);
    if (var[static_cast<std::size_t>(i)] >= 0) f.landmarks.push_back(var[static_cast<std::size_t>(i)]);
  }
  Eigen::MatrixXd Lk = L(keep, keep);
  Eigen::VectorXd gk = g(keep);
  if (!drop.empty()) {
    const Eigen::LDLT<Eigen::MatrixXd> ld(L(drop, drop));
    const Eigen::MatrixXd Lkd = L(keep, drop);
    Lk -= Lkd * ld.solve(Lkd.transpose());
    gk -= Lkd * ld.solve(g(drop));
  }
  Lk = (0.5 * (Lk + Lk.transpose())).eval();
  // r = W delta - c with W^T W = L (its informed directions) and W^T c = -g. L is scaled to a unit
  // diagonal first (L = S Ls S): a pose known to a micrometre and a landmark to a decimetre differ by
  // 10^10 in information, and a direction is uninformed only against its own scale. A diagonal entry
  // below 1e-9 of the posterior's information there is such a direction (a carried landmark the map
  // learned nothing of: its prior divided out).
  const Eigen::VectorXd floor = 1e-9 * posterior.diagonal()(keep).cwiseAbs();
  square_root_information(Lk, gk, floor, f.W, f.c);
  const auto r = f.W.rows();
  f.y0 = m.x(keep);
  if (opt_.loss_confidence > 0 && chi2_inv(opt_.loss_confidence, static_cast<int>(r), f.loss_d2) != Status::kOk)
    throw std::runtime_error("join: chi2");
  graph_->add_map(f);
  base_frame_ = f.to;
}

void GlobalMap::update_shared(const Submap& m, const Shared& sh, const std::vector<int>& target_view, View& v,
                              JoinResult& res) const {
  if (sh.shared.empty()) return;
  if (!sh.carried.empty() && !sh.seeded.empty()) {  // the seeded ones alone, reported (docs/submaps.md)
    std::vector<int> s, t, rows;
    for (int k : sh.seeded) {
      s.push_back(sh.shared[static_cast<std::size_t>(k)]);
      t.push_back(target_view[static_cast<std::size_t>(k)]);
      rows.push_back(2 * k);
      rows.push_back(2 * k + 1);
    }
    res.seeded_d2 = shared_update(m, s, t, sh.m0(rows), sh.P0(rows, rows), false, res.seeded_dof, v);
  }
  res.shared_d2 = shared_update(m, sh.shared, target_view, sh.m0, sh.P0, true, res.shared_dof, v);
  if (sh.carried.empty()) {
    res.seeded_d2 = res.shared_d2;
    res.seeded_dof = res.shared_dof;
  }
}

GlobalMap::Pairing GlobalMap::associate_map(const Submap& m, const Shared& sh, const View& v,
                                            const std::vector<int>& target_view, JoinResult& res) const {
  // The association, in the base's frame: the map's other landmarks as range-bearing observations
  // from the base, the view's landmarks (but the shared ones' targets) as predictions from it.
  Pairing out;
  const int n = m.landmarks();
  out.ambiguous.assign(static_cast<std::size_t>(n), false);
  const int N = static_cast<int>(v.g.size());
  const Eigen::VectorXd& x = v.x;
  const Eigen::MatrixXd& Pv = v.P;
  const double th = x(2);
  const Eigen::Matrix2d Rt = rotation(th).transpose();
  std::vector<Eigen::Vector2d> h(static_cast<std::size_t>(N));
  std::vector<Eigen::Matrix<double, 2, 5>> H(static_cast<std::size_t>(N));  // d h / d [base, landmark]
  for (int j = 0; j < N; ++j) {
    const Eigen::Vector2d d = Rt * (x.segment<2>(3 + 2 * j) - x.head<2>());
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
    Pab.block<3, 3>(0, 0) = Pv.block<3, 3>(0, 0);
    Pab.block<3, 2>(0, 3) = Pv.block<3, 2>(0, rb);
    Pab.block<2, 3>(3, 0) = Pv.block<2, 3>(ra, 0);
    Pab.block<2, 2>(3, 3) = Pv.block<2, 2>(ra, rb);
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
  std::vector<bool> is_target(static_cast<std::size_t>(N),
                              false);  // not a candidate: removed, or shared (the target of one)
  for (int j = 0; j < N; ++j)
    is_target[static_cast<std::size_t>(j)] = sh.gone[static_cast<std::size_t>(v.g[static_cast<std::size_t>(j)])];
  for (int j : target_view) is_target[static_cast<std::size_t>(j)] = true;
  std::vector<Eigen::Matrix2d> Cjj(static_cast<std::size_t>(N));
  for (int j = 0; j < N; ++j) Cjj[static_cast<std::size_t>(j)] = block_cov(j, j);
  std::vector<int> obs_of, cand_of;
  std::vector<bool> cand_used(static_cast<std::size_t>(N), false);
  for (int i = 0; i < n; ++i) {
    if (sh.is_shared[static_cast<std::size_t>(i)]) continue;
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
  auto nearer = [](const std::vector<Eigen::Vector2d>& w) {
    return [&w](int a, int b) { return w[static_cast<std::size_t>(a)].x() < w[static_cast<std::size_t>(b)].x(); };
  };
  std::sort(obs_of.begin(), obs_of.end(), nearer(z));
  std::sort(cand_of.begin(), cand_of.end(), nearer(h));
  if (obs_of.size() > static_cast<std::size_t>(JoinBounds::kMaxObservations))
    obs_of.resize(JoinBounds::kMaxObservations);
  if (cand_of.size() > static_cast<std::size_t>(JoinBounds::kMaxCandidates)) cand_of.resize(JoinBounds::kMaxCandidates);
  res.offered = static_cast<int>(obs_of.size());
  if (obs_of.empty() || cand_of.empty()) return out;
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
    if (f >= 0) out.pairs.emplace_back(obs_of[static_cast<std::size_t>(k)], static_cast<int>(f));
    if (f == kUnmatched) {
      ++res.declined;
      out.ambiguous[static_cast<std::size_t>(obs_of[static_cast<std::size_t>(k)])] = true;
    }
  }
  out.compatible = a.out.jointly_compatible;
  return out;
}

std::vector<int> GlobalMap::fuse(const std::vector<std::pair<int, int>>& pairs, const std::vector<int>& row_of,
                                 bool compatible, Eigen::VectorXd& X, Eigen::MatrixXd& P, JoinResult& res) const {
  // The pairs' constraints l_new - l_global = 0 fused as one update (fusion.hpp), unless the
  // association's answer is not jointly compatible; their d2 with the full covariance is reported.
  std::vector<int> in;
  if (pairs.empty()) return in;
  const int k = static_cast<int>(pairs.size());
  std::vector<std::pair<int, int>> rows;
  rows.reserve(pairs.size());
  for (const auto& [i, g] : pairs) rows.emplace_back(row_of[static_cast<std::size_t>(i)], 3 + 2 * g);
  const SamePoints c = same_points(rows, X, P, opt_.constraint_var_m2);
  // The largest jointly compatible subset, with the full covariance (the association's test
  // leaves out the local map's own correlations): the pair whose removal lowers d2 most goes,
  // until the rest pass chi2(confidence, 2 pairs).  O(k^5) at worst, k pairs.
  in.resize(static_cast<std::size_t>(k));
  for (int p = 0; p < k; ++p) in[static_cast<std::size_t>(p)] = p;
  auto limit_of = [&](std::size_t pairs_in) {
    double q = 0;
    if (chi2_inv(opt_.confidence, 2 * static_cast<int>(pairs_in), q) != Status::kOk)
      throw std::runtime_error("join: chi2");
    return q;
  };
  res.joint_d2 = joint_d2(c, in);
  double d2 = res.joint_d2;
  while (opt_.joint_check && !in.empty() && !(d2 <= limit_of(in.size()))) {
    std::size_t worst = 0;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t q = 0; q < in.size(); ++q) {
      std::vector<int> w = in;
      w.erase(w.begin() + static_cast<std::ptrdiff_t>(q));
      const double e = joint_d2(c, w);
      if (e < best) {
        best = e;
        worst = q;
      }
    }
    in.erase(in.begin() + static_cast<std::ptrdiff_t>(worst));
    ++res.pruned;
    d2 = best;
  }
  res.refused = !compatible || !std::isfinite(d2) || !fuse_same_points(c, in, X, P);
  if (res.refused || in.empty()) return {};
  return in;
}

double GlobalMap::shared_update(const Submap& m, const std::vector<int>& shared, const std::vector<int>& target,
                                const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0, bool apply, int& dof,
                                View& v) const {
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
  const int D0 = static_cast<int>(v.x.size());
  Eigen::VectorXd c;
  Eigen::MatrixXd Hc;
  in_frame(v.x, target, c, Hc);
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
    const Eigen::VectorXd e_q = eig.eigenvectors().col(dirs[static_cast<std::size_t>(q)]);
    const double lambda = eig.eigenvalues()(dirs[static_cast<std::size_t>(q)]);
    Hm.row(q) = e_q.transpose() * Hc;
    nu(q) = e_q.dot(b) / lambda - e_q.dot(c);
    noise(q) = 1 / lambda;
  }
  const std::vector<Eigen::Index> nz = nonzero_columns(Hm);
  const Eigen::MatrixXd Hnz = Hm(Eigen::indexing::all, nz);
  const Eigen::MatrixXd HP = Hnz * v.P(nz, Eigen::indexing::all);
  Eigen::MatrixXd S = HP(Eigen::indexing::all, nz) * Hnz.transpose();
  S = (0.5 * (S + S.transpose())).eval();
  S.diagonal() += noise;
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) throw std::runtime_error("join: the shared landmarks' update is not definite");
  dof = r;
  const double d2 = nu.dot(llt.solve(nu));
  if (!apply) return d2;
  const Eigen::MatrixXd K = llt.solve(HP).transpose();
  v.x += K * nu;
  v.x(2) = wrap_angle(v.x(2));
  v.P.noalias() -= K * HP;
  symmetrize(v.P);
  return d2;
}

void GlobalMap::augment(const Submap& m, const std::vector<int>& u, const std::vector<int>& shared,
                        const std::vector<int>& target, const View& v, Eigen::VectorXd& X, Eigen::MatrixXd& P) const {
  const int D0 = static_cast<int>(v.x.size()), Du = static_cast<int>(u.size()), s = static_cast<int>(shared.size());
  // Given the shared landmarks c (in the base's frame), the rest of the map: u | c ~ N(v.xu + B (c - v.xc),
  // v.Puu - B v.Pcu), B = v.Puc v.Pcc^-1; c from the global state (c = R^T (g - b)).
  std::vector<int> rows;
  for (int i : shared) {
    rows.push_back(3 + 2 * i);
    rows.push_back(4 + 2 * i);
  }
  Eigen::VectorXd xu = m.x(u);
  Eigen::MatrixXd Pu = m.P(u, u);
  const double th = v.x(2);
  const Eigen::Matrix2d Rb = rotation(th);
  Eigen::MatrixXd Fu = Eigen::MatrixXd::Zero(Du, D0);  // d u_local / d global state, through c
  if (s > 0) {
    const Eigen::MatrixXd Pcc = m.P(rows, rows), Puc = m.P(u, rows);
    const Eigen::MatrixXd B = Pcc.ldlt().solve(Puc.transpose()).transpose();
    Eigen::VectorXd c;
    Eigen::MatrixXd Hc;
    in_frame(v.x, target, c, Hc);
    xu += B * (c - m.x(rows));
    Pu -= B * Puc.transpose();
    Pu = (0.5 * (Pu + Pu.transpose())).eval();
    Fu = B * Hc;
  }
  // u_global = base (+) u_local: the pose composed, each landmark transformed.
  Eigen::VectorXd w(Du);
  Eigen::MatrixXd Jb = Eigen::MatrixXd::Zero(Du, 3), Jy = Eigen::MatrixXd::Zero(Du, Du);
  Eigen::Matrix2d dRb;
  dRb << -std::sin(th), -std::cos(th), std::cos(th), -std::sin(th);
  for (int r = 0; r < Du; r += (r == 0 ? 3 : 2)) {  // the pose's position at 0, then each landmark
    const Eigen::Vector2d l = xu.segment<2>(r);
    w.segment<2>(r) = v.x.head<2>() + Rb * l;
    Jb.block<2, 2>(r, 0).setIdentity();
    Jb.block<2, 1>(r, 2) = dRb * l;
    Jy.block<2, 2>(r, r) = Rb;
  }
  w(2) = wrap_angle(th + xu(2));
  Jb(2, 2) = 1;
  Jy(2, 2) = 1;
  Eigen::MatrixXd F = Jy * Fu;  // d u_global / d global state
  F.leftCols(3) += Jb;
  const int D = D0 + Du;
  X.resize(D);
  X << v.x, w;
  P.resize(D, D);
  P.topLeftCorner(D0, D0) = v.P;
  const std::vector<Eigen::Index> nz = nonzero_columns(F);
  const Eigen::MatrixXd Fnz = F(Eigen::indexing::all, nz);
  const Eigen::MatrixXd cross = Fnz * v.P(nz, Eigen::indexing::all);  // Du x D0
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
  if (graph_) {
    std::vector<int> gs(m);
    for (std::size_t a = 0; a < m; ++a) gs[a] = near[a].second;
    cache_joint(gs);
  }
  for (std::size_t a = 0; a < m; ++a) {
    const int g = near[a].second;
    Eigen::VectorXd xs(5), ca;
    xs << x_.head<3>(), landmark(g);
    Eigen::MatrixXd Ps(5, 5), H;
    if (graph_) {
      Ps = joint_.at(g);
    } else {
      const std::vector<int> rows = {0, 1, 2, 3 + 2 * g, 4 + 2 * g};
      Ps = P_(rows, rows);
    }
    in_frame(xs, {0}, ca, H);
    const Eigen::Matrix2d Ca = H * Ps * H.transpose();
    c[a] = ca;
    Pc[a] = 0.5 * (Ca + Ca.transpose());
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
