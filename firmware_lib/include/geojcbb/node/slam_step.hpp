// node: one EKF-SLAM step with data association, the unit of work of the device loop and of the
// host's evaluation (host_tools/eval), so both run the same code. step() is the one orchestrator:
//   predict(odometry)  ...  step(scan):
//     relocaliser (lost: align, nothing else) -> predict_local(r + d) -> associate (strategy, or the
//     caller's override) -> [tentative] -> loop check -> [clusters first] -> hypothesis window ->
//     update (a stage's Closure: inflated pose, rounds) -> augment (stages/augment.hpp) -> review -> [duplicate merge]
//     -> the lost test (scan_evidence) and the relocaliser's confirmation
// Each stage that keeps state across scans is a member of its own type (node/stages/), reads the
// map through a MapView, edits the association only through pair/unpair, and returns what it
// decided; the step applies it to the filter.
// Augmentation rule: an observation left kNewFeature becomes a landmark only if its nearest d2
// also exceeds a second gate (chi-square level `new_landmark_level`, 2 dof); between the gates it
// is dropped. review() then keeps clutter out of the map (each landmark's log-odds of existence,
// ekf/landmark_book.hpp).
// No heap: the object holds the filter and every workspace, sized by the Bounds; typically static
// on the device. Every call validates first and changes no state unless it returns kOk.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "geojcbb/associate.hpp"
#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/core/strategy.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/stages/augment.hpp"
#include "geojcbb/node/stages/clusters_first.hpp"
#include "geojcbb/node/stages/duplicate_merge.hpp"
#include "geojcbb/node/stages/hypothesis_window.hpp"
#include "geojcbb/node/stages/loop_check.hpp"
#include "geojcbb/node/stages/map_seed.hpp"
#include "geojcbb/node/stages/map_view.hpp"
#include "geojcbb/node/stages/movers.hpp"
#include "geojcbb/node/stages/relocaliser.hpp"
#include "geojcbb/node/stages/seeding.hpp"
#include "geojcbb/node/stages/tentative.hpp"
#include "geojcbb/node/step_result.hpp"

namespace geojcbb::node {

/// The step's settings: every option of core/options.h (core/settings.hpp).
using geojcbb::StepSettings;

template <typename T, class B>
class SlamStep {
 public:
  /// A committed closure's pairs are applied in this many rounds, most certain first; each round
  /// after the first is linearised at the estimate the rounds before it left (an iterated update
  /// with a bounded number of iterations).
  static constexpr int kClosureRounds = 3;
  static constexpr int kMaxMergesPerScan = DuplicateMerge<T, B>::kMaxMergesPerScan;
  static constexpr int kMaxMovers = Tentative<T, B>::kMaxMovers;
  /// The next local map's origin variance on each of x, y, theta (restart): (1 mm)^2 and (1 mrad)^2,
  /// the origin known (it is the map's frame) up to what keeps the covariance definite in float.
  static constexpr T kOriginVariance = T(1e-6);

