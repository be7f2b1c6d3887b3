// host_tools/mapping: maps of several robots merged into one when their relative start poses are
// unknown (docs/submaps.md, "Several robots, one map"). Each robot's map is in its own frame (its
// start pose). The first map is the merged map's frame; each further map is
//   1. aligned pose-free: its landmarks, as range-bearing "observations" from its origin with their
//      covariance, against the merged map's landmarks by the library's two-point alignment
//      (reloc::align, no prior): its frame's pose in the merged frame and the covariance of the fit;
//      a map whose alignment is not unique (a rival pose within the margin) or not supported (too
//      few inliers) is kept apart, not guessed;
//   2. tested: the alignment's pairs' constraints l' - m = 0 jointly, with the full covariance (the
//      maps' own and the pose's); a join whose pairs are not jointly compatible is refused (pruning
//      them into agreement would accept a subset of any pairing);
//   3. checked for unique pairs: under the alignment's own uncertainty no other merged landmark may
//      be compatible with a paired landmark of the map, nor another of the map's with the merged
//      one (chi2(confidence, 2)); otherwise the pairs could be exchanged and the map is refused as
//      ambiguous;
//   4. fused: the maps are independent (each robot's own scans), so the merged state is [M, L'] with
//      a block-diagonal covariance, the constraints applied as one update and the paired rows of L'
//      dropped (marginalised); its unpaired landmarks join as new ones.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "geojcbb/core/range_bearing.hpp"

namespace geojcbb::host {

/// One robot's map in its own frame.
struct RobotMap {
  std::vector<Eigen::Vector2d> landmarks;
  Eigen::MatrixXd P;       ///< their joint covariance, 2 per landmark
  std::vector<int> truth;  ///< per landmark: its true landmark (labelled data), or < 0
};

struct MergeOptions {
  double confidence = 0.99;   ///< the joint test's chi-square level
  int min_inliers = 5;        ///< the alignment's support (reloc::AlignOptions::min_inliers)
  double margin_nats = 10.0;  ///< a unique alignment leads every distinct rival by this
  double constraint_var_m2 = 1e-6;
};

struct MergeResult {
  std::vector<bool> aligned;         ///< per map: joined (the first is the frame)
  std::vector<Pose2<double>> start;  ///< per map: its frame in the merged frame (the first: 0)
  /// per map: the alignment's covariance of its start (x, y, theta; zero for the first and for a map
  /// not joined): how far the start found may be from the true one.
  std::vector<Eigen::Matrix3d> start_cov;
  std::vector<int> pairs;        ///< per map: landmarks fused with the merged map
  std::vector<std::string> why;  ///< per map not joined: the reason
  std::vector<Eigen::Vector2d> landmarks;
  Eigen::MatrixXd P;
  std::vector<int> truth;  ///< per merged landmark: the first truth it was made from
  int fused = 0;           ///< pairs fused
  int wrong = 0;           ///< of those, two different known truths
};

/// Merges the maps in order (see the file's head). A map larger than the alignment's capacity (127
/// landmarks per map, 256 merged) is kept apart, with the reason in `why`.
MergeResult merge_maps(const std::vector<RobotMap>& maps, const MergeOptions& o = {});

}  // namespace geojcbb::host
