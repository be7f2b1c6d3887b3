// host_tools/mapping: what one join of a local map into the global map did (GlobalMap::join), the
// figures a run records per join (run_score.hpp's JoinRecord).
#pragma once

namespace geojcbb::host {

/// What one join of a local map did (GlobalMap::join, docs/submaps.md).
struct JoinCounts {
  int landmarks = 0;     ///< of the local map
  int shared = 0;        ///< carried over from the previous map or seeded (the same ids): joined by their ids
  int offered = 0;       ///< of the others, with a compatible global landmark (the association's observations)
  int fused = 0;         ///< paired with a global landmark and fused
  int declined = 0;      ///< ambiguous: neither paired nor mapped anew (left out, as kUnmatched)
  int pruned = 0;        ///< outside the jointly compatible subset (JoinOptions::joint_check): kept apart
  int dropped = 0;       ///< tentative and not paired, or declined: left out
  int removed = 0;       ///< seeds the map took and removed by their evidence: gone from the global map
  bool refused = false;  ///< the pairs were not jointly compatible: all kept apart
  double joint_d2 = 0;   ///< of the pairs' constraints, with the full covariance
  /// The shared landmarks' update (fused by their ids, not tested): nu^T S^-1 nu and its dimension
  /// (the directions the map's scans informed). Consistent maps give about one per dimension.
  double shared_d2 = 0;
  int shared_dof = 0;
  /// The same for the seeded ones alone (against their seeds' prior): a seed the map paired
  /// wrongly, or a region of the global map off beyond its covariance, shows here first.
  double seeded_d2 = 0;
  int seeded_dof = 0;
};

}  // namespace geojcbb::host