  /// Builds the strategy's configuration and the augmentation gate.
  /// @return kOk; kInvalidInput for bad parameters (a bad view or policy too); statuses of
  ///         make_strategy / chi2_inv. No state change unless kOk.
  [[nodiscard, gnu::cold]] Status configure(const StepSettings<T>& s) {
    // Every option's range, besides the preset (make_strategy refuses the same settings below).
    if (!in_range(s)) return Status::kInvalidInput;
    // A configuration without the window and clusters first (OptionalStages) refuses their options.
    if (!OptionalStages<B>::kHypotheses && (s.hypothesis_rivals > 0 || s.cluster_first)) return Status::kInvalidInput;
    if (!OptionalStages<B>::kHandOver && (s.submap_landmarks > 0 || s.submap_distance_m > 0 || s.submap_scans > 0))
      return Status::kInvalidInput;
    if (!OptionalStages<B>::kDuplicateMerge && s.duplicate_merge_d2 > 0) return Status::kInvalidInput;
    if (!OptionalStages<B>::kWorldModel &&
        (s.motion_false_alarm > 0 || s.learn_detection || s.learn_clutter || s.detection_floor > 0.0f))
      return Status::kInvalidInput;
    double gate = 0;
    Status st = chi2_inv(s.new_landmark_level, 2, gate);
    if (st != Status::kOk) return st;
    double static_gate = 0;  // 0: the static-gate rule off
    if (s.static_gate_level > 0) {
      st = chi2_inv(s.static_gate_level, 2, static_gate);
      if (st != Status::kOk) return st;
    }
    // The stages' option structs from the table (bind_options: generated, type-checked).
    ekf::LandmarkPolicy policy;
    ekf::bind_options(s, policy);
    policy.static_gate_d2 = static_cast<float>(static_gate);
    policy.p_detect = static_cast<float>(s.loop_detection_probability);
    policy.clutter_density = static_cast<float>(s.loop_unexplained_density);
    if (!policy.valid()) return Status::kInvalidInput;
    reloc::AlignOptions<T> align;
    reloc::bind_options(s, align);
    if (!align.valid()) return Status::kInvalidInput;
    reloc::AlignOptions<T> loop_align;
    reloc::bind_loop_options(s, loop_align);
    if (!loop_align.valid()) return Status::kInvalidInput;
    // Last: make_strategy checks before it writes, so a refusal here changes nothing either.
    st = make_strategy(s.strategy, s, cfg_);
    if (st != Status::kOk) return st;
    const Mount<T> mount{s.sensor_x_m, s.sensor_y_m, s.sensor_theta_rad};
    (void)slam_.set_mount(mount);  // finite: in_range
    scratch_.ws.mount = mount;
    loop_align_ = loop_align;
    loop_.reset();
    window_.reset();
    align_ = align;
    gate_ = static_cast<T>(gate);
    ekf::bind_options(s, view_);
    policy_ = policy;
    policy_.gate_d2 = static_cast<float>(cfg_.gate.individual);  // the area of a landmark's p_FA (> 0)
    ekf::bind_options(s, filter_);
    motion_t_ = ekf::motion_threshold<T>(s.motion_false_alarm);
    configured_ = true;
    return Status::kOk;
  }

  bool configured() const { return configured_; }
  const ekf::Slam<T, B>& slam() const { return slam_; }
  /// The last scan's prediction (the local region's candidates, h and H P H^T), for the host's
  /// innovation statistics.
  const Prediction<T, B>& prediction() const { return pred_; }

  /// @return the statuses of ekf::Slam::reset.
  [[nodiscard]] Status reset(const Pose2<T>& x0, const Mat3<T>& P0) {
    const Status st = slam_.reset(x0, P0, filter_);
    if (st == Status::kOk) begin_map();
    return st;
  }
  /// The next local map, once the closed one has been handed over (StepResult::submap_due):
  /// ekf::Slam::restart, the robot's pose its origin with kOriginVariance, the ids going on. With
  /// submap_carry it keeps the confirmed landmarks of the last scan's local region (r + d, at most
  /// kMaxCandidates), so consecutive maps share them; without, it begins empty. The stages start
  /// again as after reset(). @return kOk (the origin's covariance and the kept indices are valid).
  [[nodiscard, gnu::cold]] Status restart() {
    std::int16_t keep[B::kMaxLandmarks];  // the only array on the stack: the frame stays within 512 B
    int kept = 0;
    for (int j = 0; j < slam_.landmarks(); ++j) {  // <= kMaxLandmarks
      if (carried(j)) keep[kept++] = static_cast<std::int16_t>(j);
    }
    const Status st = slam_.restart(Mat3<T>::Identity() * kOriginVariance, keep, kept);
    if (st == Status::kOk) begin_map();
    return st;
  }
  /// Whether restart() now would keep landmark j (index): with submap_carry, a confirmed landmark of
  /// the last scan's region. SUBMAP names them, so the host knows which the next map began with.
  /// O(kMaxCandidates).
  bool carried(int j) const {
    if (!cfg_.submap_carry || !slam_.confirmed(j)) return false;
    for (int a = 0; a < pred_.count; ++a) {  // <= kMaxCandidates: in the last scan's region
      if (pred_.id[a] == slam_.id(j)) return true;
    }
    return false;
  }
  /// Landmarks of the global map seeded into the local map (stages/map_seed.hpp: each added, with its
  /// existence capped at the policy's saturation, unless one the map holds is compatible with it or
  /// there is no room: the closing size or the capacity less one scan). @return the statuses of
  /// seed_map; kInvalidInput when not configured.
  [[nodiscard]] Status seed(const MapSeed<T>* seeds, int count, SeedAnswer<T>* out) {
    if (!configured_) return Status::kInvalidInput;
    int limit = B::kMaxLandmarks - B::kMaxObservations;
    if (cfg_.submap_landmarks > 0 && static_cast<int>(cfg_.submap_landmarks) < limit) {
      limit = static_cast<int>(cfg_.submap_landmarks);
    }
    return seed_map(slam_, static_cast<T>(cfg_.gate.individual), policy_.template max_nats<T>(), limit, seeds, count,
                    out);
  }
  /// Metres travelled and scans taken since the local map began (reset, restart).
  T travelled_m() const { return travelled_m_; }
  int scans_in_map() const { return scans_in_map_; }
  /// ekf::Slam::relocalise: the pose re-initialised (robot carried), the map kept.
  [[nodiscard]] Status relocalise(const Pose2<T>& x, const Mat3<T>& Pxx) { return slam_.relocalise(x, Pxx); }

