// core: the options of one association pipeline as plain data. The named strategies (ICNN, JCBB,
// and the grouped ones of grouped association) are presets of these switches, not
// separate code paths.
#pragma once

#include "geojcbb/core/capacity.hpp"
#include "geojcbb/core/consistency_options.hpp"
#include "geojcbb/core/grouping_options.hpp"
#include "geojcbb/core/gate_thresholds.hpp"
#include "geojcbb/core/settings.hpp"

namespace geojcbb {

enum class SearchMethod : std::uint8_t {
  kIcnn,  ///< each observation takes its nearest individually compatible candidate
  kJcbb,  ///< joint compatibility branch and bound (Neira & Tardos 2001)
};

/// Most RJC tries per scan (AssociationConfig::rjc_tries).
constexpr int kMaxRjcTries = 64;

/// How much of C validate() checks before the stages run (packed covariance).
enum class CovarianceCheck : std::uint8_t {
  /// Each entry of C is checked where a stage reads it: the diagonal blocks of the candidates in the
  /// local region before gating, a cross block when a joint (or pairwise) test reads it. A bad entry
  /// gets the same Status as under kFull (outputs untouched); one that no test reads cannot change
  /// the answer. O(n) before the stages instead of O(n^2).
  kWhereRead,
  /// Every entry between candidates of the local region, before any stage runs (the behaviour before
  /// packed covariance; O(n^2) per call).
  kFull,
};

/// The configuration of one association call: the step's settings (core/settings.hpp, one line per
/// option in core/options.h, inherited by value, never copied field by field), the preset's switches
/// (core/strategy.hpp's make_strategy sets them) and the values derived from the settings (the
/// chi-square gates). A stage reads an option where it uses it (`cfg.dbscan_eps_m`); an option of the
/// table needs no line here. The settings' fields the association reads, and what the design adds to
/// their one-line meanings:
///  - groups: k-means and GMM-EM, 1 .. MaxGroups; for GMM-EM 0 chooses K by BIC.
///  - joint_recheck (our addition): test the merged hypothesis jointly and, when it fails, keep its
///    largest jointly compatible subset (merge/merge.hpp). The groups share the robot pose error, so
///    a union of per-group answers can be jointly incompatible.
///  - condition_groups (our addition): search the groups one after another, each conditioned on the
///    pairings already chosen for the earlier groups (every joint test covers the whole scan so far;
///    exclusion sees their features as taken). The union is then jointly compatible by construction
///    and the groups share the pose information their pairings carry. Off: the groups are searched
///    independently and merged (the papers' method).
///  - local_radius_m: r + d [m] of the local region (2019 paper, eq. 5), when local_region is on.
///  - ambiguity_margin (our addition, decline instead of guessing): when > 0, the search also finds
///    the runner-up hypothesis (another with as many pairings, joint d2 within this margin of the
///    best's); the observations it pairs differently are left kUnmatched (neither paired nor new).
///    For ICNN: an observation whose second-nearest compatible candidate is within this margin of
///    its nearest. 0: off (the papers' methods). Compared in T.
///  - new_if_candidates_taken (our addition, with mutual exclusion): an unpaired observation whose
///    every compatible candidate is held by another observation's pairing cannot be any of them, so
///    it is reported new (kNewFeature, its d2 the nearest over the other candidates) instead of
///    kUnmatched; a second landmark next to a mapped one can then be mapped when both are seen
///    together.
///  - verify (our addition, pose-free consistency): the answer's pairings must also be
///    pairwise consistent (consistency/, pose-free distance test). The largest pairwise consistent
///    subset of the answer (the max clique of the graph over its own pairings) is kept; the other
///    pairings are dropped and their observations left kUnmatched. Dropping rather than replacing
///    the answer with the clique of every wide-gate pairing: the subset keeps the joint test's choice
///    wherever it is consistent (the wide clique alone holds a wrong pairing in about 1 scene in 10:
///    docs/consistency.md, "Limits"), and its graph has at most one node per observation, so it is
///    never truncated. make_strategy switches it on for PCJCBB.
///  - seed_min_position_var_m2: the seed's trigger (see `seed`).
///  - rjc, rjc_tries, rjc_subset (our addition, randomized joint compatibility for large scans; Paz,
///    Guivant, Tardos, Neira 2007; jcbb/rjc.hpp): JCBB on rjc_subset random observations, the rest
///    completed by nearest neighbour under the joint test, rjc_tries times from rjc_seed; the best
///    try is kept. Used by JCBB without grouping when more than rjc_subset observations have a
///    compatible candidate (smaller scans get plain JCBB). Not with an ambiguity margin (no
///    runner-up).
///  - node_budget: interpretation-tree nodes per scan, shared by every group's search, at most
///    B::kMaxJcbbNodes; 0 is that capacity (search_nodes()). The re-check's repair search may add up
///    to 2 * MaxObservations more.
template <typename T, class B>
struct AssociationConfig : StepSettings<T> {
  // The preset's switches (make_strategy).
  SearchMethod search = SearchMethod::kJcbb;
  Grouping grouping = Grouping::kNone;
  /// Local association region (2019 paper, eq. 5): only candidates with predicted range < r + d.
  bool local_region = false;
  /// A feature takes at most one observation (2019 paper, section III.C).
  bool mutual_exclusion = false;
  /// Among hypotheses with the most pairings, the one with the smallest joint d2 (eq. 14).
  bool optimal_criterion = false;
  /// Our addition (pose-free consistency), seed: when the pose is uncertain (the least
  /// Cartesian position variance of a predicted candidate, tr(J_a C_aa J_a^T), is at least
  /// seed_min_position_var_m2), the pose-free clique over the wide-gate pairings is tested jointly
  /// and, when it passes with at least seed_min_pairings pairings, fixed as the prefix of one JCBB
  /// search over the rest of the scan (no grouping: the prefix conditions the whole scan). JCBB only
  /// (not ICNN).
  bool seed = false;

