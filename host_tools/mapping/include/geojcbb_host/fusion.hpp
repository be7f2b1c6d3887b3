// host_tools/mapping: the one constraint fusion of the host's maps. Two estimates of the same
// point in one Gaussian state (a local map's landmark and the global map's it was paired with; a
// robot's landmark and the merged map's) are fused as constraints x_a - x_b = 0, all pairs at once:
// the join (global_map.cpp: after the largest jointly compatible subset of the pairs) and the
// multi-robot merge (map_merge.cpp: all or none) call the same three functions.
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

namespace geojcbb::host {

/// Pairs (a, b) of 2-row blocks of a state (X, P), each the constraint X_a - X_b = 0 with variance
/// `var` [m^2] on each axis: H has +I at a and -I at b.
struct SamePoints {
  Eigen::MatrixXd HP;  ///< H P (2 rows per pair)
  Eigen::VectorXd nu;  ///< -H X: the constraints' innovation
  Eigen::MatrixXd S;   ///< H P H^T + var I, symmetrised
};

/// The constraints of `rows` (each pair's first rows, +I, and second, -I) on (X, P).
SamePoints same_points(const std::vector<std::pair<int, int>>& rows, const Eigen::VectorXd& X, const Eigen::MatrixXd& P,
                       double var);
/// nu^T S^-1 nu over the pairs `in` (indices into the rows given), with the full covariance;
/// infinity when their S is not positive definite; 0 for none.
double joint_d2(const SamePoints& c, const std::vector<int>& in);
/// P = (P + P^T) / 2 in place, tile by tile: the same values as the expression (the sum is
/// commutative) without a second matrix of the global map's size.
void symmetrize(Eigen::MatrixXd& P);
/// The pairs `in` fused as one update: X += K nu, P -= K H P, K = P H^T S^-1 (P symmetrised).
/// Returns false, changing nothing, when their S is not positive definite.
bool fuse_same_points(const SamePoints& c, const std::vector<int>& in, Eigen::VectorXd& X, Eigen::MatrixXd& P);

}  // namespace geojcbb::host
