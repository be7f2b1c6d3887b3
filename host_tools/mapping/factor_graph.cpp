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

/// The window's prior: r = W (x (-) x0) - c over its variables stacked (a frame's theta wrapped).
class PriorCost final : public ceres::CostFunction {
 public:
  PriorCost(const std::vector<int>& dims, const std::vector<bool>& frame, Eigen::VectorXd x0, Eigen::MatrixXd W,
            Eigen::VectorXd c)
      : frame_(frame), x0_(std::move(x0)), W_(std::move(W)), c_(std::move(c)) {
    for (int d : dims) mutable_parameter_block_sizes()->push_back(d);
    set_num_residuals(static_cast<int>(W_.rows()));
  }

  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    Eigen::VectorXd delta(x0_.size());
    const auto& sizes = parameter_block_sizes();
    for (std::size_t b = 0, at = 0; b < sizes.size(); at += static_cast<std::size_t>(sizes[b]), ++b) {
      for (int a = 0; a < sizes[b]; ++a) {
        const auto i = static_cast<Eigen::Index>(at) + a;
        delta(i) = p[b][a] - x0_(i);
        if (frame_[b] && a == 2) delta(i) = wrap_angle(delta(i));
      }
    }
    const auto r = W_.rows();
    Eigen::Map<Eigen::VectorXd>(residuals, r) = W_ * delta - c_;
    if (jacobians == nullptr) return true;
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    for (std::size_t b = 0, at = 0; b < sizes.size(); at += static_cast<std::size_t>(sizes[b]), ++b) {
      if (jacobians[b] != nullptr)
        Eigen::Map<RowMajor>(jacobians[b], r, sizes[b]) = W_.middleCols(static_cast<Eigen::Index>(at), sizes[b]);
    }
    return true;
  }

 private:
  std::vector<bool> frame_;
  Eigen::VectorXd x0_;
  Eigen::MatrixXd W_;
  Eigen::VectorXd c_;
};

ceres::Solver::Options solver_options(int iterations) {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  o.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  o.max_num_iterations = iterations;
  o.num_threads = 1;  // the same answer on every machine and run
  o.logging_type = ceres::SILENT;
  return o;
}

}  // namespace

void square_root_information(const Eigen::MatrixXd& L, const Eigen::VectorXd& g, const Eigen::VectorXd& floor,
                             Eigen::MatrixXd& W, Eigen::VectorXd& c) {
  const Eigen::MatrixXd Lsym = 0.5 * (L + L.transpose());
  Eigen::VectorXd scale(Lsym.rows());
  for (Eigen::Index a = 0; a < Lsym.rows(); ++a) scale(a) = std::sqrt(std::max(Lsym(a, a), floor(a)));
  const Eigen::VectorXd inv_scale = scale.cwiseInverse();
  const Eigen::MatrixXd Ls = inv_scale.asDiagonal() * Lsym * inv_scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Ls);
  std::vector<int> dirs;
  for (Eigen::Index e = 0; e < Ls.rows(); ++e)
    if (eig.eigenvalues()(e) > 1e-9) dirs.push_back(static_cast<int>(e));
  if (dirs.empty()) throw std::runtime_error("square_root_information: nothing is informed");
  const auto r = static_cast<Eigen::Index>(dirs.size());
  W.resize(r, Lsym.cols());
  c.resize(r);
  const Eigen::VectorXd gs = inv_scale.cwiseProduct(g);
  for (Eigen::Index q = 0; q < r; ++q) {
    const double lambda = eig.eigenvalues()(dirs[static_cast<std::size_t>(q)]);
    const Eigen::VectorXd vq = eig.eigenvectors().col(dirs[static_cast<std::size_t>(q)]);
    W.row(q) = std::sqrt(lambda) * vq.cwiseProduct(scale).transpose();
    c(q) = -vq.dot(gs) / std::sqrt(lambda);
  }
}

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
  frame_gone_.push_back(false);
  frame_last_.push_back(-1);
  return frames() - 1;
}

int FactorGraph::add_landmark(const Eigen::Vector2d& l) {
  landmarks_.push_back(std::make_unique<Landmark>(Landmark{{l(0), l(1)}}));
  problem_->AddParameterBlock(landmarks_.back()->x, 2);
  landmark_gone_.push_back(false);
  landmark_last_.push_back(-1);
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
  factor_list_.push_back({cost, loss, f.from, f.to, f.landmarks, f.loss_d2});
  // A factor on an eliminated variable reaches behind the window: the prior cannot hold it.
  bool past = frame_gone_[static_cast<std::size_t>(f.from)] || frame_gone_[static_cast<std::size_t>(f.to)];
  for (int j : f.landmarks) past = past || landmark_gone_[static_cast<std::size_t>(j)];
  if (past) unsettle();
  frame_last_[static_cast<std::size_t>(f.from)] = frame_last_[static_cast<std::size_t>(f.to)] = factors_;
  for (int j : f.landmarks) landmark_last_[static_cast<std::size_t>(j)] = factors_;
  ++factors_;
}