  /// The user says the robot is lost (carried, or its pose known to be wrong): with the relocaliser
  /// on (StepSettings::relocalise), each scan from the next on is aligned against the map until a
  /// pose is accepted and confirmed. The relocaliser off: nothing changes.
  void lost() { reloc_.lost(configured_ && cfg_.relocalise); }
  Localisation localisation() const { return reloc_.state(); }
  /// Landmarks removed as movers and remembered (tentative_isolated) since reset().
  std::uint32_t movers_caught() const { return tentative_.caught(); }
  /// Movers remembered now (tentative_isolated; at most kMaxMovers).
  int movers() const { return tentative_.movers(); }
  /// The world model's movers (motion_false_alarm): landmarks that failed the motion test since
  /// reset(), and the tracks alive now (stages/movers.hpp).
  const auto& motion_movers() const { return movers_; }

  /// A landmark known beforehand (ekf::Slam::add_known_landmark); `surveyed`: see LoopCheck::surveyed.
  [[nodiscard]] Status add_known_landmark(const Vec2<T>& l, const Mat2<T>& Pll, FeatureId& id, bool surveyed = false) {
    const Status st = slam_.add_known_landmark(l, Pll, id);
    return surveyed ? loop_.surveyed(st, id) : st;
  }

  /// @return the statuses of ekf::Slam::predict.
  [[nodiscard]] Status predict(const ekf::Odometry<T>& u) {
    const Status st = slam_.predict(u);
    if (st == Status::kOk) travelled_m_ += std::abs(u.v_mps * u.dt_s);
    return st;
  }
  /// A pose increment with its covariance (wheel odometry, a vehicle model).
  /// @return the statuses of ekf::Slam::predict.
  [[nodiscard]] Status predict(const ekf::PoseIncrement<T>& u) {
    const Status st = slam_.predict(u);
    if (st == Status::kOk) travelled_m_ += std::sqrt(u.dx_m * u.dx_m + u.dy_m * u.dy_m);
    return st;
  }

