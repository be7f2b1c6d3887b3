// host_tools/runs: the scoring of one run (run_score.hpp).
#include "geojcbb_host/run_score.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace geojcbb::host {

RunScorer::RunScorer(std::size_t true_landmarks, std::vector<int> landmark_group)
    : mapped_(true_landmarks, 0), first_(true_landmarks, -1), landmark_group_(std::move(landmark_group)) {
  if (!landmark_group_.empty() && landmark_group_.size() != true_landmarks) {
    throw std::runtime_error("landmark_group: one entry per true landmark expected");
  }
}

int RunScorer::truth_of(FeatureId id) const {
  return id >= 0 && static_cast<std::size_t>(id) < feature_truth_.size() ? feature_truth_[static_cast<std::size_t>(id)]
                                                                         : kUnknown;
}

void RunScorer::score(const std::vector<int>& truth, const std::vector<FeatureId>& paired,
                      const std::vector<int>& mover) {
  if (truth.size() != paired.size() || (!mover.empty() && mover.size() != truth.size())) {
    throw std::runtime_error("score: one pairing (and mover) per observation expected");
  }
  res_.observations += static_cast<int>(truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const int t = truth[i];
    const FeatureId f = paired[i];
    const bool known = t >= 0 && mapped_[static_cast<std::size_t>(t)] > 0;
    if (f >= 0) {
      const int ft = truth_of(f);
      ++((t >= 0 && ft == t) ? res_.score.tp : res_.score.fp);
      res_.fp_clutter += t < 0;
      res_.fp_mover += t < 0 && !mover.empty() && mover[i] >= 0;
      if (t >= 0 && ft >= 0 && ft != t)
        ++(f > first_[static_cast<std::size_t>(ft)] ? res_.fp_to_duplicate : res_.fp_to_original);
      if (t >= 0 && ft != t) ++((ft >= 0 && cls(ft) == cls(t)) ? res_.fp_in_group : res_.fp_other_group);
      ++((t >= 0 && ft >= 0 && cls(ft) == cls(t)) ? res_.group_score.tp : res_.group_score.fp);
    } else if (known) {
      ++res_.score.fn;
      ++res_.group_score.fn;
    } else {
      ++res_.score.tn;
      ++res_.group_score.tn;
    }
  }
}

void RunScorer::added(FeatureId id, int truth, int mover) {
  if (id < 0) return;
  const auto k = static_cast<std::size_t>(id);
  if (k >= feature_truth_.size()) {
    feature_truth_.resize(k + 1, kUnknown);
    feature_mover_.resize(k + 1, -1);
  }
  feature_truth_[k] = truth;
  feature_mover_[k] = truth < 0 ? mover : -1;
  if (truth >= 0) {
    ++mapped_[static_cast<std::size_t>(truth)];
    if (first_[static_cast<std::size_t>(truth)] < 0) first_[static_cast<std::size_t>(truth)] = id;
  } else {
    ++res_.spurious_landmarks;
  }
}

void RunScorer::removed(FeatureId id) {
  const int t = truth_of(id);
  if (t == kRemoved || t == kUnknown) return;
  if (t >= 0) {
    --mapped_[static_cast<std::size_t>(t)];
    ++res_.removed_true_landmarks;
  } else {
    ++res_.removed_spurious_landmarks;
  }
  feature_truth_[static_cast<std::size_t>(id)] = kRemoved;
}

void RunScorer::handed_over(FeatureId id) {
  const int t = truth_of(id);
  if (t == kRemoved || t == kUnknown) return;
  if (t >= 0) --mapped_[static_cast<std::size_t>(t)];
  feature_truth_[static_cast<std::size_t>(id)] = kRemoved;
}

Eigen::Vector3d StepRecord::set_estimate(const Pose2<double>& x, const Eigen::Matrix3d& P) {
  estimate = x;
  var_x = P(0, 0);
  var_y = P(1, 1);
  var_theta = P(2, 2);
  Eigen::Vector3d e(estimate.x - truth.x, estimate.y - truth.y, wrap_angle(estimate.theta - truth.theta));
  pose_nees = e.dot(P.ldlt().solve(e));
  return e;
}

void RunScorer::pose(double t_s, const Pose2<double>& truth, const Pose2<double>& estimate, const Eigen::Matrix3d& P) {
  StepRecord r;
  r.t_s = t_s;
  r.truth = truth;
  const Eigen::Vector3d e = r.set_estimate(estimate, P);
  res_.mean_abs_x_m += std::abs(e.x());
  res_.mean_abs_y_m += std::abs(e.y());
  res_.steps.push_back(r);
}

void RunScorer::nis(int paired, double nis_sum) {
  if (res_.steps.empty()) return;
  res_.steps.back().paired = paired;
  res_.steps.back().nis_sum = nis_sum;
}

RunResult RunScorer::finish() const {
  RunResult res = res_;
  res.movers_in_map = 0;
  for (std::size_t k = 0; k < feature_truth_.size(); ++k) {
    res.movers_in_map += feature_truth_[k] != kRemoved && feature_truth_[k] != kUnknown && feature_mover_[k] >= 0;
  }
  if (!res.steps.empty()) {
    res.mean_abs_x_m /= static_cast<double>(res.steps.size());
    res.mean_abs_y_m /= static_cast<double>(res.steps.size());
  }
  return res;
}

bool pose_right(const StepRecord& k) {
  const double ex = k.estimate.x - k.truth.x, ey = k.estimate.y - k.truth.y;
  const double et = wrap_angle(k.estimate.theta - k.truth.theta);
  return std::hypot(ex, ey) < 1.0 && std::abs(et) < 5.0 * kPi<double> / 180 && ex * ex <= 9 * k.var_x &&
         ey * ey <= 9 * k.var_y && et * et <= 9 * k.var_theta;
}

KidnapScore kidnap_score(const RunResult& r, double kidnap_t_s, int window) {
  KidnapScore out;
  const int n = static_cast<int>(r.steps.size());
  int first = n;  // index into r.steps of the first scan after the kidnap
  for (int k = 0; k < n && first == n; ++k)
    if (r.steps[static_cast<std::size_t>(k)].t_s >= kidnap_t_s) first = k;
  auto at = [&](int k) -> const StepRecord& { return r.steps[static_cast<std::size_t>(k)]; };
  for (int k = 0; k < first; ++k) out.anees_before += at(k).pose_nees;
  if (first > 0) out.anees_before /= first;
  for (int k = first; k < n; ++k) {
    out.anees_after += at(k).pose_nees;
    out.pose_error_after_m += std::hypot(at(k).estimate.x - at(k).truth.x, at(k).estimate.y - at(k).truth.y);
    out.false_relocalisation = out.false_relocalisation || (at(k).declared_found && !pose_right(at(k)));
  }
  if (n > first) {
    out.anees_after /= n - first;
    out.pose_error_after_m /= n - first;
  }
  for (int k = first; k < n && out.found_at == 0; ++k) {
    bool right = true;
    for (int q = k; q < n && q < k + window && right; ++q) right = pose_right(at(q)) && at(q).fp == 0;
    if (right) out.found_at = k - first + 1;
  }
  return out;
}

}  // namespace geojcbb::host
