// host_tools/mapping: the global map as a factor graph (factor_graph.hpp).
#include "geojcbb_host/factor_graph.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "geojcbb/core/math.hpp"

namespace geojcbb::host {

namespace {

/// A local map's factor (MapFactor) with its Jacobians in closed form: y's rows are the end frame in
/// the start frame, R(theta_f)^T (t_to - t_f) and theta_to - theta_f, then each landmark there,
/// R(theta_f)^T (g - t_f).
class MapCost final : public ceres::CostFunction {
 public:
  explicit MapCost(const MapFactor& f) : y0_(f.y0), W_(f.W), c_(f.c), n_(static_cast<int>(f.landmarks.size())) {
    mutable_parameter_block_sizes()->push_back(3);
    mutable_parameter_block_sizes()->push_back(3);
    for (int j = 0; j < n_; ++j) mutable_parameter_block_sizes()->push_back(2);
    set_num_residuals(static_cast<int>(W_.rows()));
  }

  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    const double* f = p[0];
    const double* t = p[1];
    const double c = std::cos(f[2]), s = std::sin(f[2]);
    const int d = 3 + 2 * n_;
    Eigen::VectorXd delta(d);
    // D: d delta / d [from, to], and per landmark its 2 x 3 block on `from` (its block on itself is R^T).
    Eigen::Matrix<double, 3, 6> Dft = Eigen::Matrix<double, 3, 6>::Zero();
    Eigen::Matrix2d Rt;
    Rt << c, s, -s, c;
    const Eigen::Vector2d pe = Rt * Eigen::Vector2d(t[0] - f[0], t[1] - f[1]);
    delta.head<2>() = pe - y0_.head<2>();
    delta(2) = wrap_angle(t[2] - f[2] - y0_(2));
    Dft.block<2, 2>(0, 0) = -Rt;
    Dft.block<2, 1>(0, 2) << pe.y(), -pe.x();
    Dft.block<2, 2>(0, 3) = Rt;
    Dft(2, 2) = -1;
    Dft(2, 5) = 1;
    Eigen::MatrixXd Dl(2 * n_, 3);
    for (int j = 0; j < n_; ++j) {
      const double* g = p[2 + j];
      const Eigen::Vector2d l = Rt * Eigen::Vector2d(g[0] - f[0], g[1] - f[1]);
      delta.segment<2>(3 + 2 * j) = l - y0_.segment<2>(3 + 2 * j);
      Dl.block<2, 2>(2 * j, 0) = -Rt;
      Dl.block<2, 1>(2 * j, 2) << l.y(), -l.x();
    }
    const auto r = W_.rows();
    Eigen::Map<Eigen::VectorXd>(residuals, r) = W_ * delta - c_;
    if (jacobians == nullptr) return true;
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    if (jacobians[0] != nullptr) {
      Eigen::Map<RowMajor> J(jacobians[0], r, 3);
      J = W_.leftCols<3>() * Dft.leftCols<3>() + W_.middleCols(3, 2 * n_) * Dl;
    }
    if (jacobians[1] != nullptr) Eigen::Map<RowMajor>(jacobians[1], r, 3) = W_.leftCols<3>() * Dft.rightCols<3>();
    for (int j = 0; j < n_; ++j) {
      if (jacobians[2 + j] != nullptr) Eigen::Map<RowMajor>(jacobians[2 + j], r, 2) = W_.middleCols<2>(3 + 2 * j) * Rt;
    }
    return true;
  }

 private:
  Eigen::VectorXd y0_;
  Eigen::MatrixXd W_;
  Eigen::VectorXd c_;
  int n_;
};

}  // namespace

FactorGraph::FactorGraph() {
  ceres::Problem::Options o;
  o.enable_fast_removal = false;
  problem_ = std::make_unique<ceres::Problem>(o);
}

FactorGraph::~FactorGraph() = default;

int FactorGraph::add_frame(const Eigen::Vector3d& x) {
  frames_.push_back(std::make_unique<Frame>(Frame{{x(0), x(1), x(2)}}));
  problem_->AddParameterBlock(frames_.back()->x, 3);
  if (frames_.size() == 1) problem_->SetParameterBlockConstant(frames_.back()->x);
  return frames() - 1;
}

int FactorGraph::add_landmark(const Eigen::Vector2d& l) {
  landmarks_.push_back(std::make_unique<Landmark>(Landmark{{l(0), l(1)}}));
  problem_->AddParameterBlock(landmarks_.back()->x, 2);
  return landmarks() - 1;
}

