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

#include <array>
#include <cstdint>
#include <limits>

#include "geojcbb/associate.hpp"
#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/core/strategy.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/gate/compatibility.hpp"
#include "geojcbb/reloc/align.hpp"
#include "geojcbb/reloc/loop.hpp"
#include "geojcbb/reloc/window.hpp"

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
  std::uint32_t loop = 0;        ///< the closure check (check_loop; 0 when it did not run)
  std::uint32_t window = 0;      ///< the hypothesis window (check_hypotheses; 0 when it did not run)
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
  reloc::LoopStats<T> loop;
  reloc::WindowStats<T> window;
  StageCounts counts;
};

/// A free-running counter read before and after each stage (e.g. SysTick or an instruction count);
/// nullptr: no counts.
using CounterFn = std::uint32_t (*)();

template <typename T, class B>
class SlamStep {
 public:
  /// Merges of a loop closure's duplicates after one scan's review, at most (loop_merge_d2).
  static constexpr int kMaxMergesPerScan = 4;
  /// A committed loop closure's pairs are applied in this many rounds, most certain first; each
  /// round after the first is linearised at the estimate the rounds before it left (an iterated
  /// update with a bounded number of iterations).
  static constexpr int kClosureRounds = 3;
  /// commit(): the round of a pair with a tentative landmark (tentative_isolated), in no update round.
  static constexpr std::uint8_t kAlone = 255;
  /// Movers remembered (tentative_isolated): landmarks the static gate removes as moved, and
  /// tentative landmarks that jumped (paired on the last scan, their nearest sighting now outside
  /// the pairing gate but inside the augmentation gate). An observation the association made new
  /// within kMoverReach_m of one is the mover again: it is left unmatched (no landmark is made of
  /// it, no tentative landmark there is paired) and the mover follows it. A mover unseen for
  /// kMoverMemoryScans reviews is forgotten; a new one replaces the longest unseen.
  static constexpr int kMaxMovers = 4;
  static constexpr int kMoverMemoryScans = 50;
  static constexpr T kMoverReach_m = T(1);

  /// Builds the strategy's configuration and the augmentation gate.
  /// @return kOk; kInvalidInput for bad parameters (a bad view or policy too); statuses of
  ///         make_strategy / chi2_inv. No state change unless kOk.
  [[nodiscard]] Status configure(const StepSettings<T>& s) {
    // Every option's range, besides the preset (make_strategy refuses the same settings below).
    if (!in_range(s)) return Status::kInvalidInput;
    double gate = 0;
    Status st = chi2_inv(s.new_landmark_level, 2, gate);
    if (st != Status::kOk) return st;
    double static_gate = 0;  // 0: the static-gate rule off
    if (s.static_gate_level > 0) {
      st = chi2_inv(s.static_gate_level, 2, static_gate);
      if (st != Status::kOk) return st;
    }
    const ekf::LandmarkPolicy policy{s.confirm_hits,
                                     s.max_misses,
                                     s.max_tentative_reviews,
                                     s.miss_probability,
                                     static_cast<float>(static_gate),
                                     s.confirm_min_reviews};
    if (!policy.valid()) return Status::kInvalidInput;
    reloc::AlignOptions<T> align;
    align.base_pairs = s.reloc_base_pairs;
    align.min_inliers = s.reloc_min_inliers;
    align.margin = s.reloc_margin;
    align.min_range_m = s.min_range_m;
    align.max_range_m = s.max_range_m;
    align.half_fov_rad = s.half_fov_rad;
    if (!align.valid()) return Status::kInvalidInput;
    reloc::AlignOptions<T> loop_align = align;
    loop_align.min_inliers = s.loop_min_inliers;
    if (!loop_align.valid()) return Status::kInvalidInput;
    // Last: make_strategy checks before it writes, so a refusal here changes nothing either.
    st = make_strategy(s.strategy, s, cfg_);
    if (st != Status::kOk) return st;
    const Mount<T> mount{s.sensor_x_m, s.sensor_y_m, s.sensor_theta_rad};
    (void)slam_.set_mount(mount);  // finite: in_range
    align_ws_.mount = mount;
    loop_align_ = loop_align;
    loop_state_ = reloc::LoopState<T>{};
    closing_ = false;
    window_count_ = 0;
    align_ = align;
    gate_ = static_cast<T>(gate);
    view_ = ekf::Visibility<T>{s.min_range_m, s.max_range_m, s.half_fov_rad, s.occlusion_rad};
    policy_ = policy;
    filter_.first_estimates_jacobians = s.first_estimates_jacobians;
    configured_ = true;
    return Status::kOk;
  }

  bool configured() const { return configured_; }
  const ekf::Slam<T, B>& slam() const { return slam_; }

  /// @return the statuses of ekf::Slam::reset.
  [[nodiscard]] Status reset(const Pose2<T>& x0, const Mat3<T>& P0) {
    const Status st = slam_.reset(x0, P0, filter_);
    if (st == Status::kOk) {
      state_ = Localisation::kTracking;
      failed_scans_ = 0;
      merge_left_ = 0;
      closure_count_ = 0;
      mover_count_ = 0;
      movers_caught_ = 0;
      window_count_ = 0;
    }
    return st;
  }
  /// ekf::Slam::relocalise: the pose re-initialised (robot carried), the map kept.
  [[nodiscard]] Status relocalise(const Pose2<T>& x, const Mat3<T>& Pxx) { return slam_.relocalise(x, Pxx); }

  /// The user says the robot is lost (carried, or its pose known to be wrong): with the relocaliser
  /// on (StepSettings::relocalise), each scan from the next on is aligned against the map until a
  /// pose is accepted and confirmed. The relocaliser off: nothing changes.
  void lost() {
    if (configured_ && cfg_.relocalise) state_ = Localisation::kLost;
  }
  Localisation localisation() const { return state_; }
  /// Landmarks removed as movers and remembered (tentative_isolated) since reset().
  std::uint32_t movers_caught() const { return movers_caught_; }
  /// Movers remembered now (tentative_isolated; at most kMaxMovers).
  int movers() const { return mover_count_; }

  /// A landmark known beforehand (ekf::Slam::add_known_landmark), after reset().
  [[nodiscard]] Status add_known_landmark(const Vec2<T>& l, const Mat2<T>& Pll, FeatureId& id) {
    return slam_.add_known_landmark(l, Pll, id);
  }

