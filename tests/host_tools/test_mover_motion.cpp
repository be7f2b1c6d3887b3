// The MRCLAM report's split of the other robots' false pairs by how far the robot moved
// (host_tools/runs/mover_motion.hpp) on hand-made cases: the world-frame noise against finite
// differences, the buckets, and the observer fed scans as the run loop reports them.
#include <doctest/doctest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <vector>

#include "geojcbb_host/mover_motion.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {

// The world position an observation gives from a pose (the inverse observation, no mount).
Eigen::Vector2d inverse_observation(const Pose2<double>& x, const Eigen::Vector2d& z) {
  return {x.x + z.x() * std::cos(x.theta + z.y()), x.y + z.x() * std::sin(x.theta + z.y())};
}

// A sighting of robot `subject` at p, seen from `from` at range and bearing z with R = diag(0.05 m, 0.01 rad)^2.
MoverSighting seen(int subject, const Eigen::Vector2d& p, const Pose2<double>& from, const Eigen::Vector2d& z) {
  const Eigen::Matrix2d R = Eigen::Vector2d(0.05 * 0.05, 0.01 * 0.01).asDiagonal();
  return MoverSighting{subject, p, world_noise(from, z, R)};
}

}  // namespace

TEST_CASE("mover_motion: the world-frame noise is G R G^T with G the inverse observation's Jacobian") {
  const Pose2<double> x{1.0, -2.0, 0.7};
  const Eigen::Vector2d z(3.5, -0.4);
  Eigen::Matrix2d G;
  const double h = 1e-6;
  for (int k = 0; k < 2; ++k) {
    Eigen::Vector2d dz = Eigen::Vector2d::Zero();
    dz(k) = h;
    G.col(k) = (inverse_observation(x, z + dz) - inverse_observation(x, z - dz)) / (2 * h);
  }
  const Eigen::Matrix2d R = Eigen::Vector2d(0.04, 0.0001).asDiagonal();
  const Eigen::Matrix2d want = G * R * G.transpose();
  CHECK((world_noise(x, z, R) - want).norm() < 1e-8 * want.norm());
}

TEST_CASE("mover_motion: buckets by the robot's motion in units of both sightings' noise") {
  const Pose2<double> me{0, 0, 0};
  const Eigen::Vector2d p0(3, 1);
  const Eigen::Vector2d z(p0.norm(), std::atan2(p0.y(), p0.x()));
  const MoverSighting made = seen(2, p0, me, z);
  double m = 0;

  SUBCASE("a robot that did not move: under 1 sigma") {
    CHECK(mover_bucket(made, seen(2, p0, me, z), &m) == MoverBucket::kUnder1Sigma);
    CHECK(m == doctest::Approx(0));
  }
  // delta = 10 L u with L L^T = Sigma0 + Sigma_now and |u| = 1 is 10 sigma for any direction u.
  const Eigen::Matrix2d L = Eigen::LLT<Eigen::Matrix2d>(2 * made.sigma).matrixL();
  const Eigen::Vector2d u = Eigen::Vector2d(1, 1).normalized();
  SUBCASE("a robot that moved 10 sigma: over 3 sigma") {
    CHECK(mover_bucket(made, seen(2, p0 + 10 * L * u, me, z), &m) == MoverBucket::kOver3Sigma);
    CHECK(m == doctest::Approx(10));
  }
  SUBCASE("2 sigma: 1-3 sigma") {
    CHECK(mover_bucket(made, seen(2, p0 + 2 * L * u, me, z), &m) == MoverBucket::k1To3Sigma);
    CHECK(m == doctest::Approx(2));
  }
  SUBCASE("a landmark made from a tube, or from another robot: something else, whatever the motion") {
    const MoverSighting tube{8, Eigen::Vector2d::Zero(), Eigen::Matrix2d::Zero()};
    CHECK(mover_bucket(tube, seen(2, p0, me, z), &m) == MoverBucket::kOtherLandmark);
    CHECK(m == -1);
    CHECK(mover_bucket(made, seen(3, p0, me, z)) == MoverBucket::kOtherLandmark);
    CHECK(mover_bucket(MoverSighting{}, seen(2, p0, me, z)) == MoverBucket::kOtherLandmark);
  }
}

TEST_CASE("mover_motion: the observer remembers what made each landmark and splits the false pairs") {
  // Robot 1 observes from the origin facing +x; robot 2 stands at (3, 0); robot 3 drives 2 m in y.
  std::vector<std::vector<mrclam::PoseSample>> tracks(mrclam::kRobots + 1);
  for (int k = 1; k <= mrclam::kRobots; ++k) tracks[k] = {{0.0, 0, 0, 0}, {1.0, 0, 0, 0}};
  tracks[2] = {{0.0, 3, 0, 0}, {1.0, 3, 0, 0}};
  tracks[3] = {{0.0, 4, -1, 0}, {1.0, 4, 1, 0}};
  MoverMotion mm(tracks, 1);
  const Eigen::Matrix2d R = Eigen::Vector2d(0.05 * 0.05, 0.01 * 0.01).asDiagonal();
  // Scan 1 (t = 0): robot 2, robot 3 and tube 7 (truth 0) seen, each made a landmark (ids 0, 1, 2).
  const std::vector<SimObservation> a{{Eigen::Vector2d(3, 0), -1, R},
                                      {Eigen::Vector2d(std::hypot(4, 1), std::atan2(-1, 4)), -1, R},
                                      {Eigen::Vector2d(5, 0.3), 0, R}};
  // Scan 2 (t = 1): robot 2, robot 3 (moved) and an unknown barcode (subject 0, a false detection).
  const std::vector<SimObservation> b{{Eigen::Vector2d(3, 0), -1, R},
                                      {Eigen::Vector2d(std::hypot(4, 1), std::atan2(1, 4)), -1, R},
                                      {Eigen::Vector2d(2, 0.1), -1, R}};
  mm.add_subjects(0.0, a, {2, 3, 7});
  mm.add_subjects(1.0, b, {2, 3, 0});
  const std::vector<FeatureId> none(3, kNewFeature), made{0, 1, 2};
  mm.on_scan(ScanOutcome{0.0, &a, &none, &made});
  SUBCASE("robot 2 stood, robot 3 moved 2 m, the unknown barcode is not a robot") {
    const std::vector<FeatureId> paired{0, 1, 0};
    mm.on_scan(ScanOutcome{1.0, &b, &paired, &none});
    const MoverCounts& c = mm.counts();
    CHECK(c.bucket[0] == 1);  // robot 2 with the landmark made from robot 2 where it still is
    CHECK(c.bucket[1] == 0);
    CHECK(c.bucket[2] == 1);  // robot 3 moved 2 m: far beyond centimetres of noise
    CHECK(c.bucket[3] == 0);
    CHECK(c.false_detections == 1);
    CHECK(c.total() == 2);
    CHECK(c.unmatched == 0);
  }
  SUBCASE("robot 3 paired with the tube's landmark: something else") {
    const std::vector<FeatureId> paired{kNewFeature, 2, kNewFeature};
    mm.on_scan(ScanOutcome{1.0, &b, &paired, &none});
    CHECK(mm.counts().bucket[3] == 1);
    CHECK(mm.counts().total() == 1);
  }
}
