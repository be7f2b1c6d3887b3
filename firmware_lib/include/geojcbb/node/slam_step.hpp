// node: one EKF-SLAM step with data association, the unit of work of the device loop and of the
// host's evaluation (host_tools/eval), so both run the same code:
//   predict(odometry)  ...  step(scan):
//     predict_local(r + d) -> associate (strategy) -> update -> augment -> review
// Augmentation rule: an observation left kNewFeature becomes a landmark only if its nearest d2
// also exceeds a second gate (chi-square level `new_landmark_level`, 2 dof); between the gates it
// is dropped. review() then keeps clutter out of the map (tentative landmarks, ekf/landmark_book.hpp).
// No heap: the object holds the filter and every workspace, sized by the Bounds; typically static
// on the device. Every call validates first and changes no state unless it returns kOk.
#pragma once

#include <cstdint>

#include "geojcbb/associate.hpp"
#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/core/strategy.hpp"
#include "geojcbb/ekf/slam.hpp"

namespace geojcbb::node {

/// The step's settings: every option of core/options.h (core/settings.hpp).
using geojcbb::StepSettings;

/// Per observation of a scan, what became of it.
enum class Outcome : std::uint8_t {
  kPaired = 0,    ///< feature: the map landmark's id
  kNewLandmark,   ///< no compatible candidate; became the landmark `feature`
  kNewDropped,    ///< no compatible candidate, but inside the augmentation gate (or augmentation off): dropped
  kUnmatched,     ///< compatible candidates, left unpaired by the search (ambiguous)
  kNotAugmented,  ///< would have become a landmark, but the map is full
};

/// Instruction or cycle counts of the stages, from the clock the caller supplies (0 without).
struct StageCounts {
  std::uint32_t predict_local = 0, associate = 0, update = 0, augment_review = 0, total = 0;
};

template <typename T, class B>
struct StepResult {
  int count = 0;  ///< observations
  std::array<Outcome, B::kMaxObservations> outcome{};
  std::array<FeatureId, B::kMaxObservations> feature{};  ///< see Outcome; -1 when none
  std::array<T, B::kMaxObservations> d2{};               ///< the association's d2 (core semantics)
  AssociationDiagnostics diag;
  ekf::LocalMapStats local;
  ekf::ReviewStats review;
  StageCounts counts;
};

/// A free-running counter read before and after each stage (e.g. SysTick or an instruction count);
/// nullptr: no counts.
using CounterFn = std::uint32_t (*)();

template <typename T, class B>
class SlamStep {
 public:
  /// Builds the strategy's configuration and the augmentation gate.
  /// @return kOk; kInvalidInput for bad parameters (a bad view or policy too); statuses of
  ///         make_strategy / chi2_inv. No state change unless kOk.
  [[nodiscard]] Status configure(const StepSettings<T>& s) {
    AssociationConfig<T, B> cfg;
    Status st = make_strategy(s.strategy, s, cfg);  // every option's range, besides the preset
    if (st != Status::kOk) return st;
    double gate = 0;
    st = chi2_inv(s.new_landmark_level, 2, gate);
    if (st != Status::kOk) return st;
    double static_gate = 0;  // 0: the static-gate rule off
    if (s.static_gate_level > 0) {
      st = chi2_inv(s.static_gate_level, 2, static_gate);
      if (st != Status::kOk) return st;
    }
    const ekf::LandmarkPolicy policy{s.confirm_hits, s.max_misses, s.max_tentative_reviews, s.miss_probability,
                                     static_cast<float>(static_gate)};
    if (!policy.valid()) return Status::kInvalidInput;
    cfg_ = cfg;
    gate_ = static_cast<T>(gate);
    view_ = ekf::Visibility<T>{s.min_range_m, s.max_range_m, s.half_fov_rad, s.occlusion_rad};
    policy_ = policy;
    filter_.first_estimates_jacobians = s.first_estimates_jacobians;
    augment_ = s.augment;
    configured_ = true;
    return Status::kOk;
  }

  bool configured() const { return configured_; }
  const ekf::Slam<T, B>& slam() const { return slam_; }

  /// @return the statuses of ekf::Slam::reset.
  [[nodiscard]] Status reset(const Pose2<T>& x0, const Mat3<T>& P0) { return slam_.reset(x0, P0, filter_); }
  /// ekf::Slam::relocalise: the pose re-initialised (robot carried), the map kept.
  [[nodiscard]] Status relocalise(const Pose2<T>& x, const Mat3<T>& Pxx) { return slam_.relocalise(x, Pxx); }

  /// A landmark known beforehand (ekf::Slam::add_known_landmark), after reset().
  [[nodiscard]] Status add_known_landmark(const Vec2<T>& l, const Mat2<T>& Pll, FeatureId& id) {
    return slam_.add_known_landmark(l, Pll, id);
  }

