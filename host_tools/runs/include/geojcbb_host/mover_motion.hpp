// host_tools/runs: the MRCLAM report's split of the false pairs with other robots by how far the
// observed robot had moved since the landmark it was paired with was made (docs/mrclam.md, "The
// other robots' false pairs by motion").
//
// A robot seen by another is clutter for landmark SLAM (truth -1), and any pairing of it with a map
// landmark is a false pair. Most such landmarks were made from the same robot earlier: a robot that
// stood still since then is, to the camera, a landmark that is where it was, and no association can
// tell; one that moved beyond the noise should have failed the gate. The split says which of the two
// the false pairs are. Per landmark a run's step makes (RunOptions::on_scan), MoverMotion remembers
// which robot it was made from, that robot's true position (Vicon) and the observation's noise in
// the world frame; per false pair of robot k with a landmark made from robot k, m is the robot's
// displacement between the two sightings in units of their combined noise:
//   delta = p_k(t) - p_k(t0),  Sigma = Sigma0 + Sigma_now,  m = sqrt(delta^T Sigma^-1 delta),
// where each Sigma = G R G^T is the observation's R carried to the world frame at the observer's
// true pose (G: the Jacobian of the inverse observation with respect to (range, bearing)).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <tuple>
#include <vector>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/math.hpp"
#include "geojcbb_host/mrclam.hpp"
#include "geojcbb_host/slam_run.hpp"

namespace geojcbb::host {

/// Where a false pair of another robot falls: by m (above), or paired with a landmark that was not
/// made from that robot (made from a tube, from another robot, or of unknown origin).
enum class MoverBucket : std::uint8_t { kUnder1Sigma, k1To3Sigma, kOver3Sigma, kOtherLandmark };
constexpr int kMoverBuckets = 4;
/// The report's column title ("<1 sigma", ...) and the JSON and CSV key ("under_1_sigma", ...).
const char* mover_bucket_title(MoverBucket b);
const char* mover_bucket_key(MoverBucket b);

/// One observation as the split needs it: which robot was seen (0 or a landmark subject: not a
/// robot), where it truly was, and the observation's noise in the world frame.
struct MoverSighting {
  int subject = 0;
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  Eigen::Matrix2d sigma = Eigen::Matrix2d::Zero();
};

/// G R G^T: the noise R of z = (range, bearing) carried to the world position it gives from the
/// observer's pose (the MRCLAM camera sits at the robot's centre: no mount).
Eigen::Matrix2d world_noise(const Pose2<double>& observer, const Eigen::Vector2d& z, const Eigen::Matrix2d& R);

/// The bucket of a false pair: `now` (a sighting of a robot) paired with the landmark made from
/// `made`. m_out (optional) receives m, or -1 for kOtherLandmark.
MoverBucket mover_bucket(const MoverSighting& made, const MoverSighting& now, double* m_out = nullptr);

/// A run's (or a sum of runs') counts.
struct MoverCounts {
  std::array<int, kMoverBuckets> bucket{};  ///< false pairs with other robots, by MoverBucket
  int false_detections = 0;                 ///< clutter paired that was not a robot (an unknown barcode): in no bucket
  int unmatched = 0;                        ///< observations whose subject was not found (0 expected)
  int truth_gaps = 0;                       ///< positions taken from the nearest truth sample (no interpolation there)
  int total() const { return bucket[0] + bucket[1] + bucket[2] + bucket[3]; }
  MoverCounts& operator+=(const MoverCounts& o);
};

/// The observer of one MRCLAM run: subjects by observation, the robots' ground truth, and per
/// landmark id the sighting it was made from.
class MoverMotion {
 public:
  /// @param tracks    subject -> that robot's ground truth (index 1..mrclam::kRobots; others empty)
  /// @param observer  the robot whose run this is
  MoverMotion(std::vector<std::vector<mrclam::PoseSample>> tracks, int observer);
  /// Each observation of a scan input (time t_s) with its subject, as fed to the filter.
  void add_subjects(double t_s, const std::vector<SimObservation>& obs, const std::vector<int>& subjects);
  /// What a scan's observations became (RunOptions::on_scan).
  void on_scan(const ScanOutcome& s);
  const MoverCounts& counts() const { return counts_; }

 private:
  MoverSighting sighting(int subject, double t_s, const SimObservation& o);
  bool position(int subject, double t_s, mrclam::PoseSample& out);
  using Key = std::tuple<double, double, double>;  ///< (t, range, bearing): exact, the log keeps them
  std::map<Key, int> subject_of_;
  std::vector<std::vector<mrclam::PoseSample>> tracks_;
  int observer_;
  std::vector<MoverSighting> made_;  ///< landmark id -> the sighting it was made from
  MoverCounts counts_;
};

}  // namespace geojcbb::host