double* FactorGraph::frame_block(int k) const { return frames_.at(static_cast<std::size_t>(k))->x; }
double* FactorGraph::landmark_block(int j) const { return landmarks_.at(static_cast<std::size_t>(j))->x; }

Eigen::Vector3d FactorGraph::frame(int k) const {
  const double* x = frames_.at(static_cast<std::size_t>(k))->x;
  return {x[0], x[1], x[2]};
}

Eigen::Vector2d FactorGraph::landmark(int j) const {
  const double* x = landmarks_.at(static_cast<std::size_t>(j))->x;
  return {x[0], x[1]};
}

void FactorGraph::add_map(const MapFactor& f) {
  const auto n = static_cast<Eigen::Index>(f.landmarks.size());
  if (f.y0.size() != 3 + 2 * n || f.W.cols() != f.y0.size() || f.c.size() != f.W.rows() || f.W.rows() == 0) {
    throw std::invalid_argument("add_map: a factor whose sizes do not match its landmarks");
  }
  std::vector<double*> blocks = {frame_block(f.from), frame_block(f.to)};
  for (int j : f.landmarks) blocks.push_back(landmark_block(j));
  ceres::LossFunction* loss = f.loss_d2 > 0 ? new ceres::HuberLoss(std::sqrt(f.loss_d2)) : nullptr;
  auto* cost = new MapCost(f);
  problem_->AddResidualBlock(cost, loss, blocks);
  factor_list_.push_back({cost, f.from, f.to, f.landmarks, f.loss_d2});
  ++factors_;
}

GraphSolve FactorGraph::solve(int iterations) {
  GraphSolve out;
  if (factors_ == 0) return out;
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  o.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  o.max_num_iterations = iterations;
  o.num_threads = 1;  // the same answer on every machine and run
  o.logging_type = ceres::SILENT;
  ceres::Solver::Summary s;
  const auto t0 = std::chrono::steady_clock::now();
  ceres::Solve(o, problem_.get(), &s);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.iterations = static_cast<int>(s.iterations.size()) - 1;
  out.initial_cost = s.initial_cost;
  out.final_cost = s.final_cost;
  out.usable = s.IsSolutionUsable();
  for (auto& fr : frames_) fr->x[2] = wrap_angle(fr->x[2]);
  return out;
}