  /// @return the statuses of ekf::Slam::predict.
  [[nodiscard]] Status predict(const ekf::Odometry<T>& u) { return slam_.predict(u); }

  /// One scan. `clock` may be nullptr.
  /// @return kOk; kInvalidInput when not configured; the statuses of predict_local, associate and
  ///         update (then nothing changed). A full map is not an error: the observations it
  ///         turns away are reported as kNotAugmented.
  [[nodiscard]] Status step(const Observations<T, B>& obs, StepResult<T, B>& out, CounterFn clock = nullptr) {
    const std::uint32_t t0 = clock ? clock() : 0;
    ekf::LocalMapStats local;
    Status st = prepare(local);
    if (st != Status::kOk) return st;
    const std::uint32_t t1 = clock ? clock() : 0;
    st = associate(obs, pred_, cfg_, ws_, assoc_);
    if (st != Status::kOk) return st;
    const std::uint32_t t2 = clock ? clock() : 0;
    st = commit(obs, assoc_, out, clock);
    if (st != Status::kOk) return st;
    out.local = local;
    out.counts.predict_local = t1 - t0;
    out.counts.associate = t2 - t1;
    out.counts.total += t2 - t0;
    return Status::kOk;
  }

  /// The two halves of step() around the association, for a caller that associates by other means
  /// (the evaluation's ground-truth reference): prepare() predicts the local map, prediction()
  /// reads it, commit() updates, augments and reviews with the given association.
  [[nodiscard]] Status prepare(ekf::LocalMapStats& local) {
    if (!configured_) return Status::kInvalidInput;
    return slam_.predict_local(cfg_.local_radius_m, ekf_ws_, pred_, local);
  }
  const Prediction<T, B>& prediction() const { return pred_; }
  /// The configured association on the prepared prediction (what step() runs between the halves).
  [[nodiscard]] Status associate_prepared(const Observations<T, B>& obs, Association<T, B>& out) {
    if (!configured_) return Status::kInvalidInput;
    return associate(obs, pred_, cfg_, ws_, out);
  }
  T augmentation_gate() const { return gate_; }

  /// @return kOk; kInvalidInput when not configured or for a count mismatch; the statuses of
  ///         update (then nothing changed).
  [[nodiscard]] Status commit(const Observations<T, B>& obs, const Association<T, B>& assoc, StepResult<T, B>& out,
                              CounterFn clock = nullptr) {
    if (!configured_ || assoc.count != obs.count) return Status::kInvalidInput;
    const std::uint32_t t2 = clock ? clock() : 0;
    Status st = slam_.update(obs, assoc, ekf_ws_);
    if (st != Status::kOk) return st;
    const std::uint32_t t3 = clock ? clock() : 0;
    // From here on nothing can fail: the outputs are written.
    out.count = obs.count;
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      const FeatureId f = assoc.feature[i];
      out.d2[i] = assoc.d2[i];
      out.feature[i] = f >= 0 ? f : -1;
      if (f >= 0) {
        out.outcome[i] = Outcome::kPaired;
      } else if (f == kUnmatched) {
        out.outcome[i] = Outcome::kUnmatched;
      } else if (!augment_ || !(assoc.d2[i] > gate_)) {
        out.outcome[i] = Outcome::kNewDropped;
      } else {
        FeatureId id = -1;
        // update() accepted every pair; a new landmark's z and R were validated by the caller's
        // association (associate() validates them): only a full map can refuse.
        if (slam_.augment(obs.z[i], obs.R[i], id) == Status::kOk) {
          out.outcome[i] = Outcome::kNewLandmark;
          out.feature[i] = id;
        } else {
          out.outcome[i] = Outcome::kNotAugmented;
        }
      }
    }
    ekf::ReviewStats rs;
    // The view and policy were validated by configure(), the counts above.
    if (slam_.review(pred_, assoc, view_, policy_, rs) != Status::kOk) rs = ekf::ReviewStats{};
    const std::uint32_t t4 = clock ? clock() : 0;
    out.diag = assoc.diag;
    out.review = rs;
    out.counts = StageCounts{0, 0, t3 - t2, t4 - t3, t4 - t2};
    return Status::kOk;
  }

 private:
  ekf::Slam<T, B> slam_;
  ekf::SlamWorkspace<T, B> ekf_ws_;
  Prediction<T, B> pred_;
  AssociationWorkspace<T, B> ws_;
  Association<T, B> assoc_;
  AssociationConfig<T, B> cfg_;
  T gate_ = T(0);
  ekf::Visibility<T> view_;
  ekf::LandmarkPolicy policy_;
  ekf::FilterOptions filter_;
  bool augment_ = true;
  bool configured_ = false;
};

}  // namespace geojcbb::node
