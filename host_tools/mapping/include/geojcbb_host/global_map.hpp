// host_tools/mapping: the global map of sequential map joining (Tardos, Neira, Newman, Leonard 2002;
// docs/submaps.md). The device (or the in-process step) keeps a local map of bounded size, closes it
// on a rule (StepSettings::submap_*), hands it over whole and starts the next one at the robot's
// pose, empty. The local maps are therefore independent: each is built from its own scans only,
// in its own frame, whose origin is the previous map's last robot pose. The host joins each as it
// arrives:
//   1. transform: the map's landmarks and its last robot pose into the global frame through the
//      base (the previous map's last pose, a state of the global map), every correlation kept
//   2. associate: the library's own association (a preset) between the new landmarks (as
//      range-bearing "observations" from the base, R their covariance) and the global landmarks
//      near them (as predictions from the base, C = H P H^T)
//   3. test: the pairs' constraints l_new - l_global = 0 jointly, with the full covariance; a join
//      that is not jointly compatible is refused (every landmark kept apart), and pairings the
//      association declines as ambiguous (a runner-up within join_margin_d2) are kept apart
//   4. fuse: the constraints as one update, the duplicates removed (marginalised); the new
//      landmarks not paired stay; the base becomes the map's last pose.
// While a map is built the host may seed it (seed(), seeded()) with the global landmarks near the
// robot that it does not hold; their prior is divided out at the join like the carried ones'.
// The state is held one of two ways (JoinOptions::solver): dense (Eigen, the full covariance, O(D^2)
// per join for D = 3 + 2 landmarks), or as a factor graph (factor_graph.hpp): each joined map one
// factor, relinearised by Ceres at every join, with the joint marginals the join reads recovered
// exactly from a sparse factorisation (docs/mapping.md). The join's decisions are the same code on
// both: they read the base, the landmarks near the map and their joint covariance (a view).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/presets.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb_host/factor_graph.hpp"
#include "geojcbb_host/join_counts.hpp"

