// core: the six named strategies as presets of AssociationConfig (ARCHITECTURE.md's table).
//   preset   local region  grouping  mutual exclusion  optimal criterion
//   ICNN     no            none      no                -
//   JCBB     no            none      no                no
//   KJCBB    no            k-means   no                no
//   DFJCBB   no            DBSCAN    no                no
//   GEMJCBB  yes           GMM-EM    no                no
//   GEOJCBB  yes           GMM-EM    yes               yes
//   PCJCBB   no            none      yes               yes   + verify + seed (ours, issue 12)
// The joint re-check of merged hypotheses (our addition) is on by default in the grouped presets;
// StrategyParams switches it off to reproduce the papers' methods exactly. PCJCBB ("pairwise
// consistent JCBB") is not a paper's method: JCBB with exclusion and the optimal criterion, whose
// answer is verified pairwise and which is seeded by the pose-free clique when the pose is
// uncertain (docs/consistency.md). The verification can be switched into every other preset
// (StrategyParams::verify).
#pragma once

#include "geojcbb/core/association_config.hpp"

namespace geojcbb {

enum class Strategy : std::uint8_t { kIcnn, kJcbb, kKjcbb, kDfjcbb, kGemjcbb, kGeojcbb, kPcjcbb };
constexpr int kStrategyCount = 7;
/// The papers' six (ICNN .. GEOJCBB); PCJCBB is this project's preset (docs/consistency.md).
constexpr int kPaperStrategyCount = 6;

constexpr const char* to_string(Strategy s) {
  switch (s) {
    case Strategy::kIcnn: return "ICNN";
    case Strategy::kJcbb: return "JCBB";
    case Strategy::kKjcbb: return "KJCBB";
    case Strategy::kDfjcbb: return "DFJCBB";
    case Strategy::kGemjcbb: return "GEMJCBB";
    case Strategy::kGeojcbb: return "GEOJCBB";
    case Strategy::kPcjcbb: return "PCJCBB";
  }
  return "?";
}

template <typename T>
struct StrategyParams {
  double confidence = 0.99;  ///< chi-square level of the individual and joint tests
  T local_radius_m = T(0);   ///< r + d (eq. 5); must be > 0 for GEMJCBB and GEOJCBB
  int groups = 3;            ///< K for k-means and GMM-EM (the papers use 3 to 5); 0: BIC (EM)
  T dbscan_eps_m = T(1.5);
  int dbscan_min_points = 2;
  bool joint_recheck = true;
  bool condition_groups = false;         ///< our conditioned group search (AssociationConfig)
  NodeCount node_budget = 0;             ///< 0: the capacity's MaxJcbbNodes
  double ambiguity_margin = 0;           ///< AssociationConfig::ambiguity_margin (0: off)
  bool new_if_candidates_taken = false;  ///< AssociationConfig::new_if_candidates_taken
  bool verify = false;                   ///< AssociationConfig::verify, switched into any preset (PCJCBB: always on)
  /// AssociationConfig::covariance_check: true checks all of C before the stages (the behaviour
  /// before issue 13, O(n^2)); false checks each entry where a stage reads it.
  bool full_covariance_check = false;
  /// GMM-EM as before issue 13: farthest-first start and the papers' stop rule (objective tolerance
  /// only); false: the k-means start and the stop once the groups are stable (EmOptions).
  bool papers_em = false;
  /// AssociationConfig::seed_min_position_var_m2 (PCJCBB's seed trigger) [m^2]
  T seed_min_position_var_m2 = T(4);
  /// The consistency graph's wide gate, chi2inv(0.99999, 2) = -2 ln(1e-5), and its pairwise test,
  /// chi2inv(0.999, 1), as thresholds rather than levels: a second chi2_inv inlined into
  /// make_strategy took its frame over the controller's 512-byte limit (the values are checked
  /// against chi2_inv in tests/firmware_lib/consistency/test_associate_consistency.cpp).
  T consistency_wide_d2 = T(23.025850929940457);
  T consistency_pair_d2 = T(10.827566170662733);
};

/// Builds a strategy's configuration.
/// @return kOk; kInvalidInput when a grouped-region strategy has no radius or a parameter is out of
///         range; kNoConvergence from the chi-square quantiles. `out` is written only on kOk.
template <typename T, class B>
[[nodiscard]] Status make_strategy(Strategy s, const StrategyParams<T>& p, AssociationConfig<T, B>& out) {
  // Every check and quantile first, into small locals; `out` is then written field by field (a whole
  // AssociationConfig on the stack would take this frame over the controller's 512-byte limit).
  GateThresholds<T, B::kMaxObservations> gate;
  Status st = GateThresholds<T, B::kMaxObservations>::from_confidence(p.confidence, p.confidence, gate);
  if (st != Status::kOk) return st;
  ConsistencyOptions<T> consistency;
  consistency.wide_d2 = p.consistency_wide_d2;
  consistency.pair_d2 = p.consistency_pair_d2;
  if (!consistency.valid()) return Status::kInvalidInput;
  if (p.groups < 0 || p.groups > B::kMaxGroups || p.node_budget > B::kMaxJcbbNodes) {
    return Status::kInvalidInput;
  }
  const bool region = s == Strategy::kGemjcbb || s == Strategy::kGeojcbb;
  if (region && !(p.local_radius_m > T(0))) return Status::kInvalidInput;
  if (!(p.seed_min_position_var_m2 > T(0))) return Status::kInvalidInput;
  if (!(p.ambiguity_margin >= 0) || !(p.ambiguity_margin < 1e6)) return Status::kInvalidInput;
  // The fields no preset sets get AssociationConfig's defaults, one by one (a default-constructed
  // temporary would cost the frame as much as a local copy).
  out.kmeans_max_iterations = kMaxKMeansIterations;
  out.em = EmOptions<T>{};
  out.em.stop = p.papers_em ? EmStop::kObjective : EmStop::kGroupsStable;
  out.em.start = p.papers_em ? EmStart::kFarthestFirst : EmStart::kKMeans;
  out.covariance_check = p.full_covariance_check ? CovarianceCheck::kFull : CovarianceCheck::kWhereRead;
  out.order_fewest_candidates_first = true;
  out.seed_min_pairings = 3;
  out.rjc = false;
  out.rjc_tries = 8;
  out.rjc_subset = 8;
  out.rjc_seed = 1;
  out.gate = gate;
  out.consistency = consistency;
  out.search = s == Strategy::kIcnn ? SearchMethod::kIcnn : SearchMethod::kJcbb;
  out.grouping = s == Strategy::kKjcbb    ? Grouping::kKMeans
                 : s == Strategy::kDfjcbb ? Grouping::kDbscan
                 : region                 ? Grouping::kGmmEm
                                          : Grouping::kNone;
  out.local_region = region;
  out.local_radius_m = p.local_radius_m;
  out.mutual_exclusion = s == Strategy::kGeojcbb || s == Strategy::kPcjcbb;
  out.optimal_criterion = s == Strategy::kGeojcbb || s == Strategy::kPcjcbb;
  out.verify = p.verify || s == Strategy::kPcjcbb;
  out.seed = s == Strategy::kPcjcbb;
  out.seed_min_position_var_m2 = p.seed_min_position_var_m2;
  out.groups = p.groups == 0 && out.grouping != Grouping::kGmmEm ? 3 : p.groups;
  out.dbscan_eps_m = p.dbscan_eps_m;
  out.dbscan_min_points = p.dbscan_min_points;
  out.joint_recheck = p.joint_recheck;
  out.condition_groups = p.condition_groups;
  out.node_budget = p.node_budget == 0 ? B::kMaxJcbbNodes : p.node_budget;
  out.ambiguity_margin = static_cast<T>(p.ambiguity_margin);
  out.new_if_candidates_taken = p.new_if_candidates_taken;
  return Status::kOk;
}

}  // namespace geojcbb