  /// One scan. `clock` may be nullptr; `override` (nullptr: none) replaces the association.
  /// @return kOk; kInvalidInput when not configured (or an override's count mismatch); the statuses
  ///         of the relocaliser's alignment, predict_local, associate (or the override), the loop
  ///         check, the window's frozen map and update (then the filter is unchanged). A full map is
  ///         not an error: the observations it turns away are reported as kNotAugmented.
  [[nodiscard]] Status step(const Observations<T, B>& obs, StepResult<T, B>& out, CounterFn clock = nullptr,
                            const AssociationOverride<T, B>* override = nullptr) {
    if (!configured_) return Status::kInvalidInput;
    const std::uint32_t t0 = clock ? clock() : 0;
    slam_.clear_removed();  // what this step removes (POSE reports it)
    if (scans_in_map_ < std::numeric_limits<int>::max()) ++scans_in_map_;
    out.submap_due = false;
    scratch_.ws.score = {clock, 0};  // the posterior scoring's count (set_log_likelihood)
    const MapView<T, B> map{slam_, policy_};
    RelocStats rs;
    Status st = localise(obs, map, rs);
    if (st != Status::kOk) return st;
    const std::uint32_t t_reloc = clock ? clock() : 0;
    if (reloc_.state() == Localisation::kLost) {  // not aligned: the scan is not used
      unused(obs, out);
      out.reloc = rs;
      out.counts.relocalise = t_reloc - t0;  // aligned (the robot is lost)
      out.counts.score = scratch_.ws.score.count;
      out.counts.step = t_reloc - t0;
      return Status::kOk;
    }
    ekf::LocalMapStats local;
    st = slam_.predict_local(cfg_.local_radius_m, ekf_ws_, pred_, local, cfg_.tentative_isolated, view_.half_fov_rad);
    if (st != Status::kOk) return st;
    const int confirmed = local.confirmed;
    const std::uint32_t t1 = clock ? clock() : 0;
    st = override ? override->fn(override->ctx, obs, pred_, map, assoc_) : associate_configured(obs, map, confirmed);
    if (st != Status::kOk) return st;
    if (assoc_.count != obs.count) return Status::kInvalidInput;
    if (override) recount(assoc_);
    const std::uint32_t t2 = clock ? clock() : 0;
    // The stages' stats and decisions in members, not in this frame (the call chain's stack budget).
    loop_stats_ = reloc::LoopStats<T>{};
    close_.commit = false;
    const bool tracking = reloc_.state() == Localisation::kTracking;
    if (!override && cfg_.loop_check && tracking) {
      st = loop_.run(cfg_, loop_align_, obs, pred_, map, scratch_, assoc_, loop_stats_, close_);
      if (st != Status::kOk) return st;
    }
    const std::uint32_t t_loop = clock ? clock() : 0;
    window_stats_ = reloc::WindowStats<T>{};
    bool hold = false;
    if (!override) {
      st = hypotheses(obs, map, tracking, hold);
      if (st != Status::kOk) return st;
    }
    const std::uint32_t t_window = clock ? clock() : 0;
    st = commit(obs, map, hold, out, clock);
    if (st != Status::kOk) return st;
    out.loop = loop_stats_;
    out.window = window_stats_;
    out.counts.loop = loop_stats_.verdict == reloc::LoopVerdict::kNone ? 0 : t_loop - t2;
    const bool windowed = window_stats_.verdict != reloc::WindowVerdict::kNone || cfg_.cluster_first;
    out.counts.window = windowed ? t_window - t_loop : 0;
    out.local = local;
    out.counts.relocalise = rs.aligned ? t_reloc - t0 : 0;
    out.counts.predict_local = t1 - t_reloc;
    out.counts.associate = t2 - t1;
    int paired = 0;
    for (int i = 0; i < out.count; ++i) paired += out.outcome[i] == Outcome::kPaired;  // <= kMaxObservations
    // The lost test's evidence at the tracked pose (the association's prediction), while tracking.
    const std::uint32_t t_test = clock ? clock() : 0;
    const bool testing = cfg_.relocalise && cfg_.reloc_lost_nats > T(0) && tracking && !override;
    const T evidence =
        testing ? scan_evidence(obs, pred_, assoc_, map, reloc_.evidence_before(), view_, loop_align_.model) : T(0);
    const std::uint32_t t_tested = clock ? clock() : 0;
    out.counts.lost_test = testing ? t_tested - t_test : 0;
    if (reloc_.confirm(cfg_, paired, evidence, assoc_.jointly_compatible, rs)) unrelocate(rs);
    out.submap_due = submap_due();
    out.reloc = rs;
    out.counts.score = scratch_.ws.score.count;
    out.counts.step = (clock ? clock() : 0) - t0;
    return Status::kOk;
  }

  /// The configured association's augmentation gate (d2 above it makes a new landmark).
  T augmentation_gate() const { return gate_; }

 private:
  /// A map begins (reset, restart): the stages and the closing rule's counts start again.
  void begin_map() {
    reloc_.reset();
    merge_.reset();
    movers_.reset();
    tentative_.reset();
    window_.reset();
    loop_.new_map();
    travelled_m_ = T(0);
    scans_in_map_ = 0;
    added_in_map_ = 0;
  }
  /// The closing rule of the local map (submap_landmarks, submap_distance_m, submap_scans; 0 each
  /// off), after a tracked scan with no closure pending: a map is handed over at a settled pose.
  bool submap_due() const {
    if (reloc_.state() != Localisation::kTracking || loop_.pending() || window_.open()) return false;
    // The fill level counts every landmark (the device's capacity), but only once the map has added
    // one of its own: a map that began fuller (carried over, seeded) is not closed at once.
    const auto landmarks = static_cast<std::uint32_t>(slam_.landmarks());
    const auto scans = static_cast<std::uint32_t>(scans_in_map_);
    return (cfg_.submap_landmarks > 0 && landmarks >= cfg_.submap_landmarks && added_in_map_ > 0) ||
           (cfg_.submap_distance_m > T(0) && travelled_m_ >= cfg_.submap_distance_m) ||
           (cfg_.submap_scans > 0 && scans >= cfg_.submap_scans);
  }