  // Derived from the settings (make_strategy): the chi-square gates of `confidence`, the GMM-EM
  // variant of `papers_em`, the covariance check of `full_covariance_check`. The consistency
  // stage's options are built where they are used (consistency_options below).
  GateThresholds<T, B::kMaxObservations> gate;                     ///< set with GateThresholds::from_confidence
  EmOptions<T> em;                                                 ///< GMM-EM options (iterations <= kMaxEmIterations)
  CovarianceCheck covariance_check = CovarianceCheck::kWhereRead;  ///< see CovarianceCheck

  // Stage constants no option reaches.
  int kmeans_max_iterations = kMaxKMeansIterations;  ///< 1 .. kMaxKMeansIterations
  int seed_min_pairings = 3;                         ///< a seed clique smaller than this is not used (>= 2)
  std::uint64_t rjc_seed = 1;                        ///< the same inputs and seed give the same answer
  /// Search observations with the fewest compatible candidates first (smaller tree, same answer).
  bool order_fewest_candidates_first = true;

  /// The node budget of a scan: node_budget, or the capacity when it is 0.
  NodeCount search_nodes() const {
    return this->node_budget == 0 ? static_cast<NodeCount>(B::kMaxJcbbNodes) : this->node_budget;
  }
  /// The ambiguity margin in the pipeline's scalar.
  T margin() const { return static_cast<T>(this->ambiguity_margin); }
};

/// The graph options of verify and seed (consistency/): the table's thresholds and radius, the
/// preset's local region, the wide pairing gate and the default clique budget.
template <typename T, class B>
ConsistencyOptions<T> consistency_options(const AssociationConfig<T, B>& cfg) {
  ConsistencyOptions<T> out;
  bind_options(cfg, out);
  out.local_region = cfg.local_region;
  return out;
}

}  // namespace geojcbb
