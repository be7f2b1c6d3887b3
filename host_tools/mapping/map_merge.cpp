// host_tools/mapping: several robots' maps merged with unknown start poses (map_merge.hpp).
#include "geojcbb_host/map_merge.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/core/math.hpp"
#include "geojcbb/reloc/align.hpp"
#include "geojcbb_host/fusion.hpp"

namespace geojcbb::host {

namespace {

using MergeBounds = Bounds<127, 256, 5, 1000, 256>;

Eigen::Matrix2d rotation(double theta) {
  Eigen::Matrix2d R;
  R << std::cos(theta), -std::sin(theta), std::sin(theta), std::cos(theta);
  return R;
}

struct Aligner {
  Observations<double, MergeBounds> obs;
  reloc::AlignWorkspace<double, MergeBounds> ws;
  reloc::AlignResult<double, MergeBounds> out;
};

/// Map b's landmarks in the merged frame through pose x (b's frame there) with covariance Px:
/// means, and their covariance J_b P_b J_b^T + J_x Px J_x^T (the pose's part correlates them all).
void transformed(const RobotMap& b, const Pose2<double>& x, const Eigen::Matrix3d& Px, Eigen::VectorXd& l,
                 Eigen::MatrixXd& P) {
  const int n = static_cast<int>(b.landmarks.size());
  const Eigen::Matrix2d R = rotation(x.theta);
  l.resize(2 * n);
  Eigen::MatrixXd Jb = Eigen::MatrixXd::Zero(2 * n, 2 * n), Jx(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d q = b.landmarks[static_cast<std::size_t>(i)];
    const Eigen::Vector2d Rq = R * q;
    l.segment<2>(2 * i) = Rq + Eigen::Vector2d(x.x, x.y);
    Jb.block<2, 2>(2 * i, 2 * i) = R;
    Jx.block<2, 3>(2 * i, 0) << 1, 0, -Rq.y(), 0, 1, Rq.x();
  }
  P = Jb * b.P * Jb.transpose() + Jx * Px * Jx.transpose();
  P = (0.5 * (P + P.transpose())).eval();
}

/// Step 3's test: for each pair (b's landmark i, merged landmark j), another merged landmark
/// individually compatible with i, or another of b's landmarks with j (chi2 gate on the 2 x 2
/// innovation; b's landmarks l, Pl already in the merged frame with the pose's covariance), as the
/// global map's seeds must be unique (GlobalMap::seed). Returns the first rival found, in words, or
/// "" when every pair is unique. O(pairs (n + N)).
std::string rival_of(const std::vector<std::pair<int, int>>& pairs, const Eigen::VectorXd& l, const Eigen::MatrixXd& Pl,
                     const MergeResult& merged, double gate) {
  const int n = static_cast<int>(l.size() / 2), N = static_cast<int>(merged.landmarks.size());
  auto compatible = [&](int i, int j) {
    const Eigen::Vector2d e = l.segment<2>(2 * i) - merged.landmarks[static_cast<std::size_t>(j)];
    const Eigen::Matrix2d S = Pl.block<2, 2>(2 * i, 2 * i) + merged.P.block<2, 2>(2 * j, 2 * j);
    return e.dot(S.ldlt().solve(e)) < gate;
  };
  char d[160];
  for (const auto& [i, j] : pairs) {
    for (int jr = 0; jr < N; ++jr) {
      if (jr == j || !compatible(i, jr)) continue;
      std::snprintf(d, sizeof d, "its landmark %d is compatible with merged landmarks %d and %d (of %zu pairs)", i, j,
                    jr, pairs.size());
      return d;
    }
    for (int ir = 0; ir < n; ++ir) {
      if (ir == i || !compatible(ir, j)) continue;
      std::snprintf(d, sizeof d, "its landmarks %d and %d are both compatible with merged landmark %d (of %zu pairs)",
                    i, ir, j, pairs.size());
      return d;
    }
  }
  return {};
}

}  // namespace

MergeResult merge_maps(const std::vector<RobotMap>& maps, const MergeOptions& o) {
  MergeResult res;
  if (maps.empty()) return res;
  double gate1 = 0;
  if (chi2_inv(o.confidence, 2, gate1) != Status::kOk) throw std::runtime_error("merge: bad confidence");
  res.landmarks = maps[0].landmarks;
  res.P = maps[0].P;
  res.truth = maps[0].truth;
  res.aligned.push_back(true);
  res.start.push_back(Pose2<double>{0, 0, 0});
  res.start_cov.push_back(Eigen::Matrix3d::Zero());
  res.pairs.push_back(0);
  res.why.emplace_back();
  auto al = std::make_unique<Aligner>();
  for (std::size_t k = 1; k < maps.size(); ++k) {
    const RobotMap& b = maps[k];
    const int n = static_cast<int>(b.landmarks.size()), N = static_cast<int>(res.landmarks.size());
    res.start.push_back(Pose2<double>{0, 0, 0});
    res.start_cov.push_back(Eigen::Matrix3d::Zero());
    res.pairs.push_back(0);
    res.aligned.push_back(false);
    res.why.emplace_back();
    if (n > MergeBounds::kMaxObservations || N > MergeBounds::kMaxLandmarks) {  // kept apart, not an error
      char d[160];
      std::snprintf(d, sizeof d,
                    "larger than the alignment's capacity: %d landmarks (at most %d) against %d (at most %d)", n,
                    MergeBounds::kMaxObservations, N, MergeBounds::kMaxLandmarks);
      res.why.back() = d;
      continue;
    }
    // 1. Pose-free alignment: b's landmarks as range-bearing from its origin, against the merged map.
    al->obs.clear();
    al->ws.clear_map();
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d q = b.landmarks[static_cast<std::size_t>(i)];
      const double r2 = std::max(q.squaredNorm(), 1e-6), r = std::sqrt(r2);
      Eigen::Matrix2d J;
      J << q.x() / r, q.y() / r, -q.y() / r2, q.x() / r2;
      const Eigen::Matrix2d R = J * b.P.block<2, 2>(2 * i, 2 * i) * J.transpose();
      if (al->obs.push(Vec2<double>(r, std::atan2(q.y(), q.x())), (0.5 * (R + R.transpose())).eval()) != Status::kOk)
        throw std::runtime_error("merge: a landmark that is not an observation");
    }
    for (int j = 0; j < N; ++j) {
      const Status st =
          al->ws.push_landmark(res.landmarks[static_cast<std::size_t>(j)], res.P.block<2, 2>(2 * j, 2 * j));
      if (st != Status::kOk) throw std::runtime_error("merge: a merged landmark that is not a Gaussian");
    }
    reloc::AlignOptions<double> ao;
    ao.min_inliers = o.min_inliers;
    ao.margin_nats = o.margin_nats;
    ao.gate_d2 = gate1;
    if (reloc::align(al->obs, ao, al->ws, al->out) != Status::kOk) throw std::runtime_error("merge: align failed");
    const auto& a = al->out;
    if (!a.accepted) {
      char d[160];
      std::snprintf(d, sizeof d, "%d inliers at (%.2f, %.2f, %.2f), rival %d, %.1f vs %.1f nats", a.inliers, a.pose.x,
                    a.pose.y, a.pose.theta, a.rival_inliers, a.score, a.rival_score);
      res.why.back() =
          (a.ambiguous ? "ambiguous alignment (a rival pose within the margin): " : "no supported alignment: ") +
          std::string(d);
      continue;
    }
    // 2. The pairs' joint test with the full covariance: refused when they fail. X = [M, L'] (the
    // maps are independent), the pairs' constraints l'_i - m_j = 0 (fusion.hpp, as the join's).
    Eigen::VectorXd l;
    Eigen::MatrixXd Pl;
    transformed(b, a.pose, a.cov, l, Pl);
    std::vector<std::pair<int, int>> pairs, rows;  // (b's landmark, merged landmark); their rows in X
    for (int i = 0; i < n; ++i) {
      const int j = a.landmark[static_cast<std::size_t>(i)];
      if (j < 0) continue;
      pairs.emplace_back(i, j);
      rows.emplace_back(2 * N + 2 * i, 2 * j);
    }
    const int p = static_cast<int>(pairs.size());
    Eigen::VectorXd X(2 * N + 2 * n);
    Eigen::MatrixXd P = Eigen::MatrixXd::Zero(X.size(), X.size());
    for (int j = 0; j < N; ++j) X.segment<2>(2 * j) = res.landmarks[static_cast<std::size_t>(j)];
    X.tail(2 * n) = l;
    P.topLeftCorner(2 * N, 2 * N) = res.P;
    P.bottomRightCorner(2 * n, 2 * n) = Pl;
    const SamePoints c = same_points(rows, X, P, o.constraint_var_m2);
    std::vector<int> all(static_cast<std::size_t>(p));
    for (int u = 0; u < p; ++u) all[static_cast<std::size_t>(u)] = u;
    const double d2 = joint_d2(c, all);
    double limit = 0;
    if (chi2_inv(o.confidence, 2 * p, limit) != Status::kOk) throw std::runtime_error("merge: chi2");
    if (!(d2 <= limit)) {  // refused, not pruned into agreement: a subset of any pairing passes
      char d[120];
      std::snprintf(d, sizeof d, "the alignment's %d pairs are not jointly compatible (d2 %.1f > %.1f)", p, d2, limit);
      res.why.back() = d;
      continue;
    }
    // 3. Each pair unique under the alignment's own uncertainty (rival_of): otherwise the pose is as
    // well supported with the pairs exchanged: ambiguous, refused.
    if (std::string why = rival_of(pairs, l, Pl, res, gate1); !why.empty()) {
      res.why.back() = "ambiguous pairs: under the alignment's uncertainty " + why;
      continue;
    }
    // 4. Fusion: the constraints as one update, the paired rows of L' dropped.
    if (!fuse_same_points(c, all, X, P)) throw std::runtime_error("merge: constraints not positive definite");
    std::vector<bool> paired(static_cast<std::size_t>(n), false);
    for (const auto& [iu, ju] : pairs) {
      paired[static_cast<std::size_t>(iu)] = true;
      const int tb = b.truth[static_cast<std::size_t>(iu)], tm = res.truth[static_cast<std::size_t>(ju)];
      res.wrong += tb >= 0 && tm >= 0 && tb != tm;
      if (tm < 0) res.truth[static_cast<std::size_t>(ju)] = tb;
    }
    std::vector<int> keep;  // rows of X kept: the merged map's, then b's unpaired landmarks
    keep.reserve(static_cast<std::size_t>(N) + static_cast<std::size_t>(n));
    for (int j = 0; j < N; ++j) keep.push_back(j);
    for (int i = 0; i < n; ++i) {
      if (!paired[static_cast<std::size_t>(i)]) keep.push_back(N + i);
    }
    const int K = static_cast<int>(keep.size());
    res.landmarks.resize(static_cast<std::size_t>(K));
    res.P.resize(2 * K, 2 * K);
    for (int u = 0; u < K; ++u) {
      res.landmarks[static_cast<std::size_t>(u)] = X.segment<2>(2 * keep[static_cast<std::size_t>(u)]);
      for (int v = 0; v < K; ++v) {
        res.P.block<2, 2>(2 * u, 2 * v) =
            P.block<2, 2>(2 * keep[static_cast<std::size_t>(u)], 2 * keep[static_cast<std::size_t>(v)]);
      }
    }
    for (int i = 0; i < n; ++i) {
      if (!paired[static_cast<std::size_t>(i)]) res.truth.push_back(b.truth[static_cast<std::size_t>(i)]);
    }
    res.aligned.back() = true;
    res.start.back() = a.pose;
    res.start_cov.back() = a.cov;
    res.pairs.back() = p;
    res.fused += p;
  }
  return res;
}

}  // namespace geojcbb::host