  /// @return the statuses of ekf::Slam::predict.
  [[nodiscard]] Status predict(const ekf::Odometry<T>& u) { return slam_.predict(u); }
  /// A pose increment with its covariance (wheel odometry, a vehicle model).
  /// @return the statuses of ekf::Slam::predict.
  [[nodiscard]] Status predict(const ekf::PoseIncrement<T>& u) { return slam_.predict(u); }

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
    st = associate_prepared(obs, assoc_);
    if (st != Status::kOk) return st;
    const std::uint32_t t2 = clock ? clock() : 0;
    // The closure check's and the window's stats in members, not in this frame (the call chain's
    // stack budget).
    reloc::LoopStats<T>& ls = loop_stats_;
    st = check_loop(obs, assoc_, ls);
    if (st != Status::kOk) return st;
    const std::uint32_t t_loop = clock ? clock() : 0;
    st = check_hypotheses(obs, assoc_, window_stats_);
    if (st != Status::kOk) return st;
    const std::uint32_t t_window = clock ? clock() : 0;
    st = commit(obs, assoc_, out, clock);
    if (st != Status::kOk) return st;
    out.loop = ls;
    out.window = window_stats_;
    out.counts.loop = ls.verdict == reloc::LoopVerdict::kNone ? 0 : t_loop - t2;
    const bool windowed = window_stats_.verdict != reloc::WindowVerdict::kNone || cfg_.cluster_first;
    out.counts.window = windowed ? t_window - t_loop : 0;
    out.local = local;
    out.counts.relocalise = rs.aligned ? t_reloc - t0 : 0;
    out.counts.predict_local = t1 - t_reloc;
    out.counts.associate = t2 - t1;
    out.counts.total += t_window - t0;
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
    if (!cfg_.relocalise) return Status::kOk;
    if (state_ == Localisation::kTracking) {
      const T pos_var = slam_.cov(0, 0) + slam_.cov(1, 1);
      if (!(pos_var < cfg_.reloc_lost_position_var_m2) || !(slam_.cov(2, 2) < cfg_.reloc_lost_heading_var_rad2)) {
        state_ = Localisation::kLost;
      }
    }
    rs.state = state_;
    if (state_ != Localisation::kLost) return Status::kOk;
    align_ws_.clear_map();
    for (int j = 0; j < slam_.landmarks(); ++j) {  // <= kMaxLandmarks
      if (slam_.hits(j) < policy_.confirm_hits) continue;
      align_slam_[static_cast<std::size_t>(align_ws_.n)] = static_cast<std::int16_t>(j);
      const Status st = align_ws_.push_landmark(slam_.landmark(j), landmark_covariance(j));
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
    // Re-set with the pose's correlation to the landmarks it was fitted to (their error moves the
    // fit); the observations' part of its covariance times reloc_inflation. The sensitivities go
    // through the update's scratch (ekf_ws_: Hp, lm), unused until prepare().
    Mat3<T> Pobs;
    const int pairs =
        reloc::fit_sensitivities(align_ws_, obs.count, align_out_.pose, ekf_ws_.Hp.data(), ekf_ws_.lm.data(), Pobs);
    for (int k = 0; k < pairs; ++k) {  // <= kMaxObservations: sorted map index -> filter index
      ekf_ws_.lm[static_cast<std::size_t>(k)] =
          align_slam_[static_cast<std::size_t>(align_ws_.index[ekf_ws_.lm[static_cast<std::size_t>(k)]])];
    }
    st = pairs >= 2 ? slam_.relocalise_fitted(align_out_.pose, Pobs * cfg_.reloc_inflation, pairs, ekf_ws_.lm.data(),
                                              ekf_ws_.Hp.data())
                    : Status::kNotPositiveDefinite;
    if (st != Status::kOk) st = slam_.relocalise(align_out_.pose, align_out_.cov * cfg_.reloc_inflation);
    if (st != Status::kOk) return st;
    lost_cov_ = lost;
    rs.relocalised = true;
    state_ = cfg_.reloc_confirm_scans > 0 ? Localisation::kConfirming : Localisation::kTracking;
    rs.found = state_ == Localisation::kTracking;
    rs.state = state_;
    confirm_left_ = cfg_.reloc_confirm_scans;
    skip_confirm_ = true;  // the scan that was aligned does not confirm itself
    return Status::kOk;
  }

