// host_tools/runs: the other robots' false pairs by how far the robot moved (mover_motion.hpp).
#include "geojcbb_host/mover_motion.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace geojcbb::host {

namespace {
bool is_robot(int subject) { return subject >= 1 && subject <= mrclam::kRobots; }
}  // namespace

const char* mover_bucket_title(MoverBucket b) {
  switch (b) {
    case MoverBucket::kUnder1Sigma: return "<1 sigma";
    case MoverBucket::k1To3Sigma: return "1-3 sigma";
    case MoverBucket::kOver3Sigma: return ">3 sigma";
    case MoverBucket::kOtherLandmark: break;
  }
  return "landmark of something else";
}

const char* mover_bucket_key(MoverBucket b) {
  switch (b) {
    case MoverBucket::kUnder1Sigma: return "under_1_sigma";
    case MoverBucket::k1To3Sigma: return "1_to_3_sigma";
    case MoverBucket::kOver3Sigma: return "over_3_sigma";
    case MoverBucket::kOtherLandmark: break;
  }
  return "landmark_of_something_else";
}

Eigen::Matrix2d world_noise(const Pose2<double>& observer, const Eigen::Vector2d& z, const Eigen::Matrix2d& R) {
  // l = p + r (cos a, sin a), a = theta + bearing: G = dl / d(r, bearing).
  const double a = observer.theta + z.y(), c = std::cos(a), s = std::sin(a), r = z.x();
  Eigen::Matrix2d G;
  G << c, -r * s, s, r * c;
  return G * R * G.transpose();
}

MoverBucket mover_bucket(const MoverSighting& made, const MoverSighting& now, double* m_out) {
  if (m_out != nullptr) *m_out = -1;
  if (!is_robot(now.subject) || made.subject != now.subject) return MoverBucket::kOtherLandmark;
  const Eigen::Vector2d delta = now.p - made.p;
  const Eigen::Matrix2d S = made.sigma + now.sigma;
  const Eigen::LLT<Eigen::Matrix2d> llt(S);
  // Both are G R G^T with R positive definite and r > 0, so S is; a broken one reads as far moved.
  const double m =
      llt.info() == Eigen::Success ? std::sqrt(delta.dot(llt.solve(delta))) : std::numeric_limits<double>::infinity();
  if (m_out != nullptr) *m_out = m;
  if (m < 1) return MoverBucket::kUnder1Sigma;
  return m <= 3 ? MoverBucket::k1To3Sigma : MoverBucket::kOver3Sigma;
}

MoverCounts& MoverCounts::operator+=(const MoverCounts& o) {
  for (int k = 0; k < kMoverBuckets; ++k) bucket[static_cast<std::size_t>(k)] += o.bucket[static_cast<std::size_t>(k)];
  false_detections += o.false_detections;
  unmatched += o.unmatched;
  truth_gaps += o.truth_gaps;
  return *this;
}

MoverMotion::MoverMotion(std::vector<std::vector<mrclam::PoseSample>> tracks, int observer)
    : tracks_(std::move(tracks)), observer_(observer) {
  if (!is_robot(observer) || tracks_.size() <= static_cast<std::size_t>(mrclam::kRobots)) {
    throw std::invalid_argument("MoverMotion: a track per robot and an observer among them expected");
  }
}

void MoverMotion::add_subjects(double t_s, const std::vector<SimObservation>& obs, const std::vector<int>& subjects) {
  if (obs.size() != subjects.size()) throw std::invalid_argument("MoverMotion: a subject per observation expected");
  for (std::size_t i = 0; i < obs.size(); ++i) {
    // Two observations of one frame with the same values and different subjects: neither is known.
    const auto [it, fresh] = subject_of_.emplace(Key{t_s, obs[i].z.x(), obs[i].z.y()}, subjects[i]);
    if (!fresh && it->second != subjects[i]) it->second = -1;
  }
}

bool MoverMotion::position(int subject, double t_s, mrclam::PoseSample& out) {
  const std::vector<mrclam::PoseSample>& tr = tracks_[static_cast<std::size_t>(subject)];
  if (mrclam::interpolate_truth(tr, t_s, out)) return true;
  if (tr.empty()) return false;
  // Outside the track or across a gap the Vicon did not bridge: the nearest sample, counted.
  const auto after =
      std::lower_bound(tr.begin(), tr.end(), t_s, [](const mrclam::PoseSample& p, double t) { return p.t < t; });
  if (after == tr.end()) {
    out = tr.back();
  } else if (after == tr.begin() || after->t - t_s < t_s - std::prev(after)->t) {
    out = *after;
  } else {
    out = *std::prev(after);
  }
  ++counts_.truth_gaps;
  return true;
}

MoverSighting MoverMotion::sighting(int subject, double t_s, const SimObservation& o) {
  MoverSighting s;
  s.subject = subject;
  if (!is_robot(subject)) return s;
  mrclam::PoseSample seen{}, me{};
  if (!position(subject, t_s, seen) || !position(observer_, t_s, me)) {
    throw std::runtime_error("MoverMotion: robot " + std::to_string(subject) + " or " + std::to_string(observer_) +
                             " has no ground truth");
  }
  s.p = Eigen::Vector2d(seen.x, seen.y);
  s.sigma = world_noise(Pose2<double>{me.x, me.y, me.theta}, o.z, o.R);
  return s;
}

void MoverMotion::on_scan(const ScanOutcome& s) {
  const std::vector<SimObservation>& scan = *s.scan;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const SimObservation& o = scan[i];
    const FeatureId paired = (*s.paired)[i], added = (*s.added)[i];
    if (paired < 0 && added < 0) continue;
    const auto it = subject_of_.find(Key{s.t_s, o.z.x(), o.z.y()});
    const int subject = it == subject_of_.end() ? -1 : it->second;
    counts_.unmatched += subject < 0;
    const MoverSighting now = sighting(subject, s.t_s, o);
    if (paired >= 0 && o.truth < 0) {  // a false pair with clutter (RunScorer's fp_clutter)
      if (!is_robot(subject)) {
        ++counts_.false_detections;
      } else {
        const auto id = static_cast<std::size_t>(paired);
        // A landmark not made by this run's observations (a known or seeded one): of something else.
        const MoverSighting made = id < made_.size() ? made_[id] : MoverSighting{};
        ++counts_.bucket[static_cast<std::size_t>(mover_bucket(made, now))];
      }
    }
    if (added >= 0) {
      const auto id = static_cast<std::size_t>(added);
      if (made_.size() <= id) made_.resize(id + 1);
      made_[id] = now;
    }
  }
}

}  // namespace geojcbb::host