  /// The relocaliser's part: lost -> the scan aligned; an accepted pose applied to the filter with
  /// the pose's correlation to the landmarks it was fitted to, or, when the filter refuses that, as
  /// the fit's own covariance. The sensitivities go through the update's scratch (ekf_ws_: Hp, lm),
  /// unused until predict_local.
  [[gnu::noinline]] Status localise(const Observations<T, B>& obs, const MapView<T, B>& map, RelocStats& rs) {
    const Status st = reloc_.localise(cfg_, align_, obs, map, scratch_, rs);
    if (st != Status::kOk || !rs.aligned || !scratch_.result.accepted) return st;
    return relocate(obs, rs);
  }
  /// An accepted alignment applied (out of line: its matrices stay off the alignment's call chain).
  [[gnu::noinline]] Status relocate(const Observations<T, B>& obs, RelocStats& rs) {
    Relocation<T> r;
    reloc_.fit(cfg_, obs, scratch_, ekf_ws_.Hp.data(), ekf_ws_.lm.data(), r);
    const Pose2<T> lost = slam_.pose();
    const Mat3<T> lost_cov = slam_.pose_covariance();
    Status st = r.pairs >= 2 ? slam_.relocalise_fitted(r.x, r.Pobs, r.pairs, ekf_ws_.lm.data(), ekf_ws_.Hp.data())
                             : Status::kNotPositiveDefinite;
    if (st != Status::kOk) st = slam_.relocalise(r.x, r.cov);
    if (st != Status::kOk) return st;
    reloc_.relocalised(cfg_, lost, lost_cov, rs);
    return Status::kOk;
  }

  /// A failed confirmation: the pose put back (Relocaliser::lost_pose, lost_covariance; both were
  /// validated when set, so the filter takes them). Out of line: its pose stays out of step()'s frame.
  [[gnu::noinline, gnu::cold]] void unrelocate(RelocStats& rs) {
    if (slam_.relocalise(reloc_.lost_pose(slam_.pose()), reloc_.lost_covariance()) == Status::kOk) reloc_.rejected(rs);
  }

  /// The configured association on the prediction. With tentative_isolated, it sees only the
  /// `confirmed` leading candidates, and the tentative ones are paired afterwards (Tentative::pair).
  [[gnu::noinline]] Status associate_configured(const Observations<T, B>& obs, const MapView<T, B>& map,
                                                int confirmed) {
    if (!cfg_.tentative_isolated) return associate(obs, pred_, cfg_, ws_, assoc_);
    const int all = pred_.count;
    pred_.count = confirmed;  // the leading candidates: C's leading blocks are their own C
    Status st = pred_.C.resize(confirmed);
    if (st == Status::kOk) st = associate(obs, pred_, cfg_, ws_, assoc_);
    pred_.count = all;
    (void)pred_.C.resize(all);  // all <= kMaxCandidates: it held all before
    if (st != Status::kOk) return st;
    tentative_.pair(cfg_, obs, pred_, confirmed, gate_, map, assoc_);
    tentative_.follow(obs, map, assoc_);
    return Status::kOk;
  }

