// host_tools/mapping: the global map as a factor graph (docs/mapping.md, "The global map on the
// solver"). Variables: frames (x, y, theta: a local map's origin in the world) and landmarks (x, y).
// Factors: one per joined local map, on the frame it began at, the frame it ended at and the global
// landmarks it holds, weighted by the information the map's own scans gave (its prior divided out).
// Solved by Ceres Solver (sparse normal Cholesky, SuiteSparse), relinearised at every solve; joint
// marginals recovered exactly from a sparse Cholesky factor of the information J^T J at the solution.
// Host only: Ceres and SuiteSparse are linked here, never by the firmware library (docs/cmake.md).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

namespace ceres {
class CostFunction;
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
  GraphSolve solve(int iterations);

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
  /// variable no factor constrains).
  Eigen::MatrixXd marginal(const std::vector<int>& fs, const std::vector<int>& ls) const;

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
  /// Each factor's cost (owned by the problem), its variables and its loss (for the information).
  struct Factor {
    const ceres::CostFunction* cost;
    int from, to;
    std::vector<int> landmarks;
    double loss_d2;
  };
  std::vector<Factor> factor_list_;
  int factors_ = 0;
};

}  // namespace geojcbb::host