namespace geojcbb::host {

/// One closed local map as handed over: its last robot pose and its landmarks in its own frame
/// (origin: the robot's pose when it began), with their covariance.
struct Submap {
  int index = 0;               ///< the map's number (0, 1, ...)
  std::vector<FeatureId> ids;  ///< landmark ids (never reused across maps)
  /// Per landmark: confirmed by its evidence (ekf::LandmarkPolicy). A tentative one joins the global
  /// map only when it is paired with a global landmark; otherwise it is dropped (marginalised).
  std::vector<bool> confirmed;
  /// Per landmark: its log-odds of existence at the hand-over (ekf::LandmarkPolicy). The global map
  /// keeps it: a seed starts from it, and a seed the map took and removed by its evidence (missed
  /// where it was expected) leaves the global map.
  std::vector<double> exist_nats;
  /// Per landmark: kept into the next map (SUBMAP's `carried`, node::SlamStep::carried); empty when
  /// not known. One the next map no longer holds at its hand-over was removed there by its evidence
  /// (JoinOptions::remove_carried: it leaves the global map, as a seed the map took does).
  std::vector<bool> carried;
  Eigen::VectorXd x;  ///< [x_r, y_r, theta_r, l_1x, l_1y, ...], 3 + 2 ids.size()
  Eigen::MatrixXd P;  ///< its covariance
  int landmarks() const { return static_cast<int>(ids.size()); }
};

/// A closed map read from the filter that holds it (the state and covariance as they are).
template <typename T, class B>
Submap submap_of(const ekf::Slam<T, B>& slam, int index) {
  Submap m;
  m.index = index;
  const int n = slam.dim();
  m.x.resize(n);
  m.P.resize(n, n);
  for (int r = 0; r < n; ++r) {
    m.x(r) = static_cast<double>(slam.x(r));
    for (int c = 0; c < n; ++c) m.P(r, c) = static_cast<double>(slam.cov(r, c));
  }
  for (int j = 0; j < slam.landmarks(); ++j) {
    m.ids.push_back(slam.id(j));
    m.confirmed.push_back(slam.confirmed(j));
    m.exist_nats.push_back(static_cast<double>(slam.existence(j)));
  }
  return m;
}

/// A pose of a frame's, `local`, in the world through the frame's origin `o`: o (+) local, and its
/// covariance from the two (uncorrelated: a local map begins with its origin exact).
void compose(const Eigen::Vector3d& o, const Eigen::Matrix3d& P_o, const Pose2<double>& local,
             const Eigen::Matrix3d& P_local, Pose2<double>& global, Eigen::Matrix3d& P_global);

struct JoinOptions {
  /// The association between maps: PCJCBB, whose pose-free seed takes over when the base pose is
  /// uncertain (a long chain of maps, another robot's).
  Preset preset{Strategy::kPcjcbb, 0};
  double confidence = 0.99;         ///< of the individual and joint tests
  double margin_d2 = 6.0;           ///< ambiguity: a runner-up within this joint d2 (2 x loop_margin_nats)
  double constraint_var_m2 = 1e-6;  ///< the fused constraint's noise, as ekf::Slam::merge's
  /// The association's pairings tested again with the full covariance (the local map's own
  /// correlations, which the association leaves out): only a jointly compatible subset is fused.
  bool joint_check = true;
  /// A landmark the local map was born with (carried over: Submap::carried of the map before) and no
  /// longer holds at its join leaves the global map, as a removed seed does. Off by default: on
  /// Victoria Park through the default-bounds device it set off a chain of maps born full
  /// (docs/submaps.md, "Carried landmarks removed").
  bool remove_carried = false;
  /// How the global state is held and fused: kDense, the EKF-style join (one linearisation, the full
  /// covariance); kGraph, the local maps as factors solved by Ceres and relinearised at every join.
  enum class Solver { kDense, kGraph };
  Solver solver = Solver::kDense;
  int solver_iterations = 20;  ///< kGraph: Ceres' iterations per join at most
  /// kGraph: the fixed window in front (docs/mapping.md): a join solves and queries its last
  /// `solver_window` local maps' factors and a prior that holds the older ones (FactorGraph::settle);
  /// a map that reaches behind the window (a loop closure) solves everything again. 0: every join
  /// relinearises and solves every factor.
  int solver_window = 8;
  /// kGraph: Huber's loss on a map's factor beyond chi2(loss_confidence, its dimension) (0: none).
  double loss_confidence = 0;
};

/// What one join did, and its pairs.
struct JoinResult : JoinCounts {
  /// The fused pairs: (local id, the global landmark's first id).
  std::vector<std::pair<FeatureId, FeatureId>> pairs;
};

/// Global landmarks given to the local map (its seed): their means in the base's frame (the map's
/// origin) and their covariance there, block-diagonal (each one's marginal, as SUBMAP_SEED carries it).
struct Seed {
  std::vector<FeatureId> first_ids;  ///< the global landmarks (their first ids)
  Eigen::VectorXd x;                 ///< 2 per landmark
  Eigen::MatrixXd P;
  std::vector<double> exist_nats;  ///< per landmark: the global map's log-odds of its existence
};

class GlobalMap {
 public:
  explicit GlobalMap(const JoinOptions& options);
  ~GlobalMap();
  GlobalMap(const GlobalMap&) = delete;
  GlobalMap& operator=(const GlobalMap&) = delete;

