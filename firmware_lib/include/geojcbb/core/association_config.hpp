// core: the options of one association pipeline as plain data. The named strategies (ICNN, JCBB, and
// the grouped ones of issue 3) are presets of these switches, not separate code paths.
#pragma once

#include "geojcbb/core/capacity.hpp"
#include "geojcbb/gate/thresholds.hpp"

namespace geojcbb {

enum class SearchMethod : std::uint8_t {
  kIcnn,  ///< each observation takes its nearest individually compatible candidate
  kJcbb,  ///< joint compatibility branch and bound (Neira & Tardos 2001)
};

template <typename T, class B>
struct AssociationConfig {
  SearchMethod search = SearchMethod::kJcbb;
  /// Local association region (2019 paper, eq. 5): only candidates with predicted range < r + d.
  bool local_region = false;
  T local_radius_m = T(0);  ///< r + d [m]; used when local_region is on
  /// A feature takes at most one observation (2019 paper, section III.C).
  bool mutual_exclusion = false;
  /// Among hypotheses with the most pairings, the one with the smallest joint d2 (eq. 14).
  bool optimal_criterion = false;
  /// Search observations with the fewest compatible candidates first (smaller tree, same answer).
  bool order_fewest_candidates_first = true;
  /// Interpretation-tree nodes per call, 1 .. B::kMaxJcbbNodes.
  int node_budget = B::kMaxJcbbNodes;
  GateThresholds<T, B::kMaxObservations> gate;  ///< set with GateThresholds::from_confidence
};

}  // namespace geojcbb
