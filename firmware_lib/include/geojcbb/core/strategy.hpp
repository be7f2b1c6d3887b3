// core: the seven named strategies as presets of AssociationConfig (ARCHITECTURE.md's table).
//   preset   local region  grouping  mutual exclusion  optimal criterion
//   ICNN     no            none      no                -
//   JCBB     no            none      no                no
//   KJCBB    no            k-means   no                no
//   DFJCBB   no            DBSCAN    no                no
//   GEMJCBB  yes           GMM-EM    no                no
//   GEOJCBB  yes           GMM-EM    yes               yes
//   PCJCBB   no            none      yes               yes   + verify + seed (ours)
// A preset switches only the columns above (and PCJCBB's verify and seed); AssociationConfig holds
// the step's settings themselves (core/settings.hpp, one line per option in core/options.h). The
// joint re-check of merged hypotheses (our addition) is on by default in the grouped presets;
// `joint_recheck` off reproduces the papers' methods exactly. PCJCBB ("pairwise consistent JCBB") is
// not a paper's method: JCBB with exclusion and the optimal criterion, whose answer is verified
// pairwise and which is seeded by the pose-free clique when the pose is uncertain
// (docs/consistency.md). The verification can be switched into every other preset
// (StepSettings::verify).
#pragma once

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/settings.hpp"

namespace geojcbb {

/// Builds a strategy's configuration from the step's settings: `p` whole, then the preset's switches
/// and the derived gates (`s` names the preset; out.strategy is set to it).
/// @return kOk; kInvalidInput when an option is outside its range (core/options.h), over the Bounds'
///         capacity (groups, node budget, RJC subset), or a grouped-region strategy has no radius;
///         kNoConvergence from the chi-square quantiles. `out` is written only on kOk.
template <typename T, class B>
[[nodiscard]] Status make_strategy(Strategy s, const StepSettings<T>& p, AssociationConfig<T, B>& out) {
  // Every check and quantile first, into small locals; `out` is then written field by field (a whole
  // AssociationConfig on the stack would take this frame over the controller's 512-byte limit).
  if (!in_range(p) || p.groups > B::kMaxGroups || p.node_budget > B::kMaxJcbbNodes ||
      (p.rjc && p.rjc_subset > B::kMaxObservations)) {
    return Status::kInvalidInput;
  }
  GateThresholds<T, B::kMaxObservations> gate;
  Status st = GateThresholds<T, B::kMaxObservations>::from_confidence(p.confidence, p.confidence, gate);
  if (st != Status::kOk) return st;
  const bool region = s == Strategy::kGemjcbb || s == Strategy::kGeojcbb;
  ConsistencyOptions<T> consistency;
  bind_options(p, consistency);
  consistency.local_region = region;
  if (!consistency.valid()) return Status::kInvalidInput;
  // RJC replaces one ungrouped JCBB search (jcbb/rjc.hpp): refused here rather than at every scan.
  const bool grouped = region || s == Strategy::kKjcbb || s == Strategy::kDfjcbb;
  if (p.rjc && (s == Strategy::kIcnn || grouped || p.ambiguity_margin > 0 ||
                (p.node_budget != 0 && p.node_budget < static_cast<NodeCount>(p.rjc_tries)))) {
    return Status::kInvalidInput;
  }
  // The settings, whole (the stages read them where they use them), then the preset's switches and
  // what is derived from the settings.
  static_cast<StepSettings<T>&>(out) = p;
  out.strategy = s;
  out.search = s == Strategy::kIcnn ? SearchMethod::kIcnn : SearchMethod::kJcbb;
  out.grouping = s == Strategy::kKjcbb    ? Grouping::kKMeans
                 : s == Strategy::kDfjcbb ? Grouping::kDbscan
                 : region                 ? Grouping::kGmmEm
                                          : Grouping::kNone;
  out.local_region = region;
  out.mutual_exclusion = s == Strategy::kGeojcbb || s == Strategy::kPcjcbb;
  out.optimal_criterion = s == Strategy::kGeojcbb || s == Strategy::kPcjcbb;
  out.verify = p.verify || s == Strategy::kPcjcbb;
  out.seed = s == Strategy::kPcjcbb;
  // 0 groups (BIC) is GMM-EM's alone; k-means takes the default K.
  if (p.groups == 0 && out.grouping != Grouping::kGmmEm) out.groups = StepSettings<T>{}.groups;
  out.gate = gate;
  out.em = EmOptions<T>{};
  out.em.stop = p.papers_em ? EmStop::kObjective : EmStop::kGroupsStable;
  out.em.start = p.papers_em ? EmStart::kFarthestFirst : EmStart::kKMeans;
  out.covariance_check = p.full_covariance_check ? CovarianceCheck::kFull : CovarianceCheck::kWhereRead;
  // Stage constants, set one by one: a default-constructed temporary would cost the frame as much as
  // a local copy.
  out.kmeans_max_iterations = kMaxKMeansIterations;
  out.seed_min_pairings = 3;
  out.rjc_seed = 1;
  out.order_fewest_candidates_first = true;
  return Status::kOk;
}

}  // namespace geojcbb
