// host_tools/mapping: the one constraint fusion of the host's maps (fusion.hpp).
#include "geojcbb_host/fusion.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <limits>

namespace geojcbb::host {

namespace {

/// The rows of S and nu that pairs `in` own (two each).
std::vector<int> rows_of(const std::vector<int>& in) {
  std::vector<int> r;
  r.reserve(2 * in.size());
  for (int p : in) {
    r.push_back(2 * p);
    r.push_back(2 * p + 1);
  }
  return r;
}

}  // namespace

// P = (P + P^T) / 2 in place, tile by tile: the same values as the expression (the sum is
// commutative) without a second matrix of the global map's size (docs/submaps.md, "How the host's
// join scales").
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

SamePoints same_points(const std::vector<std::pair<int, int>>& rows, const Eigen::VectorXd& X, const Eigen::MatrixXd& P,
                       double var) {
  SamePoints c;
  const auto k = static_cast<Eigen::Index>(rows.size());
  c.HP.resize(2 * k, P.cols());
  c.nu.resize(2 * k);
  c.S.resize(2 * k, 2 * k);
  for (Eigen::Index p = 0; p < k; ++p) {
    const auto [a, b] = rows[static_cast<std::size_t>(p)];
    c.HP.middleRows<2>(2 * p) = P.middleRows<2>(a) - P.middleRows<2>(b);
    c.nu.segment<2>(2 * p) = X.segment<2>(b) - X.segment<2>(a);
  }
  for (Eigen::Index p = 0; p < k; ++p) {
    const auto [a, b] = rows[static_cast<std::size_t>(p)];
    c.S.middleCols<2>(2 * p) = c.HP.middleCols<2>(a) - c.HP.middleCols<2>(b);
  }
  c.S = (0.5 * (c.S + c.S.transpose()) + var * Eigen::MatrixXd::Identity(2 * k, 2 * k)).eval();
  return c;
}

double joint_d2(const SamePoints& c, const std::vector<int>& in) {
  if (in.empty()) return 0.0;
  const std::vector<int> r = rows_of(in);
  const Eigen::LLT<Eigen::MatrixXd> l(c.S(r, r));
  const Eigen::VectorXd e = c.nu(r);
  return l.info() == Eigen::Success ? e.dot(l.solve(e)) : std::numeric_limits<double>::infinity();
}

bool fuse_same_points(const SamePoints& c, const std::vector<int>& in, Eigen::VectorXd& X, Eigen::MatrixXd& P) {
  if (in.empty()) return true;
  const std::vector<int> r = rows_of(in);
  const Eigen::LLT<Eigen::MatrixXd> llt(c.S(r, r));
  if (llt.info() != Eigen::Success) return false;
  const Eigen::MatrixXd HPi = c.HP(r, Eigen::indexing::all);
  const Eigen::MatrixXd K = llt.solve(HPi).transpose();  // P H^T S^-1
  X += K * c.nu(r);
  P.noalias() -= K * HPi;
  symmetrize(P);
  return true;
}

}  // namespace geojcbb::host
