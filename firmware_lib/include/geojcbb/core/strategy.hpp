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
/// The papers' six (ICNN .. GEOJCBB); the wire protocol's strategy codes cover these only.
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
  bool condition_groups = false;  ///< our conditioned group search (AssociationConfig)
  int node_budget = 0;       ///< 0: the capacity's MaxJcbbNodes
  double ambiguity_margin = 0;  ///< AssociationConfig::ambiguity_margin (0: off)
  bool new_if_candidates_taken = false;  ///< AssociationConfig::new_if_candidates_taken
  bool verify = false;  ///< AssociationConfig::verify, switched into any preset (PCJCBB: always on)
  /// AssociationConfig::seed_min_position_var_m2 (PCJCBB's seed trigger) [m^2]
  T seed_min_position_var_m2 = T(4);
  double consistency_wide_confidence = 0.99999;  ///< the consistency graph's wide gate (2 dof)
  double consistency_pair_confidence = 0.999;    ///< its pairwise distance test (1 dof)
};

/// Builds a strategy's configuration.
/// @return kOk; kInvalidInput when a grouped-region strategy has no radius or a parameter is out of
///         range; kNoConvergence from the chi-square quantiles. `out` is written only on kOk.
template <typename T, class B>
[[nodiscard]] Status make_strategy(Strategy s, const StrategyParams<T>& p, AssociationConfig<T, B>& out) {
  AssociationConfig<T, B> c;
  const Status st = GateThresholds<T, B::kMaxObservations>::from_confidence(p.confidence, p.confidence, c.gate);
  if (st != Status::kOk) return st;
  if (p.groups < 0 || p.groups > B::kMaxGroups || p.node_budget < 0 || p.node_budget > B::kMaxJcbbNodes) {
    return Status::kInvalidInput;
  }
  c.search = s == Strategy::kIcnn ? SearchMethod::kIcnn : SearchMethod::kJcbb;
  c.grouping = s == Strategy::kKjcbb    ? Grouping::kKMeans
               : s == Strategy::kDfjcbb ? Grouping::kDbscan
               : (s == Strategy::kGemjcbb || s == Strategy::kGeojcbb) ? Grouping::kGmmEm
                                                                     : Grouping::kNone;
  c.local_region = s == Strategy::kGemjcbb || s == Strategy::kGeojcbb;
  if (c.local_region && !(p.local_radius_m > T(0))) return Status::kInvalidInput;
  c.local_radius_m = p.local_radius_m;
  c.mutual_exclusion = s == Strategy::kGeojcbb || s == Strategy::kPcjcbb;
  c.optimal_criterion = s == Strategy::kGeojcbb || s == Strategy::kPcjcbb;
  c.verify = p.verify || s == Strategy::kPcjcbb;
  c.seed = s == Strategy::kPcjcbb;
  if (!(p.seed_min_position_var_m2 > T(0))) return Status::kInvalidInput;
  c.seed_min_position_var_m2 = p.seed_min_position_var_m2;
  const Status cs = c.consistency.set_confidence(p.consistency_wide_confidence, p.consistency_pair_confidence);
  if (cs != Status::kOk) return cs;
  c.groups = p.groups == 0 && c.grouping != Grouping::kGmmEm ? 3 : p.groups;
  c.dbscan_eps_m = p.dbscan_eps_m;
  c.dbscan_min_points = p.dbscan_min_points;
  c.joint_recheck = p.joint_recheck;
  c.condition_groups = p.condition_groups;
  c.node_budget = p.node_budget == 0 ? B::kMaxJcbbNodes : p.node_budget;
  if (!(p.ambiguity_margin >= 0) || !(p.ambiguity_margin < 1e6)) return Status::kInvalidInput;
  c.ambiguity_margin = static_cast<T>(p.ambiguity_margin);
  c.new_if_candidates_taken = p.new_if_candidates_taken;
  out = c;
  return Status::kOk;
}

}  // namespace geojcbb
