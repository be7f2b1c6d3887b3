// host_tools/eval: the global map of sequential map joining (Tardos, Neira, Newman, Leonard 2002;
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
// Dense double (Eigen), O(D^2 pairs) per join for D = 3 + 2 landmarks.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/presets.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb_host/run_score.hpp"

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
  Eigen::Matrix2d landmark_covariance(int k) const { return P_.block<2, 2>(3 + 2 * k, 3 + 2 * k); }
  /// Global landmark k's log-odds of existence: the last local map's that held it (which began from
  /// the global map's, carried or seeded), or the sum of two maps' that each made it (fused).
  double existence(int k) const { return exist_[static_cast<std::size_t>(k)]; }
  /// The id of the local landmark global landmark k was made from (its first).
  FeatureId first_id(int k) const { return first_id_[static_cast<std::size_t>(k)]; }
  /// Local maps joined so far.
  int maps() const { return maps_; }
  /// The local ids the last joined map kept into the next one (its Submap::carried): what the next
  /// map begins with.
  const std::vector<FeatureId>& carried_ids() const { return carried_ids_; }
  /// The whole state [base, landmarks] and its covariance.
  const Eigen::VectorXd& state() const { return x_; }
  const Eigen::MatrixXd& covariance() const { return P_; }

 private:
  struct Association;
  /// The global landmark a local id was made into or fused with (-1: none).
  int global_index(FeatureId local) const;
  int index_of_first(FeatureId first) const;
  /// What the map's scans add on the landmarks it shares with the previous map: its information on
  /// them less the prior it began with (the previous map's, in its last pose's frame), as a
  /// measurement of the global state (conditionally independent maps, Pinies and Tardos 2008).
  /// With `apply` false the state is left as it was. @return the measurement's nu^T S^-1 nu; `dof`
  /// its dimension (the directions the scans informed; 0: nothing to fuse, and 0 returned).
  double shared_update(const Submap& m, const std::vector<int>& shared, const std::vector<int>& target,
                       const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0, bool apply, int& dof);
  /// The global state with the map's rows u (its pose, its landmarks not shared) appended, given the
  /// shared ones: X = [x_, base (+) u], P with every correlation.
  void augment(const Submap& m, const std::vector<int>& u, const std::vector<int>& shared,
               const std::vector<int>& target, Eigen::VectorXd& X, Eigen::MatrixXd& P) const;
  JoinOptions opt_;
  Eigen::VectorXd x_;  ///< [base pose (3), landmarks (2 each)]
  Eigen::MatrixXd P_;
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
