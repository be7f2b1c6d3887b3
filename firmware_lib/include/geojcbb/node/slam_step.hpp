// node: one EKF-SLAM step with data association, the unit of work of the device loop and of the
// host's evaluation (host_tools/runs), so both run the same code. step() is the one orchestrator:
//   predict(odometry)  ...  step(scan):
//     relocaliser (lost: align, nothing else) -> predict_local(r + d) -> associate (strategy, or the
//     caller's override) -> [tentative] -> loop check -> [clusters first] -> hypothesis window ->
//     commit(): [movers] -> the update's plan applied (node/update_plan.hpp) -> augment -> review ->
//     [duplicate merge] -> the lost test (scan_evidence), the relocaliser's confirmation, the closing rule
// Each stage that keeps state across scans is a member of its own type (node/stages/), reads the
// map through a MapView, edits the association only through pair/unpair, and returns what it
// decided (into the update's plan, or as a list); the step applies it to the filter.
// No heap: the object holds the filter and every workspace, sized by the Bounds; typically static
// on the device. Every call validates first and changes no state unless it returns kOk.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "geojcbb/associate.hpp"
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
#include "geojcbb/node/stages/submap_close.hpp"
#include "geojcbb/node/stages/tentative.hpp"
#include "geojcbb/node/step_config.hpp"
#include "geojcbb/node/step_result.hpp"
#include "geojcbb/node/update_plan.hpp"

namespace geojcbb::node {

template <typename T, class B>
class SlamStep {
 public:
  /// The next local map's origin variance on each of x, y, theta (restart): (1 mm)^2 and (1 mrad)^2,
  /// the origin known (it is the map's frame) up to what keeps the covariance definite in float.
  static constexpr T kOriginVariance = T(1e-6);

  /// Binds the settings (StepConfig::bind) and begins the stages that depend on them.
  /// @return kOk; the statuses of StepConfig::bind. No state change unless kOk.
  [[nodiscard, gnu::cold]] Status configure(const StepSettings<T>& s) {
    const Status st = c_.bind(s);
    if (st != Status::kOk) return st;
    (void)slam_.set_mount(c_.mount);  // finite: in_range
    scratch_.ws.mount = c_.mount;
    loop_.reset();
    window_.reset();
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
    const Status st = slam_.reset(x0, P0, c_.filter);
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
    const int kept = SubmapClose<T, B>::kept(c_.cfg, MapView<T, B>{slam_, c_.policy}, pred_, keep);
    const Status st = slam_.restart(Mat3<T>::Identity() * kOriginVariance, keep, kept);
    if (st == Status::kOk) begin_map();
    return st;
  }
  /// Whether restart() now would keep landmark j (index): with submap_carry, a confirmed landmark of
  /// the last scan's region. SUBMAP names them, so the host knows which the next map began with.
  /// O(kMaxCandidates).
  bool carried(int j) const { return SubmapClose<T, B>::carried(c_.cfg, MapView<T, B>{slam_, c_.policy}, pred_, j); }
  /// Landmarks of the global map seeded into the local map (stages/map_seed.hpp: each added, with its
  /// existence capped at the policy's saturation, unless one the map holds is compatible with it or
  /// there is no room: the closing size or the capacity less one scan). @return the statuses of
  /// seed_map; kInvalidInput when not configured.
  [[nodiscard]] Status seed(const MapSeed<T>* seeds, int count, SeedAnswer<T>* out) {
    if (!configured_) return Status::kInvalidInput;
    return seed_map(slam_, static_cast<T>(c_.cfg.gate.individual), c_.policy.template max_nats<T>(),
                    SubmapClose<T, B>::room(c_.cfg), seeds, count, out);
  }
  /// Metres travelled and scans taken since the local map began (reset, restart).
  T travelled_m() const { return submap_.travelled_m(); }
  int scans_in_map() const { return submap_.scans(); }
  /// ekf::Slam::relocalise: the pose re-initialised (robot carried), the map kept.
  [[nodiscard]] Status relocalise(const Pose2<T>& x, const Mat3<T>& Pxx) { return slam_.relocalise(x, Pxx); }

