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
#include <limits>

#include "geojcbb/associate.hpp"
#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/core/strategy.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/reloc/align.hpp"

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

/// Where the robot stands with the relocaliser (StepSettings::relocalise).
enum class Localisation : std::uint8_t {
  kTracking = 0,  ///< the pose is trusted: association as usual
  kLost,          ///< the pose is not trusted: each scan is aligned against the map, nothing else
  kConfirming,    ///< relocalised at an aligned pose: associated as usual, not yet found
};

/// The relocaliser's part of a step.
struct RelocStats {
  Localisation state = Localisation::kTracking;  ///< after the step
  bool aligned = false;                          ///< the scan was aligned against the map (the robot was lost)
  bool relocalised = false;                      ///< the alignment was accepted: the filter was reset at its pose
  bool found = false;                            ///< this scan confirmed the pose: back to tracking
  bool rejected = false;                         ///< this scan failed the confirmation: lost again
  int inliers = 0, rival_inliers = 0, misses = 0, hypotheses = 0;  ///< of the alignment
};

/// Instruction or cycle counts of the stages, from the clock the caller supplies (0 without).
struct StageCounts {
  std::uint32_t predict_local = 0, associate = 0, update = 0, augment_review = 0, total = 0;
  std::uint32_t relocalise = 0;  ///< the alignment of a lost scan (0 otherwise)
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
  RelocStats reloc;
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
    reloc::AlignOptions<T> align;
    align.base_pairs = s.reloc_base_pairs;
    align.min_inliers = s.reloc_min_inliers;
    align.margin = s.reloc_margin;
    align.min_range_m = s.min_range_m;
    align.max_range_m = s.max_range_m;
    align.half_fov_rad = s.half_fov_rad;
    if (!align.valid()) return Status::kInvalidInput;
    cfg_ = cfg;
    align_ = align;
    reloc_ = s.relocalise;
    reloc_lost_position_var_ = s.reloc_lost_position_var_m2;
    reloc_lost_heading_var_ = s.reloc_lost_heading_var_rad2;
    reloc_inflation_ = s.reloc_inflation;
    reloc_confirm_scans_ = s.reloc_confirm_scans;
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
  [[nodiscard]] Status reset(const Pose2<T>& x0, const Mat3<T>& P0) {
    const Status st = slam_.reset(x0, P0, filter_);
    if (st == Status::kOk) state_ = Localisation::kTracking;
    return st;
  }
  /// ekf::Slam::relocalise: the pose re-initialised (robot carried), the map kept.
  [[nodiscard]] Status relocalise(const Pose2<T>& x, const Mat3<T>& Pxx) { return slam_.relocalise(x, Pxx); }