GraphSolve FactorGraph::solve(int iterations) {
  GraphSolve out;
  unsettle();
  if (factors_ == 0) return out;
  const ceres::Solver::Options o = solver_options(iterations);
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

std::vector<FactorGraph::Var> FactorGraph::vars_of(const Factor& f) const {
  std::vector<Var> v = {{true, f.from}, {true, f.to}};
  v.reserve(2 + f.landmarks.size());
  for (int j : f.landmarks) v.push_back({false, j});
  return v;
}

void FactorGraph::linearise(const Factor& f, Eigen::MatrixXd& J, Eigen::VectorXd& r) const {
  const std::vector<Var> vs = vars_of(f);
  const int rows = f.cost->num_residuals();
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  std::vector<RowMajor> blocks(vs.size());
  std::vector<double*> jac(vs.size());
  std::vector<const double*> params(vs.size());
  int d = 0;
  for (std::size_t b = 0; b < vs.size(); ++b) {
    blocks[b].resize(rows, dim(vs[b]));
    jac[b] = blocks[b].data();
    params[b] = block(vs[b]);
    d += dim(vs[b]);
  }
  r.resize(rows);
  if (!f.cost->Evaluate(params.data(), r.data(), jac.data())) throw std::runtime_error("linearise: evaluation failed");
  J.resize(rows, d);
  for (std::size_t b = 0, c = 0; b < vs.size(); c += static_cast<std::size_t>(dim(vs[b])), ++b)
    J.middleCols(static_cast<Eigen::Index>(c), dim(vs[b])) = blocks[b];
  // With Huber's loss beyond its threshold, J and r scaled by sqrt(rho'(s)), as Ceres' corrector does
  // where rho'' < 0 (the robustified Jacobian the solver and ceres::Covariance see).
  const double s2 = r.squaredNorm();
  if (f.loss_d2 > 0 && s2 > f.loss_d2) {
    const double k = std::sqrt(std::sqrt(f.loss_d2 / s2));  // rho'(s) = sqrt(a^2 / s)
    J *= k;
    r *= k;
  }
}

Eigen::MatrixXd FactorGraph::marginal_of(std::vector<Eigen::Triplet<double>>& info, int n,
                                         const std::vector<int>& want) {
  const int q = static_cast<int>(want.size());
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(q, q);
  if (n == 0) return out;
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

Eigen::MatrixXd FactorGraph::marginal(const std::vector<int>& fs, const std::vector<int>& ls) const {
  const int nf = frames(), nl = landmarks();
  for (int k : fs)
    if (k < 0 || k >= nf) throw std::out_of_range("marginal: no such frame");
  for (int j : ls)
    if (j < 0 || j >= nl) throw std::out_of_range("marginal: no such landmark");
  // From the window when every requested variable is in it; else from every factor.
  bool window = settled_ > 0;
  for (int k : fs) window = window && !frame_gone_[static_cast<std::size_t>(k)];
  for (int j : ls) window = window && !landmark_gone_[static_cast<std::size_t>(j)];
  last_windowed_ = window;
  // The system's columns: every variable in it but the fixed first frame (-1).
  std::vector<int> frame_col(static_cast<std::size_t>(nf), -1), landmark_col(static_cast<std::size_t>(nl), -1);
  int n = 0;
  for (int k = 1; k < nf; ++k) {
    if (window && frame_gone_[static_cast<std::size_t>(k)]) continue;
    frame_col[static_cast<std::size_t>(k)] = n;
    n += 3;
  }
  for (int j = 0; j < nl; ++j) {
    if (window && landmark_gone_[static_cast<std::size_t>(j)]) continue;
    landmark_col[static_cast<std::size_t>(j)] = n;
    n += 2;
  }
  auto col = [&](Var v) {
    return v.frame ? frame_col[static_cast<std::size_t>(v.index)] : landmark_col[static_cast<std::size_t>(v.index)];
  };
  // The query's columns, in its order (-1: a row of the fixed frame, whose covariance is zero).
  std::vector<int> want;
  want.reserve(3 * fs.size() + 2 * ls.size());
  for (int k : fs)
    for (int a = 0; a < 3; ++a) want.push_back(k == 0 ? -1 : col({true, k}) + a);
  for (int j : ls)
    for (int a = 0; a < 2; ++a) want.push_back(col({false, j}) + a);
  // The information J^T J at the estimate, factor by factor (each one's Jacobian is dense over its
  // variables), and the prior's W^T W.
  std::vector<Eigen::Triplet<double>> info;
  auto add = [&](const Eigen::MatrixXd& J, const std::vector<Var>& vs) {
    std::vector<int> at;  // J's column -> the information's (-1: the fixed frame)
    at.reserve(static_cast<std::size_t>(J.cols()));
    for (Var v : vs)
      for (int a = 0; a < dim(v); ++a) at.push_back(col(v) < 0 ? -1 : col(v) + a);
    const Eigen::MatrixXd H = J.transpose() * J;
    for (Eigen::Index a = 0; a < H.rows(); ++a) {
      for (Eigen::Index b = 0; b < H.cols(); ++b) {
        const int ra = at[static_cast<std::size_t>(a)], rb = at[static_cast<std::size_t>(b)];
        if (ra >= 0 && rb >= 0) info.emplace_back(ra, rb, H(a, b));
      }
    }
  };
  const std::size_t first = window ? static_cast<std::size_t>(settled_) : 0;
  std::size_t entries = static_cast<std::size_t>(prior_W_.cols() * prior_W_.cols());
  for (std::size_t k = first; k < factor_list_.size(); ++k)
    entries += (6 + 2 * factor_list_[k].landmarks.size()) * (6 + 2 * factor_list_[k].landmarks.size());
  info.reserve(entries);
  for (std::size_t k = first; k < factor_list_.size(); ++k) {
    Eigen::MatrixXd J;
    Eigen::VectorXd r;
    linearise(factor_list_[k], J, r);
    add(J, vars_of(factor_list_[k]));
  }
  if (window) add(prior_W_, prior_vars_);
  return marginal_of(info, n, want);
}

void FactorGraph::unsettle() {
  settled_ = 0;
  prior_vars_.clear();
  prior_x0_.resize(0);
  prior_W_.resize(0, 0);
  prior_c_.resize(0);
  prior_cost_.reset();
  std::fill(frame_gone_.begin(), frame_gone_.end(), false);
  std::fill(landmark_gone_.begin(), landmark_gone_.end(), false);
}

void FactorGraph::settle(int window) {
  for (int k = settled_; k < factors_ - std::max(window, 0); ++k) {  // one factor at a time, oldest first
    const Factor& f = factor_list_[static_cast<std::size_t>(k)];
    // The variables: the prior's, then the factor's others (the fixed first frame is none).
    std::vector<Var> u = prior_vars_;
    const std::vector<Var> fv = vars_of(f);
    for (Var v : fv)
      if (!(v.frame && v.index == 0) && std::find(u.begin(), u.end(), v) == u.end()) u.push_back(v);
    std::vector<Eigen::Index> at(u.size());
    Eigen::Index n = 0;
    for (std::size_t a = 0; a < u.size(); ++a) {
      at[a] = n;
      n += dim(u[a]);
    }
    auto at_of = [&](Var v) { return at[static_cast<std::size_t>(std::find(u.begin(), u.end(), v) - u.begin())]; };
    // 1/2 delta^T H delta + b^T delta: the prior's (at its own linearisation point) and the factor's.
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
    if (!prior_vars_.empty()) {
      const auto m = prior_x0_.size();
      Eigen::VectorXd r(prior_W_.rows());
      std::vector<const double*> p(prior_vars_.size());
      for (std::size_t a = 0; a < prior_vars_.size(); ++a) p[a] = block(prior_vars_[a]);
      if (!prior_cost_->Evaluate(p.data(), r.data(), nullptr)) throw std::runtime_error("settle: evaluation failed");
      H.topLeftCorner(m, m) += prior_W_.transpose() * prior_W_;
      b.head(m) += prior_W_.transpose() * r;
    }
    Eigen::MatrixXd J;
    Eigen::VectorXd r;
    linearise(f, J, r);
    std::vector<Eigen::Index> cols;  // J's columns -> H's (-1: the fixed frame)
    cols.reserve(static_cast<std::size_t>(J.cols()));
    for (Var v : fv)
      for (int a = 0; a < dim(v); ++a) cols.push_back(v.frame && v.index == 0 ? -1 : at_of(v) + a);
    const Eigen::MatrixXd Hf = J.transpose() * J;
    const Eigen::VectorXd bf = J.transpose() * r;
    for (Eigen::Index a = 0; a < J.cols(); ++a) {
      const Eigen::Index ra = cols[static_cast<std::size_t>(a)];
      if (ra < 0) continue;
      b(ra) += bf(a);
      for (Eigen::Index c = 0; c < J.cols(); ++c)
        if (cols[static_cast<std::size_t>(c)] >= 0) H(ra, cols[static_cast<std::size_t>(c)]) += Hf(a, c);
    }
    // Eliminate the variables no later factor touches; the rest are the new prior's.
    std::vector<Var> keep_vars;
    std::vector<int> keep, drop;
    for (std::size_t a = 0; a < u.size(); ++a) {
      const Var v = u[a];
      const int last =
          v.frame ? frame_last_[static_cast<std::size_t>(v.index)] : landmark_last_[static_cast<std::size_t>(v.index)];
      std::vector<int>& to = last > k ? keep : drop;
      for (int c = 0; c < dim(v); ++c) to.push_back(static_cast<int>(at[a]) + c);
      if (last > k) keep_vars.push_back(v);
    }
    Eigen::MatrixXd Hk = H(keep, keep);
    Eigen::VectorXd bk = b(keep);
    if (!drop.empty()) {
      const Eigen::LLT<Eigen::MatrixXd> ld(H(drop, drop));
      if (ld.info() != Eigen::Success) return;  // not absorbed: the window stays longer
      const Eigen::MatrixXd Hkd = H(keep, drop);
      Hk -= Hkd * ld.solve(Hkd.transpose());
      bk -= Hkd * ld.solve(b(drop));
    }
    Eigen::MatrixXd W;
    Eigen::VectorXd c, x0(static_cast<Eigen::Index>(keep.size()));
    if (!keep.empty()) {
      // The prior's square root by Cholesky (W = L^T, c = -L^-1 b), every direction kept: its
      // information on the absolute position of what it holds is all that anchors the window, and
      // after a long chain it is 10^-8 of the relative one (a threshold would drop it). The informed
      // directions of an eigendecomposition only when Hk is not positive definite.
      const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (Hk + Hk.transpose()));
      if (llt.info() == Eigen::Success) {
        W = llt.matrixU();
        c = -llt.matrixL().solve(bk);
      } else {
        const Eigen::VectorXd floor = (1e-12 * Hk.diagonal().cwiseAbs()).array() + 1e-300;
        square_root_information(Hk, bk, floor, W, c);
      }
    }
    std::vector<int> dims;
    std::vector<bool> is_frame;
    for (std::size_t a = 0, i = 0; a < keep_vars.size(); ++a) {
      const double* x = block(keep_vars[a]);
      for (int e = 0; e < dim(keep_vars[a]); ++e) x0(static_cast<Eigen::Index>(i++)) = x[e];
      dims.push_back(dim(keep_vars[a]));
      is_frame.push_back(keep_vars[a].frame);
    }
    for (Var v : u)
      if (std::find(keep_vars.begin(), keep_vars.end(), v) == keep_vars.end())
        (v.frame ? frame_gone_ : landmark_gone_)[static_cast<std::size_t>(v.index)] = true;
    prior_vars_ = std::move(keep_vars);
    prior_x0_ = x0;
    prior_W_ = W;
    prior_c_ = c;
    prior_cost_ = keep.empty() ? nullptr : std::make_unique<PriorCost>(dims, is_frame, x0, W, c);
    settled_ = k + 1;
  }
}

GraphSolve FactorGraph::solve_window(int iterations) {
  if (settled_ == 0) return solve(iterations);
  GraphSolve out;
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.enable_fast_removal = false;
  ceres::Problem p(po);
  for (std::size_t k = static_cast<std::size_t>(settled_); k < factor_list_.size(); ++k) {
    const Factor& f = factor_list_[k];
    std::vector<double*> blocks;
    for (Var v : vars_of(f)) blocks.push_back(block(v));
    p.AddResidualBlock(f.cost, f.loss, blocks);
  }
  if (prior_cost_) {
    std::vector<double*> blocks;
    blocks.reserve(prior_vars_.size());
    for (Var v : prior_vars_) blocks.push_back(block(v));
    p.AddResidualBlock(prior_cost_.get(), nullptr, blocks);
  }
  if (p.HasParameterBlock(frames_.front()->x)) p.SetParameterBlockConstant(frames_.front()->x);
  const ceres::Solver::Options o = solver_options(iterations);
  ceres::Solver::Summary s;
  const auto t0 = std::chrono::steady_clock::now();
  ceres::Solve(o, &p, &s);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.iterations = static_cast<int>(s.iterations.size()) - 1;
  out.initial_cost = s.initial_cost;
  out.final_cost = s.final_cost;
  out.usable = s.IsSolutionUsable();
  for (std::size_t k = 0; k < frames_.size(); ++k)
    if (!frame_gone_[k]) frames_[k]->x[2] = wrap_angle(frames_[k]->x[2]);
  return out;
}

}  // namespace geojcbb::host