Eigen::MatrixXd FactorGraph::marginal(const std::vector<int>& fs, const std::vector<int>& ls) const {
  // The free variables' columns: every frame but the first (fixed), then every landmark.
  const int nf = frames(), nl = landmarks();
  auto frame_col = [&](int k) { return 3 * (k - 1); };
  auto landmark_col = [&](int j) { return 3 * (nf - 1) + 2 * j; };
  const int n = 3 * (nf - 1) + 2 * nl;
  // The query's columns, in its order (-1: a row of the fixed frame, whose covariance is zero).
  std::vector<int> want;
  for (int k : fs) {
    if (k < 0 || k >= nf) throw std::out_of_range("marginal: no such frame");
    for (int a = 0; a < 3; ++a) want.push_back(k == 0 ? -1 : frame_col(k) + a);
  }
  for (int j : ls) {
    if (j < 0 || j >= nl) throw std::out_of_range("marginal: no such landmark");
    for (int a = 0; a < 2; ++a) want.push_back(landmark_col(j) + a);
  }
  const int q = static_cast<int>(want.size());
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(q, q);
  if (n == 0) return out;
  // The information J^T J at the estimate, factor by factor (each one's Jacobian is dense over its
  // variables): with Huber's loss beyond its threshold, J scaled by sqrt(rho'(s)), as Ceres' corrector
  // does where rho'' < 0 (the robustified Jacobian the solver and ceres::Covariance see).
  std::vector<Eigen::Triplet<double>> info;
  std::size_t entries = 0;
  for (const Factor& f : factor_list_)
    entries += static_cast<std::size_t>((6 + 2 * f.landmarks.size()) * (6 + 2 * f.landmarks.size()));
  info.reserve(entries);
  for (const Factor& f : factor_list_) {
    std::vector<const double*> params = {frames_[static_cast<std::size_t>(f.from)]->x,
                                         frames_[static_cast<std::size_t>(f.to)]->x};
    std::vector<int> col = {f.from == 0 ? -1 : frame_col(f.from), f.to == 0 ? -1 : frame_col(f.to)};
    std::vector<int> size = {3, 3};
    for (int j : f.landmarks) {
      params.push_back(landmarks_[static_cast<std::size_t>(j)]->x);
      col.push_back(landmark_col(j));
      size.push_back(2);
    }
    const int r = f.cost->num_residuals(), d = 3 + 3 + 2 * static_cast<int>(f.landmarks.size());
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    std::vector<RowMajor> blocks(params.size());
    std::vector<double*> jac(params.size());
    for (std::size_t b = 0; b < params.size(); ++b) {
      blocks[b].resize(r, size[b]);
      jac[b] = blocks[b].data();
    }
    Eigen::VectorXd res(r);
    if (!f.cost->Evaluate(params.data(), res.data(), jac.data()))
      throw std::runtime_error("marginal: evaluation failed");
    Eigen::MatrixXd J(r, d);
    std::vector<int> at;  // J's column -> the information's (-1: the fixed frame)
    for (std::size_t b = 0, c = 0; b < params.size(); c += static_cast<std::size_t>(size[b]), ++b) {
      J.middleCols(static_cast<Eigen::Index>(c), size[b]) = blocks[b];
      for (int a = 0; a < size[b]; ++a) at.push_back(col[b] < 0 ? -1 : col[b] + a);
    }
    const double s2 = res.squaredNorm();
    if (f.loss_d2 > 0 && s2 > f.loss_d2) J *= std::sqrt(std::sqrt(f.loss_d2 / s2));  // rho'(s) = sqrt(a^2 / s)
    const Eigen::MatrixXd H = J.transpose() * J;
    for (int a = 0; a < d; ++a) {
      for (int b = 0; b < d; ++b) {
        if (at[static_cast<std::size_t>(a)] >= 0 && at[static_cast<std::size_t>(b)] >= 0)
          info.emplace_back(at[static_cast<std::size_t>(a)], at[static_cast<std::size_t>(b)], H(a, b));
      }
    }
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(info.begin(), info.end());
  info = {};
  // The elimination order: the minimum-degree order of the others, then the query's variables.
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> amd;
  Eigen::AMDOrdering<int>()(A, amd);
  std::vector<int> pos(static_cast<std::size_t>(n), -1);
  int next = 0;
  std::vector<bool> queried(static_cast<std::size_t>(n), false);
  for (int w : want)
    if (w >= 0) queried[static_cast<std::size_t>(w)] = true;
  for (int k = 0; k < n; ++k) {
    const int v = amd.indices()(k);
    if (!queried[static_cast<std::size_t>(v)]) pos[static_cast<std::size_t>(v)] = next++;
  }
  const int tail = next;
  std::vector<int> want_pos(static_cast<std::size_t>(q), -1);
  for (int a = 0; a < q; ++a) {
    const int w = want[static_cast<std::size_t>(a)];
    if (w < 0) continue;
    if (pos[static_cast<std::size_t>(w)] < 0) pos[static_cast<std::size_t>(w)] = next++;
    want_pos[static_cast<std::size_t>(a)] = pos[static_cast<std::size_t>(w)];
  }
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(A.nonZeros()));
  for (int c = 0; c < A.outerSize(); ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it) {
      const int r = pos[static_cast<std::size_t>(it.row())], cc = pos[static_cast<std::size_t>(c)];
      if (r >= cc) t.emplace_back(r, cc, it.value());
    }
  }
  Eigen::SparseMatrix<double> Ap(n, n);
  Ap.setFromTriplets(t.begin(), t.end());
  const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>> llt(Ap);
  if (llt.info() != Eigen::Success) throw std::runtime_error("marginal: the information is not positive definite");
  const int d = n - tail;
  const Eigen::SparseMatrix<double> L = llt.matrixL();
  const Eigen::MatrixXd L22 = Eigen::MatrixXd(L.bottomRightCorner(d, d));
  const Eigen::MatrixXd Linv = L22.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(d, d));
  const Eigen::MatrixXd S = Linv.transpose() * Linv;  // (L22 L22^T)^-1
  for (int a = 0; a < q; ++a) {
    for (int b = 0; b < q; ++b) {
      const int pa = want_pos[static_cast<std::size_t>(a)], pb = want_pos[static_cast<std::size_t>(b)];
      if (pa >= 0 && pb >= 0) out(a, b) = S(pa - tail, pb - tail);
    }
  }
  return out;
}

}  // namespace geojcbb::host