  /// The user says the robot is lost (carried, or its pose known to be wrong): with the relocaliser
  /// on (StepSettings::relocalise), each scan from the next on is aligned against the map until a
  /// pose is accepted and confirmed. The relocaliser off: nothing changes.
  void lost() { reloc_.lost(configured_ && c_.cfg.relocalise); }
  Localisation localisation() const { return reloc_.state(); }
  /// Tentative landmarks and their movers (tentative_isolated): caught since reset(), remembered now.
  const Tentative<T, B>& tentative() const { return tentative_; }
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
    if (st == Status::kOk) submap_.travelled(std::abs(u.v_mps * u.dt_s));
    return st;
  }
  /// A pose increment with its covariance (wheel odometry, a vehicle model).
  /// @return the statuses of ekf::Slam::predict.
  [[nodiscard]] Status predict(const ekf::PoseIncrement<T>& u) {
    const Status st = slam_.predict(u);
    if (st == Status::kOk) submap_.travelled(std::sqrt(u.dx_m * u.dx_m + u.dy_m * u.dy_m));
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
    submap_.scan();
    out.submap_due = false;
    scratch_.ws.score = {clock, 0};  // the posterior scoring's count (set_log_likelihood)
    const MapView<T, B> map{slam_, c_.policy};
    RelocStats rs;
    Status st = localise(obs, map, rs);
    if (st != Status::kOk) return st;
    const std::uint32_t t_reloc = clock ? clock() : 0;
    if (reloc_.state() == Localisation::kLost) {  // not aligned: the scan is not used
      out.unused(obs.count);
      out.reloc = rs;
      out.counts.relocalise = t_reloc - t0;  // aligned (the robot is lost)
      out.counts.score = scratch_.ws.score.count;
      out.counts.step = t_reloc - t0;
      return Status::kOk;
    }
    ekf::LocalMapStats local;
    st = slam_.predict_local(c_.cfg.local_radius_m, ekf_ws_, pred_, local, c_.cfg.tentative_isolated,
                             c_.view.half_fov_rad);
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
    plan_.clear();
    const bool tracking = reloc_.state() == Localisation::kTracking;
    if (!override && c_.cfg.loop_check && tracking) {
      st = loop_.run(c_.cfg, c_.loop_align, obs, pred_, map, scratch_, assoc_, loop_stats_, plan_.close);
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
    const bool windowed = window_stats_.verdict != reloc::WindowVerdict::kNone || c_.cfg.cluster_first;
    out.counts.window = windowed ? t_window - t_loop : 0;
    out.local = local;
    out.counts.relocalise = rs.aligned ? t_reloc - t0 : 0;
    out.counts.predict_local = t1 - t_reloc;
    out.counts.associate = t2 - t1;
    int paired = 0;
    for (int i = 0; i < out.count; ++i) paired += out.outcome[i] == Outcome::kPaired;  // <= kMaxObservations
    // The lost test's evidence at the tracked pose (the association's prediction), while tracking.
    const std::uint32_t t_test = clock ? clock() : 0;
    const bool testing = c_.cfg.relocalise && c_.cfg.reloc_lost_nats > T(0) && tracking && !override;
    const T evidence =
        testing ? scan_evidence(obs, pred_, assoc_, map, reloc_.evidence_before(), c_.view, c_.loop_align.model) : T(0);
    const std::uint32_t t_tested = clock ? clock() : 0;
    out.counts.lost_test = testing ? t_tested - t_test : 0;
    if (reloc_.confirm(c_.cfg, paired, evidence, assoc_.jointly_compatible, rs)) unrelocate(rs);
    const bool settled = reloc_.state() == Localisation::kTracking && !loop_.pending() && !window_.open();
    out.submap_due = submap_.due(c_.cfg, settled, slam_.landmarks());
    out.reloc = rs;
    out.counts.score = scratch_.ws.score.count;
    out.counts.step = (clock ? clock() : 0) - t0;
    return Status::kOk;
  }

  /// The configured association's augmentation gate (d2 above it makes a new landmark).
  T augmentation_gate() const { return c_.gate; }

 private:
  /// A map begins (reset, restart): the stages and the closing rule's counts start again.
  void begin_map() {
    reloc_.reset();
    merge_.reset();
    movers_.reset();
    tentative_.reset();
    window_.reset();
    loop_.new_map();
    submap_.begin();
  }
  /// The relocaliser's part: lost -> the scan aligned; an accepted pose applied to the filter with
  /// the pose's correlation to the landmarks it was fitted to, or, when the filter refuses that, as
  /// the fit's own covariance. The sensitivities go through the update's scratch (ekf_ws_: Hp, lm),
  /// unused until predict_local.
  [[gnu::noinline]] Status localise(const Observations<T, B>& obs, const MapView<T, B>& map, RelocStats& rs) {
    const Status st = reloc_.localise(c_.cfg, c_.align, obs, map, scratch_, rs);
    if (st != Status::kOk || !rs.aligned || !scratch_.result.accepted) return st;
    return relocate(obs, rs);
  }
  /// An accepted alignment applied (out of line: its matrices stay off the alignment's call chain).
  [[gnu::noinline]] Status relocate(const Observations<T, B>& obs, RelocStats& rs) {
    Relocation<T> r;
    reloc_.fit(c_.cfg, obs, scratch_, ekf_ws_.Hp.data(), ekf_ws_.lm.data(), r);
    const Pose2<T> lost = slam_.pose();
    const Mat3<T> lost_cov = slam_.pose_covariance();
    Status st = r.pairs >= 2 ? slam_.relocalise_fitted(r.x, r.Pobs, r.pairs, ekf_ws_.lm.data(), ekf_ws_.Hp.data())
                             : Status::kNotPositiveDefinite;
    if (st != Status::kOk) st = slam_.relocalise(r.x, r.cov);
    if (st != Status::kOk) return st;
    reloc_.relocalised(c_.cfg, lost, lost_cov, rs);
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
    if (!c_.cfg.tentative_isolated) return associate(obs, pred_, c_.cfg, ws_, assoc_);
    const int all = pred_.count;
    pred_.count = confirmed;  // the leading candidates: C's leading blocks are their own C
    Status st = pred_.C.resize(confirmed);
    if (st == Status::kOk) st = associate(obs, pred_, c_.cfg, ws_, assoc_);
    pred_.count = all;
    (void)pred_.C.resize(all);  // all <= kMaxCandidates: it held all before
    if (st != Status::kOk) return st;
    tentative_.pair(c_.cfg, obs, pred_, confirmed, c_.gate, map, assoc_);
    tentative_.follow(obs, map, assoc_);
    return Status::kOk;
  }

  /// Clusters first and the hypothesis window, on a tracked scan with no closure pending or
  /// committed, over the frozen map. Out of line and cold: its seeds stay out of step()'s frame.
  [[gnu::noinline, gnu::cold]] Status hypotheses(const Observations<T, B>& obs, const MapView<T, B>& map, bool tracking,
                                                 bool& hold) {
    if ((c_.cfg.hypothesis_rivals == 0 && !c_.cfg.cluster_first) || !tracking || plan_.close.commit ||
        loop_.pending()) {
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
                            reloc::SetModel<T>{c_.cfg.loop_detection_probability, c_.cfg.loop_unexplained_density},
                            &c_.loop_align, c_.cfg.gate.individual};
      if (c_.cfg.cluster_first && !window_.open()) {
        window_stats_.regrouped += clusters_.run(c_.cfg, obs, pred_, map, scratch_, seeds_, sm, assoc_);
      }
      if (c_.cfg.hypothesis_rivals > 0) {
        window_.run(c_.cfg, obs, pred_, map, scratch_, seeds_, sm, assoc_, window_stats_, plan_.close, hold);
      }
      return Status::kOk;
    }
  }

