// host_tools/mapping: the global map as a factor graph (docs/mapping.md, "The global map on the
// solver"). Variables: frames (x, y, theta: a local map's origin in the world) and landmarks (x, y).
// Factors: one per joined local map, on the frame it began at, the frame it ended at and the global
// landmarks it holds, weighted by the information the map's own scans gave (its prior divided out).
// Solved by Ceres Solver (sparse normal Cholesky, SuiteSparse), relinearised at every solve; joint
// marginals recovered exactly from a sparse Cholesky factor of the information J^T J at the solution.
// A fixed window in front (settle, solve_window): the factors behind the window are absorbed into one
// linear prior on the variables they share with the window (a Schur complement), so a join's solve
// and its marginal queries cost what the window holds, not the whole map.
// Host only: Ceres and SuiteSparse are linked here, never by the firmware library (docs/cmake.md).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

namespace ceres {
class CostFunction;
class LossFunction;
class Problem;
}  // namespace ceres

namespace geojcbb::host {

/// What a local map says of its frames and landmarks: with y = [the end frame in the start frame
/// (x, y, theta); each landmark in the start frame], the residual is W (y (-) y0) - c (theta's
/// difference wrapped), so ||residual||^2 is the map's negative log-likelihood up to a constant.
struct MapFactor {
  int from = 0;                ///< the frame the map began at
  int to = 0;                  ///< the frame it ended at
  std::vector<int> landmarks;  ///< the graph's landmarks, in y's order
  Eigen::VectorXd y0;          ///< the linearisation point of W and c (3 + 2 landmarks)
  Eigen::MatrixXd W;           ///< square root of the information (rows: the informed directions)
  Eigen::VectorXd c;
  /// Huber's loss on the factor's squared norm from this value on (0: none): a map that disagrees
  /// with the rest beyond it (a wrong pairing in its join) pulls linearly, not quadratically.
  double loss_d2 = 0;
};

/// r = W delta - c as the square root of a quadratic 1/2 delta^T L delta + g^T delta: W^T W = L in its
/// informed directions and W^T c = -g. L is scaled to a unit diagonal first (its diagonal floored at
/// `floor`), so a direction is uninformed (eigenvalue at most 1e-9) only against its own scale.
/// Throws when nothing is informed.
void square_root_information(const Eigen::MatrixXd& L, const Eigen::VectorXd& g, const Eigen::VectorXd& floor,
                             Eigen::MatrixXd& W, Eigen::VectorXd& c);

struct GraphSolve {
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
  double seconds = 0;
  bool usable = true;  ///< Ceres' verdict (a solution, converged or at the iteration limit)
};

class FactorGraph {
 public:
  FactorGraph();
  ~FactorGraph();
  FactorGraph(const FactorGraph&) = delete;
  FactorGraph& operator=(const FactorGraph&) = delete;

  /// A frame at `x`; the first one is the world's origin and held fixed. @return its index.
  int add_frame(const Eigen::Vector3d& x);
  /// A landmark at `l`. @return its index.
  int add_landmark(const Eigen::Vector2d& l);
  /// Adds a local map's factor (its frames and landmarks must exist).
  void add_map(const MapFactor& f);
  /// Relinearises and solves every variable, from the current estimate, for at most `iterations`.
  /// Drops the window's prior (unsettle): every factor is linearised anew.
  GraphSolve solve(int iterations);

  /// The fixed window in front. Absorbs every factor but the last `window` into the prior: one at a
  /// time, at the current estimate, each factor's information and gradient are added to the prior's and
  /// the variables no later factor touches are eliminated (Schur complement); the prior is then a linear
  /// factor on the variables the absorbed factors share with the window. Those eliminated stay where
  /// they are until a full solve. A step whose eliminated block is not positive definite is not taken
  /// (the window stays longer). O(window) per new factor; O(factors) after a full solve.
  void settle(int window);
  /// Solves the window only: the factors not absorbed and the prior, from the current estimate; the
  /// eliminated variables are untouched. The whole graph when nothing is absorbed.
  GraphSolve solve_window(int iterations);
  /// Drops the prior (every factor in the window again). add_map calls it when a new factor touches an
  /// eliminated variable (a loop closure into the past), solve() after relinearising everything.
  void unsettle();
  /// Factors absorbed into the prior.
  int settled() const { return settled_; }