  /// The user says the robot is lost (carried, or its pose known to be wrong): with the relocaliser
  /// on (StepSettings::relocalise), each scan from the next on is aligned against the map until a
  /// pose is accepted and confirmed. The relocaliser off: nothing changes.
  void lost() {
    if (configured_ && reloc_) state_ = Localisation::kLost;
  }
  Localisation localisation() const { return state_; }

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
    RelocStats rs;
    Status st = localise(obs, rs);
    if (st != Status::kOk) return st;
    const std::uint32_t t_reloc = clock ? clock() : 0;
    if (state_ == Localisation::kLost) {  // not aligned: the scan is not used
      unused(obs, out);
      out.reloc = rs;
      out.counts.relocalise = t_reloc - t0;  // aligned (the robot is lost)
      out.counts.total = t_reloc - t0;
      return Status::kOk;
    }
    ekf::LocalMapStats local;
    st = prepare(local);
    if (st != Status::kOk) return st;
    const std::uint32_t t1 = clock ? clock() : 0;
    st = associate(obs, pred_, cfg_, ws_, assoc_);
    if (st != Status::kOk) return st;
    const std::uint32_t t2 = clock ? clock() : 0;
    st = commit(obs, assoc_, out, clock);
    if (st != Status::kOk) return st;
    out.local = local;
    out.counts.relocalise = rs.aligned ? t_reloc - t0 : 0;
    out.counts.predict_local = t1 - t_reloc;
    out.counts.associate = t2 - t1;
    out.counts.total += t2 - t0;
    confirm(out, assoc_.jointly_compatible, rs);
    out.reloc = rs;
    return Status::kOk;
  }

  /// The relocaliser's halves of step(), for a caller that runs the halves itself (the evaluation).
  /// localise() before prepare(): with the relocaliser on and the robot lost (the pose covariance
  /// over a trigger, or asked), the scan is aligned against the map's confirmed landmarks, and an
  /// accepted pose re-initialises the filter's pose (Slam::relocalise, the fit's covariance times
  /// reloc_inflation). When localisation() is still kLost afterwards, the scan must not be
  /// associated (unused() writes its result). The relocaliser off: nothing happens.
  /// @return kOk; kInvalidInput when not configured; the statuses of reloc::align.
  [[nodiscard]] Status localise(const Observations<T, B>& obs, RelocStats& rs) {
    if (!configured_) return Status::kInvalidInput;
    rs = RelocStats{};
    rs.state = state_;
    if (!reloc_) return Status::kOk;
    if (state_ == Localisation::kTracking) {
      const T pos_var = slam_.cov(0, 0) + slam_.cov(1, 1);
      if (!(pos_var < reloc_lost_position_var_) || !(slam_.cov(2, 2) < reloc_lost_heading_var_)) {
        state_ = Localisation::kLost;
      }
    }
    rs.state = state_;
    if (state_ != Localisation::kLost) return Status::kOk;
    align_ws_.clear_map();
    for (int j = 0; j < slam_.landmarks(); ++j) {  // <= kMaxLandmarks
      if (slam_.hits(j) < policy_.confirm_hits) continue;
      const int r = ekf::Layout::landmark(j);
      Mat2<T> P;
      P << slam_.cov(r, r), slam_.cov(r, r + 1), slam_.cov(r, r + 1), slam_.cov(r + 1, r + 1);
      const Status st = align_ws_.push_landmark(slam_.landmark(j), P);
      if (st != Status::kOk) return st;
    }
    Status st = reloc::align(obs, align_, align_ws_, align_out_);
    if (st != Status::kOk) return st;
    rs.aligned = true;
    rs.inliers = align_out_.inliers;
    rs.rival_inliers = align_out_.rival_inliers;
    rs.misses = align_out_.misses;
    rs.hypotheses = align_out_.hypotheses;
    if (!align_out_.accepted) return Status::kOk;
    Mat3<T> lost;
    for (int r = 0; r < 3; ++r) {    // <= 3
      for (int c = 0; c < 3; ++c) {  // <= 3
        lost(r, c) = slam_.cov(r, c);
      }
    }
    st = slam_.relocalise(align_out_.pose, align_out_.cov * reloc_inflation_);
    if (st != Status::kOk) return st;
    lost_cov_ = lost;
    rs.relocalised = true;
    state_ = reloc_confirm_scans_ > 0 ? Localisation::kConfirming : Localisation::kTracking;
    rs.found = state_ == Localisation::kTracking;
    rs.state = state_;
    confirm_left_ = reloc_confirm_scans_;
    skip_confirm_ = true;  // the scan that was aligned does not confirm itself
    return Status::kOk;
  }

  /// After commit(): while confirming, a scan after the relocalisation that pairs at least
  /// reloc_min_inliers map landmarks in a jointly compatible answer counts; reloc_confirm_scans of
  /// them make the robot found, one that does not sends it back to lost (with the pose covariance
  /// it had when lost).
  void confirm(const StepResult<T, B>& out, bool jointly_compatible, RelocStats& rs) {
    if (state_ == Localisation::kConfirming && !skip_confirm_) {
      int paired = 0;
      for (int i = 0; i < out.count; ++i) paired += out.outcome[i] == Outcome::kPaired;  // <= kMaxObservations
      if (paired >= align_.min_inliers && jointly_compatible) {
        if (--confirm_left_ <= 0) {
          state_ = Localisation::kTracking;
          rs.found = true;
        }
      } else if (slam_.relocalise(slam_.pose(), lost_cov_) == Status::kOk) {  // validated when it was set
        state_ = Localisation::kLost;
        rs.rejected = true;
      }
    }
    skip_confirm_ = false;
    rs.state = state_;
  }

  /// A scan that is not used (lost, not aligned): every observation kUnmatched, no counts.
  static void unused(const Observations<T, B>& obs, StepResult<T, B>& out) {
    out.count = obs.count;
    out.diag = AssociationDiagnostics{};
    out.local = ekf::LocalMapStats{};
    out.review = ekf::ReviewStats{};
    out.counts = StageCounts{};
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      out.outcome[i] = Outcome::kUnmatched;
      out.feature[i] = kUnmatched;
      out.d2[i] = std::numeric_limits<T>::infinity();
    }
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
  // The relocaliser (StepSettings::relocalise).
  reloc::AlignOptions<T> align_;
  reloc::AlignWorkspace<T, B> align_ws_;
  reloc::AlignResult<T, B> align_out_;
  bool reloc_ = false;
  T reloc_lost_position_var_ = T(0), reloc_lost_heading_var_ = T(0), reloc_inflation_ = T(1);
  int reloc_confirm_scans_ = 0, confirm_left_ = 0;
  bool skip_confirm_ = false;
  Localisation state_ = Localisation::kTracking;
  Mat3<T> lost_cov_ = Mat3<T>::Identity();
};

}  // namespace geojcbb::node