  /// The update's plan filled by the stages (node/update_plan.hpp: a committed closure's rounds,
  /// the movers set aside, the pairs held alone) and applied; then augment, review (`hold`: the scan
  /// is no evidence) and the duplicate merge. @return kOk; the statuses of the plan's update (then
  /// nothing changed). The three halves of step() are out of line: inlined, they took step()'s frame
  /// past 512 B.
  [[gnu::noinline]] Status commit(const Observations<T, B>& obs, const MapView<T, B>& map, bool hold,
                                  StepResult<T, B>& out, CounterFn clock) {
    const std::uint32_t t2 = clock ? clock() : 0;
    // The world model's movers set aside (compiled out: configure() refused motion_false_alarm).
    const int caught = c_.motion_t > T(0) ? movers_.run(obs, map, pred_, static_cast<T>(c_.cfg.gate.individual),
                                                        c_.motion_t, T(c_.policy.static_gate_d2), assoc_, slam_)
                                          : 0;
    if (plan_.close.commit) closure_rounds(map, assoc_, plan_);
    if (c_.cfg.tentative_isolated) tentative_.set_aside(map, assoc_, plan_);
    const Status st = plan_.apply(obs, assoc_, slam_, ekf_ws_);
    if (st != Status::kOk) return st;
    window_.rebase(slam_.pose(), slam_.pose_covariance());
    const std::uint32_t t3 = clock ? clock() : 0;
    // From here on nothing can fail: the outputs are written (stages/augment.hpp).
    const int evicted = augment_unpaired(obs, assoc_, c_.cfg, c_.gate, slam_, out, submap_.added);
    // The scan's observed landmarks (paired, or added from it) are distinct for good.
    constexpr bool kMerge = OptionalStages<B>::kDuplicateMerge;  // compiled out: configure() refused it
    if (kMerge && c_.cfg.duplicate_merge_d2 > T(0))
      merge_.note(slam_, out, c_.cfg.duplicate_merge_d2, c_.cfg.gate.individual);
    if (c_.cfg.tentative_isolated) tentative_.catch_movers(map, assoc_);
    ekf::ReviewStats rs;
    // The view and policy were validated by configure(), the counts above. A scan the hypothesis
    // window holds is no evidence: its landmarks were not paired because the pose is in doubt.
    std::uint32_t existence = 0;
    if (!hold && slam_.review(obs, pred_, assoc_, c_.view, c_.policy, rs, clock, &existence) != Status::kOk) {
      rs = ekf::ReviewStats{};
    }
    if (c_.cfg.tentative_isolated) {                   // the movers' landmarks Tentative::pair found jumped
      for (int k = 0; k < tentative_.jumped(); ++k) {  // <= kMaxMovers
        rs.removed_moved += slam_.forget(tentative_.jumped(k)) == Status::kOk;
      }
    }
    if (kMerge && c_.cfg.duplicate_merge_d2 > T(0) && !hold)
      rs.merged = merge_.merge(c_.cfg.duplicate_merge_d2, pred_, out, slam_, ekf_ws_);
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

  ekf::Slam<T, B> slam_;
  ekf::SlamWorkspace<T, B> ekf_ws_;
  Prediction<T, B> pred_;
  AssociationWorkspace<T, B> ws_;
  Association<T, B> assoc_;
  StepConfig<T, B> c_;  ///< the settings, bound (configure())
  bool configured_ = false;
  // The stages: each owns its state across scans.
  Relocaliser<T, B> reloc_;
  LoopCheck<T, B> loop_;
  HypothesisWindow<T, B> window_;
  ClustersFirst<T, B> clusters_;
  Tentative<T, B> tentative_;
  DuplicateMerge<T, B> merge_;
  /// The movers' tracks, or a stand-in without the world model (OptionalStages::kWorldModel).
  std::conditional_t<OptionalStages<B>::kWorldModel, Movers<T, B>, NoMovers> movers_;
  // Scratch of one scan, shared by the stages in turn (one buffer in RAM).
  AlignScratch<T, B> scratch_;
  Seeds<T, B> seeds_;
  UpdatePlan<T, B> plan_;               ///< the stages' plan for commit()'s update
  reloc::LoopStats<T> loop_stats_;      ///< step()'s, until it writes them out
  reloc::WindowStats<T> window_stats_;  ///< step()'s, until it writes them out
  SubmapClose<T, B> submap_;            ///< the local map's closing rule
};

}  // namespace geojcbb::node