  int frames() const { return static_cast<int>(frames_.size()); }
  int landmarks() const { return static_cast<int>(landmarks_.size()); }
  int factors() const { return factors_; }
  Eigen::Vector3d frame(int k) const;
  Eigen::Vector2d landmark(int j) const;

  /// The joint covariance of frames `fs` and landmarks `ls` (3 rows per frame, then 2 per landmark,
  /// in the order given) at the current estimate: the information J^T J factored with an ordering
  /// that eliminates every other variable first (approximate minimum degree), so the requested ones
  /// form the factor's trailing block L22 and their covariance is (L22 L22^T)^-1, exactly. The fixed
  /// first frame has zero covariance. Throws when the information is not positive definite (a
  /// variable no factor constrains). When every requested variable is in the window (not eliminated),
  /// the information is the window's factors' and the prior's only: the same marginal (the prior is the
  /// absorbed factors' Schur complement), exact at the linearisation the prior was absorbed at.
  Eigen::MatrixXd marginal(const std::vector<int>& fs, const std::vector<int>& ls) const;
  /// Whether the last marginal() was answered from the window (for the benchmark and the tests).
  bool last_marginal_windowed() const { return last_windowed_; }

  /// The solver's problem and the variables' blocks (for the test against ceres::Covariance).
  ceres::Problem& problem() const { return *problem_; }
  double* frame_block(int k) const;
  double* landmark_block(int j) const;

 private:
  struct Frame {
    double x[3];
  };
  struct Landmark {
    double x[2];
  };
  std::vector<std::unique_ptr<Frame>> frames_;  // stable addresses: the solver holds them
  std::vector<std::unique_ptr<Landmark>> landmarks_;
  std::unique_ptr<ceres::Problem> problem_;
  /// Each factor's cost and loss (owned by the problem), its variables and its loss threshold.
  struct Factor {
    ceres::CostFunction* cost;
    ceres::LossFunction* loss;
    int from, to;
    std::vector<int> landmarks;
    double loss_d2;
  };
  std::vector<Factor> factor_list_;
  int factors_ = 0;

  /// A variable: a frame (3 rows) or a landmark (2).
  struct Var {
    bool frame;
    int index;
    bool operator==(const Var& o) const { return frame == o.frame && index == o.index; }
  };
  double* block(Var v) const { return v.frame ? frame_block(v.index) : landmark_block(v.index); }
  static int dim(Var v) { return v.frame ? 3 : 2; }
  /// The variables of factor k, in its Jacobian's order (from, to, its landmarks).
  std::vector<Var> vars_of(const Factor& f) const;
  /// Factor f's robustified Jacobian over its variables and its residual at the current estimate.
  void linearise(const Factor& f, Eigen::MatrixXd& J, Eigen::VectorXd& r) const;
  /// The joint covariance of `want` (columns of `info`, -1: the fixed frame) from the n x n information
  /// given as triplets (each (a, b) entry once per contribution).
  static Eigen::MatrixXd marginal_of(std::vector<Eigen::Triplet<double>>& info, int n, const std::vector<int>& want);

  // The window's prior (settle): r = W (x (-) x0) - c on prior_vars_, the factors [0, settled_) absorbed.
  int settled_ = 0;
  std::vector<Var> prior_vars_;
  Eigen::VectorXd prior_x0_;
  Eigen::MatrixXd prior_W_;
  Eigen::VectorXd prior_c_;
  std::unique_ptr<ceres::CostFunction> prior_cost_;
  std::vector<bool> frame_gone_, landmark_gone_;  ///< eliminated into the prior
  std::vector<int> frame_last_, landmark_last_;   ///< the last factor that touches each variable
  mutable bool last_windowed_ = false;
};

}  // namespace geojcbb::host