  /// Clusters first and the hypothesis window, on a tracked scan with no closure pending or
  /// committed, over the frozen map. Out of line and cold: its seeds stay out of step()'s frame.
  [[gnu::noinline, gnu::cold]] Status hypotheses(const Observations<T, B>& obs, const MapView<T, B>& map, bool tracking,
                                                 bool& hold) {
    if ((cfg_.hypothesis_rivals == 0 && !cfg_.cluster_first) || !tracking || close_.commit || loop_.pending()) {
      window_.reset();
      return Status::kOk;
    }
    if constexpr (!OptionalStages<B>::kHypotheses) {  // not compiled in: configure() refused the options
      (void)obs;
      (void)hold;
      return Status::kOk;
    } else {
      const Status st = load_frozen(pred_, map, scratch_);
      if (st != Status::kOk) {
        window_.reset();
        return st;
      }
      const SeedModel<T> sm{slam_.pose(), slam_.pose_covariance(),
                            reloc::SetModel<T>{cfg_.loop_detection_probability, cfg_.loop_unexplained_density},
                            &loop_align_, cfg_.gate.individual};
      if (cfg_.cluster_first && !window_.open()) {
        window_stats_.regrouped += clusters_.run(cfg_, obs, pred_, map, scratch_, seeds_, sm, assoc_);
      }
      if (cfg_.hypothesis_rivals > 0) {
        window_.run(cfg_, obs, pred_, map, scratch_, seeds_, sm, assoc_, window_stats_, close_, hold);
      }
      return Status::kOk;
    }
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

  /// Update (a committed closure: the pose block inflated, the pairs in rounds at its pose; the
  /// pairs with tentative landmarks set aside), augment, review (`hold`: the scan is no evidence),
  /// and the duplicate merge. @return kOk; the statuses of update (then nothing changed).
  /// The three halves of step() are out of line: inlined, they took step()'s frame past 512 B.
  [[gnu::noinline]] Status commit(const Observations<T, B>& obs, const MapView<T, B>& map, bool hold,
                                  StepResult<T, B>& out, CounterFn clock) {
    const std::uint32_t t2 = clock ? clock() : 0;
    const int caught = motion_t_ > T(0) ? movers(obs, map) : 0;
    const bool closing = close_.commit;
    const Mat3<T> before = slam_.pose_covariance();
    Status st = closing ? slam_.inflate_pose(close_.Q) : Status::kOk;
    if (st != Status::kOk) return st;
    if (closing) closure_rounds(map, assoc_, kClosureRounds, round_);
    const bool aside = cfg_.tentative_isolated && tentative_.set_aside(map, assoc_, closing, round_);
    const bool rounds = closing || aside;
    st = slam_.update(obs, assoc_, ekf_ws_, closing ? &close_.at : nullptr, rounds ? round_.data() : nullptr, 0);
    if (st != Status::kOk) {
      // Undone: the pose block as it was (it was positive definite, the write cannot fail).
      if (closing) (void)slam_.replace_pose_covariance(before);
      return st;
    }
    // The closure's later rounds, at the estimate the first left; a round the filter refuses is
    // skipped (its pairs stay unused), as update() skips a block after its first.
    for (int r = 1; r < kClosureRounds && closing; ++r) {  // <= kClosureRounds
      (void)slam_.update(obs, assoc_, ekf_ws_, nullptr, round_.data(), r);
    }
    // The pairs set aside: each moves only its tentative landmark (ekf::Slam::update_alone); one the
    // filter refuses is skipped.
    for (int i = 0; i < obs.count && aside; ++i) {  // <= kMaxObservations
      if (round_[static_cast<std::size_t>(i)] != Tentative<T, B>::kAlone) continue;
      const int j = slam_.index_of(assoc_.feature[i]);
      T d2 = T(0);
      if (j >= 0) (void)slam_.update_alone(j, obs.z[i], obs.R[i], ekf_ws_, d2);
    }
    window_.rebase(slam_.pose(), slam_.pose_covariance());
    const std::uint32_t t3 = clock ? clock() : 0;
    // From here on nothing can fail: the outputs are written (stages/augment.hpp).
    const int evicted = augment_unpaired(obs, assoc_, cfg_, gate_, slam_, out, added_in_map_);
    // The scan's observed landmarks (paired, or added from it) are distinct for good.
    constexpr bool kMerge = OptionalStages<B>::kDuplicateMerge;  // compiled out: configure() refused it
    if (kMerge && cfg_.duplicate_merge_d2 > T(0))
      merge_.note(slam_, out, cfg_.duplicate_merge_d2, cfg_.gate.individual);
    if (cfg_.tentative_isolated) tentative_.catch_movers(map, assoc_);
    ekf::ReviewStats rs;
    // The view and policy were validated by configure(), the counts above. A scan the hypothesis
    // window holds is no evidence: its landmarks were not paired because the pose is in doubt.
    std::uint32_t existence = 0;
    if (!hold && slam_.review(obs, pred_, assoc_, view_, policy_, rs, clock, &existence) != Status::kOk) {
      rs = ekf::ReviewStats{};
    }
    if (cfg_.tentative_isolated) {                     // the movers' landmarks Tentative::pair found jumped
      for (int k = 0; k < tentative_.jumped(); ++k) {  // <= kMaxMovers
        rs.removed_moved += slam_.forget(tentative_.jumped(k)) == Status::kOk;
      }
    }
    if (kMerge && cfg_.duplicate_merge_d2 > T(0) && !hold)
      rs.merged = merge_.merge(cfg_.duplicate_merge_d2, pred_, out, slam_, ekf_ws_);
    const std::uint32_t t4 = clock ? clock() : 0;
    out.diag = assoc_.diag;
    out.review = rs;
    out.review.evicted = evicted;
    out.review.movers = caught;
    out.counts = StageCounts{};
    out.counts.update = t3 - t2;
    out.counts.augment_review = t4 - t3;
    out.counts.existence = existence;
    return Status::kOk;
  }

  /// The world model's motion (stages/movers.hpp), before the update: the movers' tracks take the
  /// observations in their gates; each remaining pair's landmark takes the motion test, and one that
  /// fails leaves the map (marginalised) while its observation begins a track. The update and the
  /// review then see neither. @return the landmarks that became movers.
  [[gnu::noinline]] int movers(const Observations<T, B>& obs, const MapView<T, B>& map) {
    if constexpr (!OptionalStages<B>::kWorldModel) {  // compiled out: configure() refused the option
      (void)obs;
      (void)map;
      return 0;
    } else {
      movers_.take(obs, map, cfg_.gate.individual, assoc_);
      std::array<std::int16_t, B::kMaxObservations> moved;
      int n = slam_.test_motion(obs, pred_, assoc_, motion_t_, moved);
      // The static gate's movers too (static_gate_level): before the update, so they become tracks.
      for (int i = 0; i < obs.count && policy_.static_gate_d2 > 0.0f; ++i) {  // <= kMaxObservations
        const int j = slam_.index_of(assoc_.feature[i]);
        bool listed = false;
        for (int k = 0; k < n; ++k) listed = listed || moved[static_cast<std::size_t>(k)] == i;  // <= kMaxObservations
        if (j >= 0 && !listed && map.moved(j)) moved[static_cast<std::size_t>(n++)] = static_cast<std::int16_t>(i);
      }
      int caught = 0;
      for (int k = 0; k < n; ++k) {  // <= kMaxObservations
        const int i = moved[static_cast<std::size_t>(k)];
        const FeatureId id = assoc_.feature[i];
        movers_.start(obs, map, i, assoc_);
        caught += slam_.forget(id) == Status::kOk;
      }
      return caught;
    }
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
  reloc::AlignOptions<T> align_;       ///< the relocaliser's alignment
  reloc::AlignOptions<T> loop_align_;  ///< the relocaliser's, with loop_min_inliers (loop check, window, clusters)
  // The stages: each owns its state across scans.
  Relocaliser<T, B> reloc_;
  LoopCheck<T, B> loop_;
  HypothesisWindow<T, B> window_;
  ClustersFirst<T, B> clusters_;
  Tentative<T, B> tentative_;
  DuplicateMerge<T, B> merge_;
  /// The movers' tracks, or a stand-in without the world model (OptionalStages::kWorldModel).
  std::conditional_t<OptionalStages<B>::kWorldModel, Movers<T, B>, NoMovers> movers_;
  T motion_t_ = T(0);  ///< the motion test's threshold (0: off)
  // Scratch of one scan, shared by the stages in turn (one buffer in RAM).
  AlignScratch<T, B> scratch_;
  Seeds<T, B> seeds_;
  Closure<T> close_;                    ///< a stage's committed closure, for commit()
  reloc::LoopStats<T> loop_stats_;      ///< step()'s, until it writes them out
  reloc::WindowStats<T> window_stats_;  ///< step()'s, until it writes them out
  /// Each pair's round in commit(): a closure's (closure_rounds), or kAlone (Tentative::set_aside).
  std::array<std::uint8_t, B::kMaxObservations> round_{};
  T travelled_m_ = T(0);  ///< since the local map began (reset, restart)
  int scans_in_map_ = 0;  ///< since the local map began
  int added_in_map_ = 0;  ///< landmarks augmented since the local map began
};

}  // namespace geojcbb::node