  /// Joins a closed local map. Throws std::runtime_error when the association fails (its status).
  JoinResult join(const Submap& m);
  /// A seed of the current local map (docs/submaps.md, "Seed"): the global landmarks within
  /// radius_m of `center` (a point in the global frame: where the robot is), nearest first, at most
  /// max_count. Left out: those a landmark of the map stands for (`held`: the local ids it holds,
  /// carried, seeded or joined), those seeded into this map before or refused by it (compatible with
  /// a landmark it made anew), and those compatible (chi2(confidence, 2)) with another global
  /// landmark near them (ambiguous: a seed is an unchecked closure). Each one's mean and marginal
  /// covariance are in the base's frame (the local map's origin), uncorrelated with each other, as
  /// SUBMAP_SEED carries them; they depend on the global state alone, which does not change while the
  /// map is built, so a map may be seeded at any scan. The map decides which it takes (node::seed_map).
  Seed seed(const Eigen::Vector2d& center, double radius_m, int max_count, const std::vector<FeatureId>& held) const;
  /// The local map's answer to seed `s`, one local id per seed: >= 0, it took the seed under that id
  /// (remembered as the map's prior on it); kUnmatched, it holds one compatible with it (not offered
  /// again to this map); kNewFeature, no room (offered again).
  void seeded(const Seed& s, const std::vector<FeatureId>& local_ids);
  /// The global position of the base's point `local`.
  Eigen::Vector2d to_global(const Eigen::Vector2d& local) const;
  /// The global pose and covariance of a pose of the current local map (its origin is the base).
  void to_global(const Pose2<double>& local, const Eigen::Matrix3d& P_local, Pose2<double>& global,
                 Eigen::Matrix3d& P_global) const;
  int landmarks() const { return static_cast<int>(first_id_.size()); }
  Eigen::Vector2d landmark(int k) const { return x_.segment<2>(3 + 2 * k); }
  /// Global landmark k's marginal covariance.
  Eigen::Matrix2d landmark_covariance(int k) const;
  /// The base's (the current local map's origin) marginal covariance.
  Eigen::Matrix3d base_covariance() const;
  /// The joint covariance of the base and landmarks `gs` (3 + 2 rows each): dense, read from the
  /// state's; kGraph, recovered from a factorisation with them eliminated last.
  Eigen::MatrixXd joint_marginal(const std::vector<int>& gs) const;
  /// Every landmark's joint covariance (2 rows each, in their order): dense, O(landmarks^2).
  Eigen::MatrixXd landmarks_covariance() const;
  /// Global landmark k's log-odds of existence: the last local map's that held it (which began from
  /// the global map's, carried or seeded), or the sum of two maps' that each made it (fused).
  double existence(int k) const { return exist_[static_cast<std::size_t>(k)]; }
  /// The id of the local landmark global landmark k was made from (its first).
  FeatureId first_id(int k) const { return first_id_[static_cast<std::size_t>(k)]; }
  /// Local maps joined so far.
  int maps() const { return maps_; }
  /// kGraph: the origin of local map k (k <= maps(): maps() is the one being built) in the world, as
  /// the last solve left it. Dense, the origins are never revisited: a trace needs no recomposing
  /// (std::logic_error).
  Eigen::Vector3d origin(int k) const;
  /// kGraph: every local map's origin (0..maps()) and its marginal covariance, from one factorisation.
  void origins(std::vector<Eigen::Vector3d>& o, std::vector<Eigen::Matrix3d>& P) const;
  /// The local ids the last joined map kept into the next one (its Submap::carried): what the next
  /// map begins with.
  const std::vector<FeatureId>& carried_ids() const { return carried_ids_; }
  /// The estimate [base, landmarks] (kGraph: the solution's).
  const Eigen::VectorXd& state() const { return x_; }
  /// kGraph: the factor graph (null when dense) and the last join's solve.
  const FactorGraph* graph() const { return graph_.get(); }
  const GraphSolve& last_solve() const { return last_solve_; }