  /// After commit(): while confirming, a scan after the relocalisation that pairs at least
  /// reloc_min_inliers map landmarks in a jointly compatible answer counts; reloc_confirm_scans of
  /// them make the robot found, one that does not sends it back to lost (with the pose covariance
  /// it had when lost). While tracking, with reloc_lost_failed_scans > 0: a scan that pairs nothing
  /// although it has reloc_min_inliers observations and as many landmarks in the local region
  /// fails; that many failures in a row make the robot lost (a kidnap the covariance does not show).
  void confirm(const StepResult<T, B>& out, bool jointly_compatible, RelocStats& rs) {
    int paired = 0;
    for (int i = 0; i < out.count; ++i) paired += out.outcome[i] == Outcome::kPaired;  // <= kMaxObservations
    const int need = cfg_.reloc_min_inliers;
    const bool failed = paired == 0 && out.count >= need && pred_.count >= need;
    failed_scans_ = state_ == Localisation::kTracking && failed ? failed_scans_ + 1 : 0;
    if (cfg_.relocalise && cfg_.reloc_lost_failed_scans > 0 && failed_scans_ >= cfg_.reloc_lost_failed_scans) {
      state_ = Localisation::kLost;
      failed_scans_ = 0;
    }
    if (state_ == Localisation::kConfirming && !skip_confirm_) {
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

  /// Between the association and commit(): with loop_check on and the robot tracking, a scan
  /// whose local region holds old landmarks has its closure checked (reloc/loop.hpp): `assoc` is
  /// left as it is (no old landmark in the region, agreement, or the association's closure within
  /// the margin), has its disputed pairs held (kUnmatched) while the alignment's closure is
  /// pending, or gets the alignment's pairs when that closure is committed (commit() then inflates
  /// the pose block and updates at the closure's pose). loop_check off: nothing happens.
  /// @return kOk; kInvalidInput when not configured or for a count mismatch; the statuses of
  ///         reloc::align (then `assoc` unchanged).
  [[nodiscard]] Status check_loop(const Observations<T, B>& obs, Association<T, B>& assoc, reloc::LoopStats<T>& ls) {
    if (!configured_ || assoc.count != obs.count) return Status::kInvalidInput;
    ls = reloc::LoopStats<T>{};
    closing_ = false;
    if (!cfg_.loop_check || state_ != Localisation::kTracking) return Status::kOk;
    auto old = [&](int j) { return slam_.unseen(j) >= cfg_.loop_age && slam_.hits(j) >= policy_.confirm_hits; };
    int in_region = 0;
    for (int a = 0; a < pred_.count; ++a) {  // <= kMaxCandidates
      const int j = slam_.index_of(pred_.id[a]);
      in_region += j >= 0 && old(j);
    }
    if (in_region == 0) {  // away from old ground: the next visit is checked afresh
      loop_state_ = reloc::LoopState<T>{};
      return Status::kOk;
    }
    if (loop_state_.pending == 0 && loop_state_.agreed >= reloc::kLoopSettleScans) return Status::kOk;
    const Pose2<T> xp = slam_.pose();
    const T reach = cfg_.local_radius_m + cfg_.loop_search_m;
    const reloc::SetModel<T> model{cfg_.loop_detection_probability, cfg_.loop_unexplained_density};
    align_ws_.clear_map();
    for (int j = 0; j < slam_.landmarks(); ++j) {  // <= kMaxLandmarks
      if (!old(j) || (slam_.landmark(j) - Vec2<T>(xp.x, xp.y)).squaredNorm() > reach * reach) continue;
      align_slam_[static_cast<std::size_t>(align_ws_.n)] = static_cast<std::int16_t>(j);
      const Status st = align_ws_.push_landmark(slam_.landmark(j), landmark_covariance(j));
      if (st != Status::kOk) return st;
    }
    // An observation the association paired with a landmark that is not old is explained where
    // the filter is: no closure's, so left out of both.
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      const int j = assoc.feature[i] >= 0 ? slam_.index_of(assoc.feature[i]) : -1;
      align_ws_.skip[static_cast<std::size_t>(i)] = j >= 0 && !old(j);
    }
    Status st = reloc::align(obs, loop_align_, align_ws_, align_out_);
    if (st != Status::kOk) return st;
    const int m = obs.count;
    ls.old_landmarks = align_ws_.n;
    ls.inliers = align_out_.inliers;
    ls.rival_inliers = align_out_.rival_inliers;
    // The association's closure: its pairs with old landmarks, as sorted map indices.
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      align_ws_.pick[i] = -1;
      const int j = assoc.feature[i] >= 0 ? slam_.index_of(assoc.feature[i]) : -1;
      if (j < 0 || !old(j)) continue;
      for (int k = 0; k < align_ws_.n; ++k) {  // <= kMaxLandmarks
        if (align_slam_[static_cast<std::size_t>(align_ws_.index[k])] == j)
          align_ws_.pick[i] = static_cast<std::int16_t>(k);
      }
    }
    // Consistent with the pose as it is, without the pose's (perhaps overconfident) covariance.
    const bool fits_as_is = reloc::max_pair_d2(align_ws_, m, xp) <= loop_align_.gate_d2;
    Pose2<T> x_assoc = xp;
    reloc::fit_picked(align_ws_, m, x_assoc);
    ls.ll_association = reloc::set_log_likelihood(align_ws_, m, x_assoc, loop_align_, model);
    ls.association_pose = x_assoc;
    const T jump2 = (align_out_.pose.x - xp.x) * (align_out_.pose.x - xp.x) +
                    (align_out_.pose.y - xp.y) * (align_out_.pose.y - xp.y);
    const bool alternative = align_out_.accepted && jump2 <= cfg_.loop_search_m * cfg_.loop_search_m &&
                             std::abs(wrap_angle(align_out_.pose.theta - xp.theta)) <= cfg_.loop_search_rad;
    const Pose2<T> x_align = align_out_.pose;
    if (alternative) {
      reloc::align_detail::exclusive_inliers(align_ws_, m, x_align, loop_align_.gate_d2);  // its pairs in pick
      ls.ll_alignment = reloc::set_log_likelihood(align_ws_, m, x_align, loop_align_, model);
      ls.alignment_pose = x_align;
    } else {
      for (int i = 0; i < m; ++i) align_ws_.pick[i] = -1;  // <= kMaxObservations
    }
    if (alternative && !reloc::align_detail::distinct(x_align, x_assoc, loop_align_)) {
      ls.verdict = reloc::LoopVerdict::kAgreed;
      loop_state_.pending = 0;
      loop_state_.agreed = std::min(loop_state_.agreed + 1, reloc::kLoopSettleScans);
      return Status::kOk;
    }
    if (!alternative && fits_as_is) {
      ls.verdict = reloc::LoopVerdict::kConsistent;
      loop_state_.pending = 0;
      return Status::kOk;
    }
    loop_state_.agreed = 0;
    bool commit_now = false;
    if (!alternative || !(ls.ll_alignment >= ls.ll_association + cfg_.loop_margin_nats)) {
      // No closure is unique and best: the association's is held too.
      ls.verdict = alternative ? reloc::LoopVerdict::kKept : reloc::LoopVerdict::kNoAlternative;
      loop_state_.pending = 0;
    } else {
      const bool same =
          loop_state_.pending > 0 &&
          !reloc::align_detail::distinct(reloc::corrected(loop_state_.correction, xp), x_align, loop_align_);
      loop_state_.pending = same ? loop_state_.pending + 1 : 1;
      loop_state_.correction = reloc::correction_between(xp, x_align);
      commit_now = loop_state_.pending >= cfg_.loop_confirm_scans;
      ls.verdict = commit_now ? reloc::LoopVerdict::kCommitted : reloc::LoopVerdict::kPending;
    }
    // The disputed observations (paired with an old landmark by either closure): held, or paired
    // as the committed closure says.
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      const int j = assoc.feature[i] >= 0 ? slam_.index_of(assoc.feature[i]) : -1;
      const bool disputed = align_ws_.pick[i] >= 0 || (j >= 0 && old(j));
      if (!disputed) continue;
      ++ls.held;
      if (commit_now && align_ws_.pick[i] >= 0) {
        pair_with(assoc, i, align_slam_[static_cast<std::size_t>(align_ws_.index[align_ws_.pick[i]])],
                  align_ws_.pick_d2[i]);
      } else {
        assoc.feature[i] = kUnmatched;
        assoc.candidate[i] = -1;
      }
    }
    int pairings = 0;
    for (int i = 0; i < m; ++i) pairings += assoc.feature[i] >= 0;  // <= kMaxObservations
    assoc.pairings = pairings;
    if (!commit_now) return Status::kOk;
    const T dx = x_align.x - xp.x, dy = x_align.y - xp.y, dth = wrap_angle(x_align.theta - xp.theta);
    Mat3<T> Q = align_out_.cov;
    Q(0, 0) += dx * dx;
    Q(1, 1) += dy * dy;
    Q(2, 2) += dth * dth;
    close_Q_ = cfg_.loop_inflation * Q;
    close_at_ = x_align;
    closing_ = true;
    loop_state_ = reloc::LoopState<T>{};
    ls.verdict = reloc::LoopVerdict::kCommitted;
    return Status::kOk;
  }

  /// After check_loop() and before commit(): with hypothesis_rivals > 0 and the robot tracking, a scan
  /// is checked for ambiguity (reloc/window.hpp, docs/hypotheses.md). Seeds: the association's
  /// pairs with confirmed landmarks of the region, and for each of the first kMaxAnchors
  /// observations with two or more landmarks in its individual gate, one per such landmark (the
  /// kMaxAnchorChoices nearest), grown by nearest neighbour; each is a pose-only filter scored with
  /// the set likelihood. When the best seed pairs kMinPosePairs or more and a seed that conflicts
  /// with it is within hypothesis_margin_nats, or the best conflicts with the association's, the
  /// window opens with up to 1 + hypothesis_rivals mutually conflicting seeds, the association's among them.
  /// While it is open, each scan moves every hypothesis by the filter's motion (a correction of the
  /// filter's pose, the covariance grown as the filter's), pairs it (the association's member takes
  /// the association's pairs) and adds its score. A hypothesis whose sum leads every other by the
  /// margin closes the window: the association's stands; another (with kMinPosePairs pairs on this
  /// scan) is committed: its pairs replace the association's, the pose block is inflated by
  /// loop_inflation times the correction squared and the update is linearised at its pose, as a
  /// loop closure's. The hypotheses pairing a scan alike, or hypothesis_window_scans scans without a
  /// leader, close it with nothing committed. Meanwhile the association's pairs stand; with
  /// hypothesis_hold, an observation the hypotheses pair differently is held (kUnmatched; a scan
  /// with no pair left is not reviewed). A loop closure's scan (pending or committed) closes it.
  /// With cluster_first, each cluster of observations is paired as a unit first (pair_cluster),
  /// on every tracked scan with the window closed, before the window's part.
  /// @return kOk; kInvalidInput when not configured or for a count mismatch; the statuses of
  ///         AlignWorkspace::push_landmark (then `assoc` unchanged, the window closed).
  [[nodiscard, gnu::noinline, gnu::cold]] Status check_hypotheses(const Observations<T, B>& obs,
                                                                  Association<T, B>& assoc,
                                                                  reloc::WindowStats<T>& out) {
    if (!configured_ || assoc.count != obs.count) return Status::kInvalidInput;
    out = reloc::WindowStats<T>{};
    if ((cfg_.hypothesis_rivals == 0 && !cfg_.cluster_first) || state_ != Localisation::kTracking || closing_ ||
        loop_state_.pending > 0) {
      window_count_ = 0;
      return Status::kOk;
    }
    // The frozen map: the region's confirmed landmarks, their own covariances.
    align_ws_.clear_map();
    for (int a = 0; a < pred_.count; ++a) {  // <= kMaxCandidates
      const int j = slam_.index_of(pred_.id[a]);
      if (!frozen(j)) continue;
      align_slam_[static_cast<std::size_t>(align_ws_.n)] = static_cast<std::int16_t>(j);
      const Status st = align_ws_.push_landmark(slam_.landmark(j), landmark_covariance(j));
      if (st != Status::kOk) {
        window_count_ = 0;
        return st;
      }
    }
    const int m = obs.count;
    const Pose2<T> xp = slam_.pose();
    const Mat3<T> Pxx = slam_.pose_covariance();
    const reloc::SetModel<T> model{cfg_.loop_detection_probability, cfg_.loop_unexplained_density};
    const T gate = cfg_.gate.individual;
    const T margin = cfg_.hypothesis_margin_nats;
    if (cfg_.cluster_first && window_count_ == 0) {
      // Each cluster of kMinPosePairs or more paired as a unit (label_clusters, pair_cluster).
      const int clusters = label_clusters(obs);
      for (int c = 0; c < clusters; ++c) {  // <= kMaxObservations
        int size = 0;
        for (int i = 0; i < m; ++i) {  // <= kMaxObservations
          align_ws_.skip[i] = cluster_label_[i] != c;
          size += cluster_label_[i] == c;
        }
        if (size < reloc::kMinPosePairs) continue;
        const int seeds = seed_hypotheses(obs, assoc, xp, Pxx, model, gate);
        out.regrouped += pair_cluster(obs, assoc, c, seeds, xp, Pxx, model, gate);
      }
      align_ws_.skip.fill(false);
      int pairings = 0;
      for (int i = 0; i < m; ++i) pairings += assoc.feature[i] >= 0;  // <= kMaxObservations
      assoc.pairings = pairings;
    }
    if (cfg_.hypothesis_rivals == 0) return Status::kOk;
    if (window_count_ == 0) {
      const int seeds = seed_hypotheses(obs, assoc, xp, Pxx, model, gate);
      out.seeds = seeds;
      if (seeds <= 1) return Status::kOk;
      const int best = best_seed(seeds);
      const std::int16_t* const bp = seed_pick_[static_cast<std::size_t>(best)].data();
      bool rival = false;
      for (int s = 0; s < seeds; ++s) {  // <= kMaxSeeds
        rival = rival || (reloc::conflict(bp, seed_pick_[static_cast<std::size_t>(s)].data(), m) &&
                          seed_[static_cast<std::size_t>(s)].ll > seed_[static_cast<std::size_t>(best)].ll - margin);
      }
      if (!rival && !reloc::conflict(bp, seed_pick_[0].data(), m)) return Status::kOk;  // the association stands
      if (reloc::pairs(bp, m) < reloc::kMinPosePairs) return Status::kOk;  // no pose in doubt: the gate's business
      // Members: the best; the association's when it conflicts with the best (else the best is the
      // association's path); then the best-scoring seeds that conflict with every member.
      std::array<int, reloc::kMaxHypotheses> member{};
      int count = 0;
      member[static_cast<std::size_t>(count++)] = best;
      window_assoc_ = 0;
      if (reloc::conflict(bp, seed_pick_[0].data(), m)) {
        window_assoc_ = count;
        member[static_cast<std::size_t>(count++)] = 0;
      }
      for (int round = count; round <= cfg_.hypothesis_rivals; ++round) {  // <= kMaxHypotheses
        int next = -1;
        for (int s = 0; s < seeds; ++s) {  // <= kMaxSeeds
          bool apart = true;
          for (int k = 0; k < count && apart; ++k) {  // <= kMaxHypotheses
            const int mk = member[static_cast<std::size_t>(k)];
            apart = s != mk && reloc::conflict(seed_pick_[static_cast<std::size_t>(mk)].data(),
                                               seed_pick_[static_cast<std::size_t>(s)].data(), m);
          }
          if (apart && (next < 0 || seed_[static_cast<std::size_t>(s)].ll > seed_[static_cast<std::size_t>(next)].ll)) {
            next = s;
          }
        }
        if (next < 0) break;
        member[static_cast<std::size_t>(count++)] = next;
      }
      for (int k = 0; k < count; ++k) {  // <= kMaxHypotheses
        const auto s = static_cast<std::size_t>(member[static_cast<std::size_t>(k)]);
        window_[static_cast<std::size_t>(k)] = seed_[s];
        window_pick_[static_cast<std::size_t>(k)] = seed_pick_[s];
        window_d2_[static_cast<std::size_t>(k)].fill(T(0));
      }
      window_count_ = count;
      window_age_ = 1;
      window_pose_ = xp;  // commit() moves it to the filter's pose after the update
      window_cov_ = Pxx;
      out.verdict = reloc::WindowVerdict::kOpened;
      out.hypotheses = count;
      out.held = keep_agreed(assoc);
      return Status::kOk;
    }
    // The window is open: each hypothesis moved as the filter moved, paired and scored.
    Mat3<T> grown = Pxx - window_cov_;
    grown = T(0.5) * (grown + grown.transpose());
    const bool moved = grown(0, 0) >= T(0) && grown(1, 1) >= T(0) && grown(2, 2) >= T(0);
    std::array<Pose2<T>, reloc::kMaxHypotheses> at{};
    for (int k = 0; k < window_count_; ++k) {  // <= kMaxHypotheses
      reloc::PoseHypothesis<T>& h = window_[static_cast<std::size_t>(k)];
      h.x = reloc::corrected(reloc::correction_between(window_pose_, h.x), xp);
      if (moved) h.P += grown;
      at[static_cast<std::size_t>(k)] = h.x;
      // The association's path takes the association's pairs; every other grows its own.
      association_picks(obs, assoc, k == window_assoc_);
      h.ll += reloc::run_hypothesis(obs, align_ws_, model, loop_align_, gate, k != window_assoc_, h);
      window_pick_[static_cast<std::size_t>(k)] = align_ws_.pick;
      for (int i = 0; i < m; ++i)
        window_d2_[static_cast<std::size_t>(k)][i] = align_ws_.pick_d2[i];  // <= kMaxObservations
    }
    window_pose_ = xp;
    window_cov_ = Pxx;
    int lead = 0;
    for (int k = 1; k < window_count_; ++k) {  // <= kMaxHypotheses
      if (window_[static_cast<std::size_t>(k)].ll > window_[static_cast<std::size_t>(lead)].ll) lead = k;
    }
    T second = -std::numeric_limits<T>::infinity();
    for (int k = 0; k < window_count_; ++k) {  // <= kMaxHypotheses
      if (k != lead) second = std::max(second, window_[static_cast<std::size_t>(k)].ll);
    }
    out.lead = window_[static_cast<std::size_t>(lead)].ll - second;
    out.hypotheses = window_count_;
    if (out.lead >= margin && lead == window_assoc_) {  // the association's path won
      window_count_ = 0;
      out.verdict = reloc::WindowVerdict::kMerged;
      return Status::kOk;
    }
    // A correction needs a pose: the leader's pairs on this scan, kMinPosePairs at least.
    if (reloc::pairs(window_pick_[static_cast<std::size_t>(lead)].data(), m) < reloc::kMinPosePairs) out.lead = T(0);
    if (out.lead >= margin) {
      // Committed: the leader's pairs, at its pose before this scan's pairs moved it.
      const Pose2<T> x = at[static_cast<std::size_t>(lead)];
      int pairings = 0;
      for (int i = 0; i < m; ++i) {  // <= kMaxObservations
        const int k = window_pick_[static_cast<std::size_t>(lead)][static_cast<std::size_t>(i)];
        assoc.candidate[i] = -1;
        if (k < 0) {
          assoc.feature[i] = kUnmatched;
          continue;
        }
        pair_with(assoc, i, align_slam_[static_cast<std::size_t>(k)],
                  window_d2_[static_cast<std::size_t>(lead)][static_cast<std::size_t>(i)]);
        ++pairings;
      }
      assoc.pairings = pairings;
      const T dx = x.x - xp.x, dy = x.y - xp.y, dth = wrap_angle(x.theta - xp.theta);
      close_Q_ = Mat3<T>::Zero();
      close_Q_(0, 0) = cfg_.loop_inflation * dx * dx;
      close_Q_(1, 1) = cfg_.loop_inflation * dy * dy;
      close_Q_(2, 2) = cfg_.loop_inflation * dth * dth;
      close_at_ = x;
      closing_ = true;
      window_count_ = 0;
      out.verdict = reloc::WindowVerdict::kCommitted;
      out.held = pairings;
      return Status::kOk;
    }
    bool disputed = false;                           // do two hypotheses pair this scan differently?
    for (int a = 0; a < window_count_; ++a) {        // <= kMaxHypotheses
      for (int b = a + 1; b < window_count_; ++b) {  // <= kMaxHypotheses
        disputed = disputed || reloc::conflict(window_pick_[static_cast<std::size_t>(a)].data(),
                                               window_pick_[static_cast<std::size_t>(b)].data(), m);
      }
    }
    if (!disputed) {  // no scan can tell them apart any more: the association stands
      window_count_ = 0;
      out.verdict = reloc::WindowVerdict::kMerged;
      return Status::kOk;
    }
    out.held = keep_agreed(assoc);
    out.verdict = reloc::WindowVerdict::kHeld;
    if (++window_age_ > cfg_.hypothesis_window_scans) {
      window_count_ = 0;
      out.verdict = reloc::WindowVerdict::kExpired;
    }
    return Status::kOk;
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
    const Status st =
        slam_.predict_local(cfg_.local_radius_m, ekf_ws_, pred_, local, cfg_.tentative_isolated ? &policy_ : nullptr);
    confirmed_ = st == Status::kOk ? local.confirmed : 0;
    return st;
  }
  const Prediction<T, B>& prediction() const { return pred_; }
  /// The configured association on the prepared prediction (what step() runs between the halves).
  /// With tentative_isolated, the association sees only the confirmed landmarks, and the
  /// tentative ones are paired afterwards (pair_tentative).
  [[nodiscard]] Status associate_prepared(const Observations<T, B>& obs, Association<T, B>& out) {
    if (!configured_) return Status::kInvalidInput;
    if (!cfg_.tentative_isolated) return associate(obs, pred_, cfg_, ws_, out);
    const int all = pred_.count;
    pred_.count = confirmed_;  // the leading candidates: C's leading blocks are their own C
    Status st = pred_.C.resize(confirmed_);
    if (st == Status::kOk) st = associate(obs, pred_, cfg_, ws_, out);
    pred_.count = all;
    (void)pred_.C.resize(all);  // all <= kMaxCandidates: it held all before
    if (st != Status::kOk) return st;
    pair_tentative(obs, out);
    follow_movers(obs, out);
    return Status::kOk;
  }
  T augmentation_gate() const { return gate_; }

  /// @return kOk; kInvalidInput when not configured or for a count mismatch; the statuses of
  ///         update (then nothing changed).
  [[nodiscard]] Status commit(const Observations<T, B>& obs, const Association<T, B>& assoc, StepResult<T, B>& out,
                              CounterFn clock = nullptr) {
    if (!configured_ || assoc.count != obs.count) return Status::kInvalidInput;
    const std::uint32_t t2 = clock ? clock() : 0;
    // A committed loop closure (check_loop): the pose block inflated, the update at its pose.
    const bool closing = closing_;
    closing_ = false;
    const Mat3<T> before = slam_.pose_covariance();
    Status st = closing ? slam_.inflate_pose(close_Q_) : Status::kOk;
    if (st != Status::kOk) return st;
    if (closing) order_closure(obs, assoc);
    const bool aside = cfg_.tentative_isolated && set_aside_tentative(obs, assoc, closing);
    const bool rounds = closing || aside;
    st = slam_.update(obs, assoc, ekf_ws_, closing ? &close_at_ : nullptr, rounds ? round_.data() : nullptr, 0);
    if (st != Status::kOk) {
      // Undone: the pose block as it was (it was positive definite, the write cannot fail).
      if (closing) (void)slam_.replace_pose_covariance(before);
      return st;
    }
    // The closure's later rounds, at the estimate the first left; a round the filter refuses is
    // skipped (its pairs stay unused), as update() skips a block after its first.
    for (int r = 1; r < kClosureRounds && closing; ++r) {  // <= kClosureRounds
      (void)slam_.update(obs, assoc, ekf_ws_, nullptr, round_.data(), r);
    }
    if (aside) update_tentative(obs, assoc);
    if (window_count_ > 0) {  // the hypotheses are corrections of the filter's pose as it is now
      window_pose_ = slam_.pose();
      window_cov_ = slam_.pose_covariance();
    }
    const std::uint32_t t3 = clock ? clock() : 0;
    // From here on nothing can fail: the outputs are written.
    out.count = obs.count;
    int evicted = 0;
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      const FeatureId f = assoc.feature[i];
      out.d2[i] = assoc.d2[i];
      out.feature[i] = f >= 0 ? f : -1;
      if (f >= 0) {
        out.outcome[i] = Outcome::kPaired;
      } else if (f == kUnmatched) {
        out.outcome[i] = Outcome::kUnmatched;
      } else if (!cfg_.augment || !(assoc.d2[i] > gate_)) {
        out.outcome[i] = Outcome::kNewDropped;
      } else {
        FeatureId id = -1;
        // update() accepted every pair; a new landmark's z and R were validated by the caller's
        // association (associate() validates them): only a full map can refuse.
        Status added = slam_.augment(obs.z[i], obs.R[i], id);
        FeatureId gone = -1;
        // A full map makes room (evict_when_full): a landmark beyond r + d, not in this scan's
        // prediction, so the pairs above and the review below are untouched.
        if (added != Status::kOk && cfg_.evict_when_full && slam_.evict(cfg_.local_radius_m, gone) == Status::kOk) {
          ++evicted;
          added = slam_.augment(obs.z[i], obs.R[i], id);
        }
        if (added == Status::kOk) {
          out.outcome[i] = Outcome::kNewLandmark;
          out.feature[i] = id;
        } else {
          out.outcome[i] = Outcome::kNotAugmented;
        }
      }
    }
    // A loop closure (check_loop's, or the association's pairs with old landmarks): the old
    // landmarks it re-pairs, each with how long it was unseen, for the merges of its duplicates
    // after this scan's review and the next kLoopSettleScans - 1.
    if (cfg_.loop_merge_d2 > T(0)) note_closure(assoc);
    if (cfg_.tentative_isolated) catch_movers(assoc);
    ekf::ReviewStats rs;
    // The view and policy were validated by configure(), the counts above. A scan the hypothesis
    // window holds is no evidence: its landmarks were not paired because the pose is in doubt.
    const bool held = holding_;
    holding_ = false;
    if (!held && slam_.review(pred_, assoc, view_, policy_, rs) != Status::kOk) rs = ekf::ReviewStats{};
    if (merge_left_ > 0) {
      --merge_left_;
      rs.merged = merge_duplicates(assoc);
      for (int k = 0; k < closure_count_; ++k) ++closure_limit_[k];  // <= kMaxObservations: a review later
    }
    const std::uint32_t t4 = clock ? clock() : 0;
    out.diag = assoc.diag;
    out.review = rs;
    out.review.evicted = evicted;
    out.counts = StageCounts{0, 0, t3 - t2, t4 - t3, t4 - t2};
    return Status::kOk;
  }

 private:
  /// Observation i paired with landmark j (filter index) at d2, its candidate in the prediction
  /// found (-1 when the landmark is not a candidate).  O(kMaxCandidates)
  void pair_with(Association<T, B>& assoc, int i, int j, T d2) const {
    assoc.feature[i] = slam_.id(j);
    assoc.d2[i] = d2;
    assoc.candidate[i] = -1;
    for (int a = 0; a < pred_.count; ++a) {  // <= kMaxCandidates
      if (pred_.id[a] == assoc.feature[i]) assoc.candidate[i] = static_cast<std::int16_t>(a);
    }
  }
  /// Landmark j (a filter index, or -1) is in the frozen map the window and the clusters are scored
  /// against: confirmed by its hits.
  bool frozen(int j) const { return j >= 0 && slam_.hits(j) >= policy_.confirm_hits; }
  /// The seed of the highest set likelihood among the first `seeds` (the first of equals).
  int best_seed(int seeds) const {
    int best = 0;
    for (int s = 1; s < seeds; ++s) {  // <= kMaxSeeds
      if (seed_[static_cast<std::size_t>(s)].ll > seed_[static_cast<std::size_t>(best)].ll) best = s;
    }
    return best;
  }
  /// check_hypotheses() while the window is open: an observation every hypothesis pairs with the
  /// same landmark is paired so; every other is held (kUnmatched). A scan with no pair left is no
  /// evidence for the review (commit() skips it). @return the observations held
  int keep_agreed(Association<T, B>& assoc) {
    if (!cfg_.hypothesis_hold) return 0;
    int held = 0, pairings = 0;
    for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
      const int k = window_pick_[0][static_cast<std::size_t>(i)];
      bool agreed = true;
      for (int h = 1; h < window_count_ && agreed; ++h) {  // <= kMaxHypotheses
        agreed = window_pick_[static_cast<std::size_t>(h)][static_cast<std::size_t>(i)] == k;
      }
      const int j = assoc.feature[i] >= 0 ? slam_.index_of(assoc.feature[i]) : -1;
      if (agreed && k < 0 && !frozen(j)) {
        // No hypothesis pairs it with the frozen map: the association's answer (new, or a
        // tentative landmark) stands.
        pairings += assoc.feature[i] >= 0;
        continue;
      }
      assoc.candidate[i] = -1;
      if (!agreed || k < 0) {
        assoc.feature[i] = kUnmatched;
        ++held;
        continue;
      }
      pair_with(assoc, i, align_slam_[static_cast<std::size_t>(k)], window_d2_[0][static_cast<std::size_t>(i)]);
      ++pairings;
    }
    assoc.pairings = pairings;
    holding_ = pairings == 0;
    return held;
  }
  /// align_ws_.pick: the association's pairs with the frozen map (`use`), or none.  O(m n)
  void association_picks(const Observations<T, B>& obs, const Association<T, B>& assoc, bool use) {
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      align_ws_.pick[i] = -1;
      const int j = use && assoc.feature[i] >= 0 ? slam_.index_of(assoc.feature[i]) : -1;
      for (int k = 0; k < align_ws_.n && j >= 0; ++k) {  // <= kMaxLandmarks
        if (align_slam_[static_cast<std::size_t>(k)] == j) align_ws_.pick[i] = static_cast<std::int16_t>(k);
      }
    }
  }
  /// check_hypotheses() with the window closed: the seeds of this scan in seed_ and seed_pick_ (the
  /// association's first), scored from the filter's pose; none when no observation is ambiguous.
  /// Out of line and cold: it runs on ambiguous scans only. @return the seeds
  /// O(kMaxSeeds kMaxObservations kMaxLandmarks)
  [[gnu::noinline, gnu::cold]] int seed_hypotheses(const Observations<T, B>& obs, const Association<T, B>& assoc,
                                                   const Pose2<T>& xp, const Mat3<T>& Pxx,
                                                   const reloc::SetModel<T>& model, T gate) {
    const int m = obs.count;
    // Anchors: the first observations with two or more landmarks in the individual gate at the
    // filter's pose, each with its nearest kMaxAnchorChoices.
    std::array<std::array<std::int16_t, reloc::kMaxAnchorChoices>, reloc::kMaxAnchors> choice{};
    std::array<std::int16_t, reloc::kMaxAnchors> anchor{};
    int anchors = 0;
    Vec2<T> nu;
    Mat2<T> S;
    Mat23<T> Jx;
    for (int i = 0; i < m && anchors < reloc::kMaxAnchors; ++i) {  // <= kMaxObservations
      if (align_ws_.skip[i]) continue;
      std::array<T, reloc::kMaxAnchorChoices> d2s{};
      auto& c = choice[static_cast<std::size_t>(anchors)];
      c.fill(-1);
      int found = 0;
      for (int j = 0; j < align_ws_.n; ++j) {  // <= kMaxLandmarks
        const T d2 = reloc::window_detail::pair_d2(obs, i, align_ws_, j, xp, Pxx, nu, S, Jx);
        if (!(d2 <= gate)) continue;
        ++found;
        // Insert among the nearest kMaxAnchorChoices.
        int at = reloc::kMaxAnchorChoices;
        while (at > 0 && (c[static_cast<std::size_t>(at - 1)] < 0 || d2s[static_cast<std::size_t>(at - 1)] > d2)) {
          --at;  // <= kMaxAnchorChoices
        }
        if (at >= reloc::kMaxAnchorChoices) continue;
        for (int k = reloc::kMaxAnchorChoices - 1; k > at; --k) {  // <= kMaxAnchorChoices
          c[static_cast<std::size_t>(k)] = c[static_cast<std::size_t>(k - 1)];
          d2s[static_cast<std::size_t>(k)] = d2s[static_cast<std::size_t>(k - 1)];
        }
        c[static_cast<std::size_t>(at)] = static_cast<std::int16_t>(j);
        d2s[static_cast<std::size_t>(at)] = d2;
      }
      if (found >= 2) anchor[static_cast<std::size_t>(anchors++)] = static_cast<std::int16_t>(i);
    }
    if (anchors == 0) return 0;
    // Seed 0: the association's pairs with the frozen map.
    int seeds = 0;
    for (int s = 0; s < 1 + anchors * reloc::kMaxAnchorChoices; ++s) {  // <= kMaxSeeds
      int ai = -1, aj = -1;
      if (s > 0) {
        ai = anchor[static_cast<std::size_t>((s - 1) / reloc::kMaxAnchorChoices)];
        aj = choice[static_cast<std::size_t>((s - 1) / reloc::kMaxAnchorChoices)]
                   [static_cast<std::size_t>((s - 1) % reloc::kMaxAnchorChoices)];
        if (aj < 0) continue;
      }
      association_picks(obs, assoc, s == 0);
      if (s > 0) align_ws_.pick[ai] = static_cast<std::int16_t>(aj);
      reloc::PoseHypothesis<T>& h = seed_[static_cast<std::size_t>(seeds)];
      h.x = xp;
      h.P = Pxx;
      h.ll = reloc::run_hypothesis(obs, align_ws_, model, loop_align_, gate, s > 0, h);
      seed_pick_[static_cast<std::size_t>(seeds)] = align_ws_.pick;
      ++seeds;
    }
    return seeds;
  }

  /// check_hypotheses() with cluster_first: the observations linked into clusters (two within
  /// dbscan_eps_m of each other in the sensor frame are in one) in cluster_label_: connected
  /// components of the eps-graph, grown through a queue (each observation is queued once).
  /// Distances by the law of cosines. Out of line and cold. @return the clusters
  /// O(kMaxObservations^2)
  [[gnu::noinline, gnu::cold]] int label_clusters(const Observations<T, B>& obs) {
    const int m = obs.count;
    std::array<std::uint8_t, B::kMaxObservations> queue;
    auto near = [&](int p, int q) {
      const T rp = obs.z[p].x(), rq = obs.z[q].x();
      return rp * rp + rq * rq - T(2) * rp * rq * fmath::cos(obs.z[p].y() - obs.z[q].y()) <=
             cfg_.dbscan_eps_m * cfg_.dbscan_eps_m;
    };
    cluster_label_.fill(-1);
    int clusters = 0;
    for (int s = 0; s < m; ++s) {  // <= kMaxObservations
      if (cluster_label_[s] >= 0) continue;
      int head = 0, tail = 0;
      cluster_label_[s] = static_cast<std::int8_t>(clusters);
      queue[tail++] = static_cast<std::uint8_t>(s);
      while (head < tail) {  // each observation is queued once: <= kMaxObservations
        const int p = queue[head++];
        for (int q = 0; q < m; ++q) {  // <= kMaxObservations
          if (cluster_label_[q] < 0 && near(p, q)) {
            cluster_label_[q] = static_cast<std::int8_t>(clusters);
            queue[tail++] = static_cast<std::uint8_t>(q);
          }
        }
      }
      ++clusters;
    }
    return clusters;
  }
  /// check_hypotheses() with cluster_first, cluster c (its seeds scored alone by seed_hypotheses:
  /// every other observation skipped): the association's pairs, and one per compatible landmark of
  /// its ambiguous observations, each grown by nearest neighbour at the pose its pairs left (the
  /// members resolved against the unit's posterior). When the best conflicts with the
  /// association's, leads it by hypothesis_margin_nats and pairs kMinPosePairs or more, its pairs
  /// replace the association's in the cluster: an observation it leaves unexplained is kUnmatched
  /// unless the association made it new or paired it outside the frozen map; an observation
  /// elsewhere paired with a landmark it took is kUnmatched. Out of line and cold (a sibling of
  /// seed_hypotheses in the call chain). @return the observations paired anew
  /// O(kMaxObservations (kMaxSeeds + kMaxObservations kMaxLandmarks))
  [[gnu::noinline, gnu::cold]] int pair_cluster(const Observations<T, B>& obs, Association<T, B>& assoc, int c,
                                                int seeds, const Pose2<T>& xp, const Mat3<T>& Pxx,
                                                const reloc::SetModel<T>& model, T gate) {
    const int m = obs.count;
    if (seeds <= 1) return 0;
    const int best = best_seed(seeds);
    const std::int16_t* const bp = seed_pick_[static_cast<std::size_t>(best)].data();
    if (best == 0 || !reloc::conflict(bp, seed_pick_[0].data(), m) ||
        seed_[static_cast<std::size_t>(best)].ll < seed_[0].ll + cfg_.hypothesis_margin_nats ||
        reloc::pairs(bp, m) < reloc::kMinPosePairs) {
      return 0;
    }
    // The best again, for its d2s (deterministic: the same pairs), in seed 0's place.
    align_ws_.pick = seed_pick_[static_cast<std::size_t>(best)];
    reloc::PoseHypothesis<T>& h = seed_[0];
    h.x = xp;
    h.P = Pxx;
    (void)reloc::run_hypothesis(obs, align_ws_, model, loop_align_, gate, true, h);
    int regrouped = 0;
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      const int k = align_ws_.pick[i];
      const int j = assoc.feature[i] >= 0 ? slam_.index_of(assoc.feature[i]) : -1;
      if (cluster_label_[i] == c) {
        if (k >= 0) {
          regrouped += j != align_slam_[static_cast<std::size_t>(k)];
          pair_with(assoc, i, align_slam_[static_cast<std::size_t>(k)], align_ws_.pick_d2[i]);
        } else if (frozen(j)) {
          assoc.feature[i] = kUnmatched;
          assoc.candidate[i] = -1;
          ++regrouped;
        }
        continue;
      }
      // Elsewhere: a landmark this cluster took is not paired twice.
      for (int q = 0; q < m && j >= 0; ++q) {  // <= kMaxObservations
        if (cluster_label_[q] == c && align_ws_.pick[q] >= 0 &&
            align_slam_[static_cast<std::size_t>(align_ws_.pick[q])] == j) {
          assoc.feature[i] = kUnmatched;
          assoc.candidate[i] = -1;
          ++regrouped;
          break;
        }
      }
    }
    return regrouped;
  }

  /// A committed closure's rounds (commit()): the paired observations ranked by their landmark's
  /// position variance (trace of its 2x2 block; the landmarks mapped before the drift first), rank k
  /// of p in round k kClosureRounds / p, the two most certain in the first. Out of line: its loops stay out of commit()'s frame.
  /// O(kMaxObservations^2)
  [[gnu::noinline]] void order_closure(const Observations<T, B>& obs, const Association<T, B>& assoc) {
    std::array<T, B::kMaxObservations> var{};
    int p = 0;
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      const int j = assoc.feature[i] >= 0 ? slam_.index_of(assoc.feature[i]) : -1;
      round_[static_cast<std::size_t>(i)] = 0;
      if (j < 0) continue;  // unpaired, or an unknown id that update() refuses
      const int l = ekf::Layout::landmark(j);
      var[static_cast<std::size_t>(i)] = slam_.cov(l, l) + slam_.cov(l + 1, l + 1);
      ++p;
    }
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      if (assoc.feature[i] < 0 || slam_.index_of(assoc.feature[i]) < 0) continue;
      int rank = 0;                          // the pairs more certain than i (ties by index)
      for (int k = 0; k < obs.count; ++k) {  // <= kMaxObservations
        if (k == i || assoc.feature[k] < 0 || slam_.index_of(assoc.feature[k]) < 0) continue;
        const T vk = var[static_cast<std::size_t>(k)], vi = var[static_cast<std::size_t>(i)];
        rank += vk < vi || (vk == vi && k < i);
      }
      // The first round takes two pairs at least (a pose needs two points).
      round_[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(rank < 2 ? 0 : rank * kClosureRounds / p);
    }
  }

  /// associate_prepared() with tentative_isolated: each observation the association made new is
  /// offered to the tentative landmarks of the prediction (the candidates after the confirmed
  /// ones), each of which takes one observation at most: the pair of smallest individual d2 first,
  /// within the individual gate, until none is left. An unpaired observation's d2 (the augmentation
  /// gate's) becomes the smallest to any candidate, tentative ones included. Out of line: its flags
  /// stay out of the callers' frames.  O(kMaxObservations^2 kMaxCandidates)
  [[gnu::noinline, gnu::cold]] void pair_tentative(const Observations<T, B>& obs, Association<T, B>& out) {
    bool taken[B::kMaxCandidates] = {};
    for (int a = confirmed_; a < pred_.count; ++a) {  // <= kMaxCandidates: a mover's stale landmark
      const int j = slam_.index_of(pred_.id[a]);
      taken[a] = j < 0 || near_mover(slam_.landmark(j));
    }
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations: the nearest tentative landmark
      if (out.feature[i] != kNewFeature) continue;
      for (int a = confirmed_; a < pred_.count; ++a) {  // <= kMaxCandidates
        out.d2[i] = std::min(out.d2[i], individual_d2(obs, pred_, i, a));
      }
    }
    for (int round = 0; round < obs.count; ++round) {  // <= kMaxObservations: one pair each
      int bi = -1, ba = -1;
      T best = cfg_.gate.individual;
      for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
        if (out.feature[i] != kNewFeature) continue;
        for (int a = confirmed_; a < pred_.count; ++a) {  // <= kMaxCandidates
          if (taken[a]) continue;
          const T d2 = individual_d2(obs, pred_, i, a);
          if (d2 <= best) {
            best = d2;
            bi = i;
            ba = a;
          }
        }
      }
      if (bi < 0) break;
      taken[ba] = true;
      out.feature[bi] = pred_.id[ba];
      out.candidate[bi] = static_cast<std::int16_t>(ba);
      out.d2[bi] = best;
      ++out.pairings;
    }
    // A tentative landmark paired on the last scan whose nearest sighting now falls outside the
    // pairing gate but inside the augmentation gate has jumped: a mover (the sighting is it).
    const Pose2<T> x = slam_.pose();
    for (int a = confirmed_; a < pred_.count; ++a) {  // <= kMaxCandidates
      const int j = slam_.index_of(pred_.id[a]);
      if (taken[a] || j < 0 || slam_.unseen(j) != 0) continue;
      int bi = -1;
      T best = std::numeric_limits<T>::infinity();
      for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
        if (out.feature[i] != kNewFeature) continue;
        const T d2 = individual_d2(obs, pred_, i, a);
        if (d2 < best) {
          best = d2;
          bi = i;
        }
      }
      if (bi < 0 || !(best > cfg_.gate.individual) || !(best <= gate_)) continue;
      out.feature[bi] = kUnmatched;
      remember_mover(inverse_observe(x, slam_.mount(), obs.z[bi]));
    }
  }
  /// A point within kMoverReach_m of a remembered mover.
  bool near_mover(const Vec2<T>& p) const {
    for (int k = 0; k < mover_count_; ++k) {  // <= kMaxMovers
      if ((p - movers_[static_cast<std::size_t>(k)].at).norm() < kMoverReach_m) return true;
    }
    return false;
  }
  /// A mover caught at p; when kMaxMovers are remembered, the longest unseen makes room.
  [[gnu::noinline, gnu::cold]] void remember_mover(const Vec2<T>& p) {
    int slot = mover_count_;
    if (slot == kMaxMovers) {
      slot = 0;
      for (int k = 1; k < kMaxMovers; ++k) {  // <= kMaxMovers
        if (movers_[static_cast<std::size_t>(k)].unseen > movers_[static_cast<std::size_t>(slot)].unseen) slot = k;
      }
    } else {
      ++mover_count_;
    }
    movers_[static_cast<std::size_t>(slot)] = Mover{p, 0};
    ++movers_caught_;
  }
  /// associate_prepared() with tentative_isolated, after pair_tentative: an observation still new
  /// within kMoverReach_m of a remembered mover (where the pose puts it) is that mover: unmatched,
  /// and the mover moves there.  O(kMaxObservations kMaxMovers)
  [[gnu::noinline, gnu::cold]] void follow_movers(const Observations<T, B>& obs, Association<T, B>& out) {
    const Pose2<T> x = slam_.pose();
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      if (out.feature[i] != kNewFeature) continue;
      const Vec2<T> p = inverse_observe(x, slam_.mount(), obs.z[i]);
      for (int k = 0; k < mover_count_; ++k) {  // <= kMaxMovers
        Mover& mv = movers_[static_cast<std::size_t>(k)];
        if ((p - mv.at).norm() < kMoverReach_m) {
          out.feature[i] = kUnmatched;
          mv.at = p;
          mv.unseen = 0;
          break;
        }
      }
    }
  }
  /// commit() with tentative_isolated, before the review: a paired landmark that fails the static
  /// gate (the review removes it) is remembered as a mover; every mover a scan older, the ones
  /// unseen for kMoverMemoryScans forgotten.  O(kMaxObservations kMaxMovers)
  [[gnu::noinline, gnu::cold]] void catch_movers(const Association<T, B>& assoc) {
    int kept = 0;
    for (int k = 0; k < mover_count_; ++k) {  // <= kMaxMovers
      Mover mv = movers_[static_cast<std::size_t>(k)];
      if (++mv.unseen >= kMoverMemoryScans) continue;
      movers_[static_cast<std::size_t>(kept++)] = mv;
    }
    mover_count_ = kept;
    const T gate = T(policy_.static_gate_d2);
    for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
      const int j = assoc.feature[i] >= 0 ? slam_.index_of(assoc.feature[i]) : -1;
      if (j >= 0 && slam_.has_moved(j, gate)) remember_mover(slam_.landmark(j));
    }
  }
  /// commit() with tentative_isolated: the pairs with a tentative landmark are set aside from the
  /// filter's update (round kAlone) and the others go in round 0 (unless a closure ordered them).
  /// @return whether any pair was set aside
  [[gnu::noinline, gnu::cold]] bool set_aside_tentative(const Observations<T, B>& obs, const Association<T, B>& assoc,
                                                        bool closing) {
    bool any = false;
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      const int j = assoc.feature[i] >= 0 ? slam_.index_of(assoc.feature[i]) : -1;
      const bool alone = j >= 0 && !slam_.confirmed(j, policy_);
      if (alone) {
        round_[static_cast<std::size_t>(i)] = kAlone;
      } else if (!closing) {
        round_[static_cast<std::size_t>(i)] = 0;
      }
      any = any || alone;
    }
    return any;
  }
  /// commit()'s pairs set aside (kAlone): each moves only its tentative landmark
  /// (ekf::Slam::update_alone), after the filter's update; one the filter refuses is skipped.
  [[gnu::noinline, gnu::cold]] void update_tentative(const Observations<T, B>& obs, const Association<T, B>& assoc) {
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      if (round_[static_cast<std::size_t>(i)] != kAlone) continue;
      const int j = slam_.index_of(assoc.feature[i]);
      T d2 = T(0);
      if (j >= 0) (void)slam_.update_alone(j, obs.z[i], obs.R[i], ekf_ws_, d2);
    }
  }

  /// Before commit()'s review (loop_merge_d2 > 0): a scan that pairs old landmarks (unpaired for
  /// loop_age reviews, confirmed) is a closure; they become the closure set, each with the reviews
  /// it was unseen plus one (closure_limit_, a landmark added later has at most that age after
  /// this review), and merge_duplicates() runs after this review and the next
  /// kLoopSettleScans - 1. A scan that pairs none keeps the set of the last closure.
  void note_closure(const Association<T, B>& assoc) {
    int n = 0;
    for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
      const int j = assoc.feature[i] >= 0 ? slam_.index_of(assoc.feature[i]) : -1;
      if (j < 0 || slam_.unseen(j) < cfg_.loop_age || slam_.hits(j) < policy_.confirm_hits) continue;
      closure_id_[static_cast<std::size_t>(n)] = assoc.feature[i];
      closure_limit_[static_cast<std::size_t>(n)] = static_cast<std::int16_t>(slam_.unseen(j) + 1);
      ++n;
    }
    if (n == 0) return;
    closure_count_ = n;
    merge_left_ = reloc::kLoopSettleScans;
  }

  /// After a loop closure (loop_merge_d2 > 0, commit()): a duplicate is a landmark of this scan's
  /// local region added while an old landmark of the closure set was unseen (its age at most that
  /// landmark's closure_limit_: drift made a copy because the original was not recognised) and
  /// within loop_merge_d2 of it in ekf::Slam::duplicate_d2, the two not both paired by this scan
  /// (two observations of one scan are two landmarks). The closest such pair is merged
  /// (ekf::Slam::merge; the old landmark keeps its id), up to kMaxMergesPerScan times. Two landmarks
  /// both seen since the original's last sighting are never merged, however close.
  /// O(kMaxMergesPerScan (kMaxObservations kMaxCandidates + n^2))
  /// Out of line: its flags stay out of commit()'s frame (512 B at the large bounds).
  /// @return landmarks merged
  [[gnu::noinline]] int merge_duplicates(const Association<T, B>& assoc) {
    bool paired[B::kMaxCandidates];
    for (int a = 0; a < pred_.count; ++a) {  // <= kMaxCandidates
      paired[a] = false;
      for (int i = 0; i < assoc.count && !paired[a]; ++i) {  // <= kMaxObservations
        paired[a] = assoc.feature[i] == pred_.id[a];
      }
    }
    int merged = 0;
    for (int m = 0; m < kMaxMergesPerScan; ++m) {  // <= kMaxMergesPerScan
      int keep = -1, drop = -1;
      T best = cfg_.loop_merge_d2;
      for (int k = 0; k < closure_count_; ++k) {  // <= kMaxObservations: the closure's old landmarks
        const FeatureId id = closure_id_[static_cast<std::size_t>(k)];
        const int ja = slam_.index_of(id);
        if (ja < 0) continue;  // removed since
        bool a_paired = false;
        for (int i = 0; i < assoc.count && !a_paired; ++i) a_paired = assoc.feature[i] == id;  // <= kMaxObservations
        for (int b = 0; b < pred_.count; ++b) {                                                // <= kMaxCandidates
          const int jb = slam_.index_of(pred_.id[b]);
          if (jb < 0 || jb == ja || (a_paired && paired[b])) continue;
          if (slam_.age(jb) > closure_limit_[static_cast<std::size_t>(k)]) continue;  // older than the absence
          const T d2 = slam_.duplicate_d2(ja, jb);
          if (!(d2 < best)) continue;
          best = d2;
          keep = ja;
          drop = jb;
        }
      }
      if (keep < 0 || slam_.merge(keep, drop, ekf_ws_) != Status::kOk) break;
      ++merged;
    }
    return merged;
  }

  Mat2<T> landmark_covariance(int j) const {
    const int r = ekf::Layout::landmark(j);
    Mat2<T> P;
    P << slam_.cov(r, r), slam_.cov(r, r + 1), slam_.cov(r, r + 1), slam_.cov(r + 1, r + 1);
    return P;
  }

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
  bool configured_ = false;
  // The relocaliser (StepSettings::relocalise).
  reloc::AlignOptions<T> align_;
  reloc::AlignWorkspace<T, B> align_ws_;
  reloc::AlignResult<T, B> align_out_;
  int confirm_left_ = 0;
  int merge_left_ = 0;     ///< scans after a loop closure whose review is followed by merge_duplicates()
  int closure_count_ = 0;  ///< the last closure's old landmarks (note_closure)
  std::array<FeatureId, B::kMaxObservations> closure_id_{};
  std::array<std::int16_t, B::kMaxObservations> closure_limit_{};  ///< the age a duplicate may have, at most
  int failed_scans_ = 0;  ///< scans in a row that paired nothing while tracking (reloc_lost_failed_scans)
  bool skip_confirm_ = false;
  Localisation state_ = Localisation::kTracking;
  Mat3<T> lost_cov_ = Mat3<T>::Identity();
  // The closure check (StepSettings::loop_check): its options, memory, the aligned landmarks' filter
  // indices in push order (the relocaliser's too), and a committed closure for commit().
  reloc::AlignOptions<T> loop_align_;  ///< the relocaliser's, with loop_min_inliers
  reloc::LoopState<T> loop_state_;
  std::array<std::int16_t, B::kMaxLandmarks> align_slam_{};
  bool closing_ = false;
  Pose2<T> close_at_{};
  Mat3<T> close_Q_ = Mat3<T>::Zero();
  /// Each pair's round in commit(): a closure's (order_closure), or kAlone (set_aside_tentative).
  std::array<std::uint8_t, B::kMaxObservations> round_{};
  int confirmed_ = 0;  ///< prepare(): the leading candidates of pred_ that are confirmed (tentative_isolated)
  struct Mover {
    Vec2<T> at;      ///< where it was last seen (world) [m]
    int unseen = 0;  ///< reviews since
  };
  std::array<Mover, kMaxMovers> movers_{};
  int mover_count_ = 0;
  std::uint32_t movers_caught_ = 0;  ///< since reset()
  // The hypothesis window (StepSettings::hypothesis_rivals): its members, the filter's pose and pose
  // covariance when they were last moved, the scans it has lasted; the seeds of an opening scan
  // (the members' pairs of the last scan in the first rows), and whether commit() holds the scan.
  std::array<reloc::PoseHypothesis<T>, reloc::kMaxHypotheses> window_;
  int window_count_ = 0;
  int window_age_ = 0;
  int window_assoc_ = 0;  ///< the member that follows the association's pairs
  Pose2<T> window_pose_{};
  Mat3<T> window_cov_;
  std::array<reloc::PoseHypothesis<T>, reloc::kMaxSeeds> seed_;
  std::array<std::array<std::int16_t, B::kMaxObservations>, reloc::kMaxSeeds> seed_pick_{};
  std::array<std::int8_t, B::kMaxObservations> cluster_label_{};  ///< label_clusters()' clusters
  std::array<std::array<std::int16_t, B::kMaxObservations>, reloc::kMaxHypotheses> window_pick_{};
  std::array<std::array<T, B::kMaxObservations>, reloc::kMaxHypotheses> window_d2_{};
  bool holding_ = false;
  reloc::LoopStats<T> loop_stats_;      ///< step()'s, until it writes them out
  reloc::WindowStats<T> window_stats_;  ///< step()'s, until it writes them out
};

}  // namespace geojcbb::node
