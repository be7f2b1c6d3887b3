// core: the options of one association pipeline as plain data. The named strategies (ICNN, JCBB, and
// the grouped ones of the grouped-association round) are presets of these switches, not separate code paths.
#pragma once

#include "geojcbb/core/capacity.hpp"
#include "geojcbb/core/consistency_options.hpp"
#include "geojcbb/core/grouping_options.hpp"
#include "geojcbb/core/gate_thresholds.hpp"

namespace geojcbb {

enum class SearchMethod : std::uint8_t {
  kIcnn,  ///< each observation takes its nearest individually compatible candidate
  kJcbb,  ///< joint compatibility branch and bound (Neira & Tardos 2001)
};

/// Most RJC tries per scan (AssociationConfig::rjc_tries).
constexpr int kMaxRjcTries = 64;

/// How much of C validate() checks before the stages run (the packed-covariance round).
enum class CovarianceCheck : std::uint8_t {
  /// Each entry of C is checked where a stage reads it: the diagonal blocks of the candidates in the
  /// local region before gating, a cross block when a joint (or pairwise) test reads it. A bad entry
  /// gets the same Status as under kFull (outputs untouched); one that no test reads cannot change
  /// the answer. O(n) before the stages instead of O(n^2).
  kWhereRead,
  /// Every entry between candidates of the local region, before any stage runs (the behaviour before
  /// the packed-covariance round; O(n^2) per call).
  kFull,
};

template <typename T, class B>
struct AssociationConfig {
  SearchMethod search = SearchMethod::kJcbb;
  Grouping grouping = Grouping::kNone;
  /// Groups for k-means and GMM-EM, 1 .. MaxGroups; for GMM-EM 0 chooses K by BIC.
  int groups = 3;
  int kmeans_max_iterations = kMaxKMeansIterations;  ///< 1 .. kMaxKMeansIterations
  T dbscan_eps_m = T(1.5);                           ///< DBSCAN neighbourhood radius [m]
  int dbscan_min_points = 2;                         ///< DBSCAN core-point threshold (itself included)
  EmOptions<T> em;                                   ///< GMM-EM options (iterations <= kMaxEmIterations)
  /// Our addition: test the merged hypothesis jointly and, when it fails, keep its largest jointly
  /// compatible subset (merge/merge.hpp). The groups share the robot pose error, so a union of
  /// per-group answers can be jointly incompatible.
  bool joint_recheck = true;
  /// Our addition: search the groups one after another, each conditioned on the pairings already
  /// chosen for the earlier groups (every joint test covers the whole scan so far; exclusion sees
  /// their features as taken). The union is then jointly compatible by construction and the groups
  /// share the pose information their pairings carry. Off: the groups are searched independently
  /// and merged (the papers' method).
  bool condition_groups = false;
  /// Local association region (2019 paper, eq. 5): only candidates with predicted range < r + d.
  bool local_region = false;
  T local_radius_m = T(0);  ///< r + d [m]; used when local_region is on
  /// A feature takes at most one observation (2019 paper, section III.C).
  bool mutual_exclusion = false;
  /// Among hypotheses with the most pairings, the one with the smallest joint d2 (eq. 14).
  bool optimal_criterion = false;
  /// Our addition, decline instead of guessing: when > 0, the search also finds the runner-up
  /// hypothesis (another with as many pairings, joint d2 within this margin of the best's); the
  /// observations it pairs differently are left kUnmatched (neither paired nor new). For ICNN: an
  /// observation whose second-nearest compatible candidate is within this margin of its nearest.
  /// 0: off (the papers' methods).
  T ambiguity_margin = T(0);
  /// Our addition, with mutual exclusion: an unpaired observation whose every compatible candidate
  /// is held by another observation's pairing cannot be any of them, so it is reported new
  /// (kNewFeature, its d2 the nearest over the other candidates) instead of kUnmatched; a second
  /// landmark next to a mapped one can then be mapped when both are seen together. Off: kUnmatched.
  bool new_if_candidates_taken = false;
  /// Our addition (the pose-free consistency round), verify: the answer's pairings must also be pairwise consistent
  /// (consistency/, pose-free distance test). The largest pairwise consistent subset of the answer
  /// (the max clique of the graph over its own pairings) is kept; the other pairings are dropped and
  /// their observations left kUnmatched. Dropping rather than replacing the answer with the clique
  /// of every wide-gate pairing: the subset keeps the joint test's choice wherever it is consistent
  /// (the wide clique alone holds a wrong pairing in about 1 scene in 10: docs/consistency.md,
  /// "Limits"), and its graph has at most one node per observation, so it is never truncated.
  bool verify = false;
  /// Our addition (the pose-free consistency round), seed: when the pose is uncertain (the least Cartesian position variance
  /// of a predicted candidate, tr(J_a C_aa J_a^T), is at least seed_min_position_var_m2), the
  /// pose-free clique over the wide-gate pairings is tested jointly and, when it passes with at
  /// least seed_min_pairings pairings, fixed as the prefix of one JCBB search over the rest of the
  /// scan (no grouping: the prefix conditions the whole scan). JCBB only (not ICNN).
  bool seed = false;
  T seed_min_position_var_m2 = T(4);  ///< [m^2]; the seed's trigger (> 0)
  int seed_min_pairings = 3;          ///< a clique smaller than this is not used (>= 2)
  /// Graph options of verify and seed: pairwise gate, wide gate, clique budget. Its local region is
  /// taken from this config's, not from here.
  ConsistencyOptions<T> consistency;
  /// Our addition (the pose-free consistency round), randomized joint compatibility for large scans (RJC; Paz, Guivant,
  /// Tardos, Neira 2007; jcbb/rjc.hpp): JCBB on rjc_subset random observations, the rest completed
  /// by nearest neighbour under the joint test, rjc_tries times from rjc_seed; the best try is kept.
  /// Used by JCBB without grouping when more than rjc_subset observations have a compatible
  /// candidate (smaller scans get plain JCBB). Not with an ambiguity margin (no runner-up).
  bool rjc = false;
  int rjc_tries = 8;           ///< 1 .. kMaxRjcTries; each try gets node_budget / rjc_tries nodes
  int rjc_subset = 8;          ///< 1 .. MaxObservations
  std::uint64_t rjc_seed = 1;  ///< the same inputs and seed give the same answer
  /// Search observations with the fewest compatible candidates first (smaller tree, same answer).
  bool order_fewest_candidates_first = true;
  /// Interpretation-tree nodes per scan, shared by every group's search, 1 .. B::kMaxJcbbNodes.
  /// The re-check's repair search may add up to 2 * MaxObservations more.
  NodeCount node_budget = B::kMaxJcbbNodes;
  GateThresholds<T, B::kMaxObservations> gate;                     ///< set with GateThresholds::from_confidence
  CovarianceCheck covariance_check = CovarianceCheck::kWhereRead;  ///< see CovarianceCheck
};

/// The grouping stage's options of a configuration (cluster/group.hpp reads only these).
template <typename T, class B>
GroupingOptions<T> grouping_options(const AssociationConfig<T, B>& cfg) {
  GroupingOptions<T> o;
  o.grouping = cfg.grouping;
  o.groups = cfg.groups;
  o.kmeans_max_iterations = cfg.kmeans_max_iterations;
  o.dbscan_eps_m = cfg.dbscan_eps_m;
  o.dbscan_min_points = cfg.dbscan_min_points;
  o.em = cfg.em;
  return o;
}

}  // namespace geojcbb