 private:
  struct Association;
  /// What a join reads of the global state: the base and some landmarks (all of them when dense),
  /// with their joint covariance. The join's decisions are taken on it.
  struct View {
    std::vector<int> g;  ///< view landmark -> global landmark
    Eigen::VectorXd x;   ///< [base, landmarks g]
    Eigen::MatrixXd P;
  };
  /// The landmarks a map shares with the global one (carried over or seeded: the same ids) and the
  /// prior it began with on them (m0, P0 in the base's frame); the global landmarks it removed.
  struct Shared {
    std::vector<int> shared, target;   ///< index in the map; global landmark
    std::vector<int> carried, seeded;  ///< positions in `shared`
    std::vector<bool> is_shared;       ///< per local landmark
    std::vector<bool> gone;            ///< per global landmark
    Eigen::VectorXd m0;
    Eigen::MatrixXd P0;
  };
  /// The association's answer between a map and a view.
  struct Pairing {
    std::vector<std::pair<int, int>> pairs;  ///< (local landmark, view landmark)
    std::vector<bool> ambiguous;             ///< per local landmark: declined
    bool compatible = true;
  };
  /// The global landmark a local id was made into or fused with (-1: none).
  int global_index(FeatureId local) const;
  int index_of_first(FeatureId first) const;
  Shared find_shared(const Submap& m, JoinResult& res) const;
  /// The view a join of `m` reads: dense, the whole state (moved out, given back at the commit);
  /// kGraph, the base, the shared ones' targets and every landmark a bound on the gate lets through,
  /// with their joint marginal.
  View open_view(const Submap& m, const Shared& sh);
  /// The shared landmarks' update on the view, and its d2 figures (also for the seeded ones alone).
  void update_shared(const Submap& m, const Shared& sh, const std::vector<int>& target_view, View& v,
                     JoinResult& res) const;
  /// What the map's scans add on the landmarks it shares with the previous map: its information on
  /// them less the prior it began with (the previous map's, in its last pose's frame), as a
  /// measurement of the view (conditionally independent maps, Pinies and Tardos 2008). With `apply`
  /// false the view is left as it was. @return the measurement's nu^T S^-1 nu; `dof` its dimension
  /// (the directions the scans informed; 0: nothing to fuse, and 0 returned). `target`: view rows.
  double shared_update(const Submap& m, const std::vector<int>& shared, const std::vector<int>& target,
                       const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0, bool apply, int& dof, View& v) const;
  Pairing associate_map(const Submap& m, const Shared& sh, const View& v, const std::vector<int>& target_view,
                        JoinResult& res) const;
  /// The view with the map's rows u (its pose, its landmarks not shared) appended, given the shared
  /// ones: X = [v.x, base (+) u], P with every correlation.
  void augment(const Submap& m, const std::vector<int>& u, const std::vector<int>& shared,
               const std::vector<int>& target_view, const View& v, Eigen::VectorXd& X, Eigen::MatrixXd& P) const;
  /// The pairs' constraints tested with the full covariance and fused into X, P: the accepted pairs
  /// (indices into `pairs`).
  std::vector<int> fuse(const std::vector<std::pair<int, int>>& pairs, const std::vector<int>& row_of, bool compatible,
                        Eigen::VectorXd& X, Eigen::MatrixXd& P, JoinResult& res) const;
  /// kGraph: the map as a factor on the base, its end frame (at X's rows D0..) and the global
  /// landmarks it holds (`var`: per local landmark, its graph variable; -1, marginalised out).
  void add_factor(const Submap& m, const Shared& sh, const std::vector<int>& var, const Eigen::Vector3d& end);
  /// kGraph: the joint marginals of the base with landmarks `gs` (cached until the next join).
  void cache_joint(const std::vector<int>& gs) const;
  std::unique_ptr<FactorGraph> graph_;
  std::vector<int> var_of_;                             ///< kGraph: global landmark -> its graph variable
  std::vector<int> frame_of_map_ = {0};                 ///< kGraph: local map k's origin's frame
  int base_frame_ = 0;                                  ///< kGraph: the base's frame
  Eigen::Matrix3d base_cov_ = Eigen::Matrix3d::Zero();  ///< kGraph: the base's marginal
  /// kGraph: [base, landmark] joint marginals (5 x 5) since the last join, per global landmark.
  mutable std::unordered_map<int, Eigen::Matrix<double, 5, 5>> joint_;
  /// kGraph: each landmark's marginal when last computed, in the global frame: a bound on today's
  /// (information only grows), for the view's gate.
  std::vector<Eigen::Matrix2d> own_cov_;
  GraphSolve last_solve_;
  JoinOptions opt_;
  Eigen::VectorXd x_;  ///< [base pose (3), landmarks (2 each)]
  Eigen::MatrixXd P_;  ///< dense: its covariance (kGraph: empty)
  std::vector<FeatureId> first_id_;
  std::vector<double> exist_;  ///< per landmark: its log-odds of existence
  int maps_ = 0;
  std::unique_ptr<Submap> prev_;                        ///< the last map joined: the next one's prior
  Seed seed_;                                           ///< the current map's seeds, stacked
  std::vector<FeatureId> seed_ids_;                     ///< its landmarks' local ids
  std::vector<FeatureId> seed_refused_;                 ///< first ids the current map refused (compatible)
  std::vector<FeatureId> carried_ids_;                  ///< the last map's landmarks kept into this one
  std::unordered_map<FeatureId, FeatureId> global_of_;  ///< local id -> its global landmark's first id
  std::unique_ptr<Association> assoc_;                  ///< the association's workspace (large: on the heap)
};

}  // namespace geojcbb::host
