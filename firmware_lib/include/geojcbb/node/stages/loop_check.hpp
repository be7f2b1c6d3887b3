// node/stages: the loop check (StepSettings::loop_check, reloc/loop.hpp). Its state across scans: the
// pending closure (wins in a row and its correction) and the agreeing checks in a row.
//   run()  after the association, while tracking: a scan whose local region holds old landmarks
//          (confirmed, unseen for loop_age reviews) has its closure checked against an alignment
//          over them with the filter's pose as the prior; three hypotheses (no closure, the
//          association's, the alignment's) by their log posteriors: the association is left as it
//          is, has its disputed pairs held, or a Closure (the alignment's pairs, or the association's
//          own with loop_min_inliers pairs, or two the prior determines) is confirmed and handed to
//          the step to commit
//   closure_rounds()  a committed closure's pairs ranked for the update's rounds (any stage's closure)
// Bounds: one align() call, two fits and two scores per checked scan; the rewrite and determined() O(m n).
// docs/relocalisation.md ("Loop closures").
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/fmath.hpp"
#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/node/stages/map_view.hpp"
#include "geojcbb/node/update_plan.hpp"
#include "geojcbb/reloc/loop.hpp"

namespace geojcbb::node {

template <typename T, class B>
class LoopCheck {
 public:
  void reset() { state_ = reloc::LoopState<T>{}; }
  /// A new map (SlamStep::reset): no closure pending, no landmark surveyed.
  void new_map() {
    reset();
    surveyed_end_ = 0;
  }
  /// After ekf::Slam::add_known_landmark returned `st` with `id` for a surveyed landmark (a map
  /// measured, not built by the robot): those added right after the reset (ids 0, 1, .. in a row)
  /// are never old. It does not drift with the robot: seeing it again localises, closes no loop.
  /// A map of an earlier session is not surveyed (SlamStep::add_known_landmark's default). @return st
  Status surveyed(Status st, FeatureId id) {
    surveyed_end_ += st == Status::kOk && id == surveyed_end_;
    return st;
  }
  /// Drops the prior when run() returns, whichever way.
  struct PriorScope {
    reloc::AlignOptions<T>& opt;
    ~PriorScope() { opt.has_prior = false; }
  };
  /// A closure is pending: the window keeps out of the way (SlamStep passes it on).
  bool pending() const { return state_.pending > 0; }

  /// One tracked scan (the step calls it with loop_check on and the robot tracking).
  /// @return kOk; kInvalidInput for a count mismatch; the statuses of AlignWorkspace::push_landmark
  ///         and reloc::align (then `assoc` unchanged).
  /// `opt` carries the filter's pose as the prior during the call (no hard search window); it is
  /// pose-free again on return (the window and clusters first still align without it).
  [[nodiscard]] Status run(const AssociationConfig<T, B>& cfg, reloc::AlignOptions<T>& opt,
                           const Observations<T, B>& obs, const Prediction<T, B>& pred, const MapView<T, B>& map,
                           AlignScratch<T, B>& scratch, Association<T, B>& assoc, reloc::LoopStats<T>& ls,
                           Closure<T>& close) {
    if (assoc.count != obs.count) return Status::kInvalidInput;
    (void)reloc::set_prior(map.pose(), map.pose_covariance(), opt);
    const PriorScope pose_free_on_return{opt};
    ls = reloc::LoopStats<T>{};
    close.commit = false;
    auto old = [&](int k) { return map.unseen(k) >= cfg.loop_age && map.confirmed(k) && map.id(k) >= surveyed_end_; };
    int in_region = 0;
    for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates
      const int k = map.slot_of(pred.id[a]);
      in_region += k >= 0 && old(k);
    }
    if (in_region == 0) {  // away from old ground: the next visit is checked afresh
      state_ = reloc::LoopState<T>{};
      return Status::kOk;
    }
    if (state_.pending == 0 && state_.agreed >= reloc::kLoopSettleScans) return Status::kOk;
    const Pose2<T> xp = map.pose();
    // The old landmarks the prior leaves within reach: the local region widened by the prior's gate
    // (opt carries the filter's pose as its prior; pose-free, the whole map).
    const Mat3<T> Pp = map.pose_covariance() + reloc::hypothesis_floor<T>();
    const T reach = opt.has_prior ? cfg.local_radius_m + std::sqrt(opt.prior_gate_d2 * (Pp(0, 0) + Pp(1, 1)))
                                  : std::numeric_limits<T>::infinity();
    const reloc::SetModel<T>& model = opt.model;
    reloc::AlignWorkspace<T, B>& ws = scratch.ws;
    scratch.clear();
    for (int k = 0; k < map.size(); ++k) {  // <= kMaxLandmarks
      if (!old(k) || (map.mean(k) - Vec2<T>(xp.x, xp.y)).squaredNorm() > reach * reach) continue;
      const Status st = scratch.push(map, k);
      if (st != Status::kOk) return st;
    }
    // An observation the association paired with a landmark that is not old is explained where
    // the filter is: no closure's, so left out of both.
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      const int k = map.slot_of(assoc.feature[i]);
      ws.skip[static_cast<std::size_t>(i)] = k >= 0 && !old(k);
    }
    Status st = reloc::align(obs, opt, ws, scratch.result);
    if (st != Status::kOk) return st;
    const reloc::AlignResult<T, B>& a = scratch.result;
    const int m = obs.count;
    ls.old_landmarks = ws.n;
    ls.inliers = a.inliers;
    ls.rival_inliers = a.rival_inliers;
    // No closure: every observation unexplained, every old landmark in view missed, at the pose as it is.
    for (int i = 0; i < m; ++i) ws.pick[i] = -1;  // <= kMaxObservations
    ls.ll_none = reloc::set_log_likelihood(ws, m, xp, opt, model);
    // The association's closure: its pairs with old landmarks, as sorted map indices.
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      const int k = map.slot_of(assoc.feature[i]);
      if (k < 0 || !old(k)) continue;
      for (int s = 0; s < ws.n; ++s) {  // <= kMaxLandmarks
        if (scratch.slot_sorted(s) == k) ws.pick[i] = static_cast<std::int16_t>(s);
      }
    }
    // Consistent with the pose as it is, without the pose's (perhaps overconfident) covariance.
    const bool fits_as_is = reloc::max_pair_d2(ws, m, xp) <= opt.gate_d2;
    Pose2<T> x_assoc = xp;
    Mat3<T> cov_assoc = Mat3<T>::Zero();
    const int assoc_pairs = reloc::fit_picked(ws, m, x_assoc, cov_assoc);
    // Each closure by its log posterior: the set likelihood at its pose plus the prior's -d2/2.
    ls.ll_association = reloc::set_log_likelihood(ws, m, x_assoc, opt, model) - T(0.5) * reloc::prior_d2(opt, x_assoc);
    ls.association_pose = x_assoc;
    // The prior ruled out what the hard window did before: an accepted alignment is within it.
    const bool alternative = a.accepted;
    ls.ambiguous = a.ambiguous;
    const Pose2<T> x_align = a.pose;
    if (alternative) {
      reloc::exclusive_inliers(ws, m, x_align, opt.gate_d2);  // its pairs in pick
      ls.ll_alignment = reloc::set_log_likelihood(ws, m, x_align, opt, model) - T(0.5) * reloc::prior_d2(opt, x_align);
      ls.alignment_pose = x_align;
    } else {
      for (int i = 0; i < m; ++i) ws.pick[i] = -1;  // <= kMaxObservations
    }
    if (alternative && !reloc::distinct(x_align, x_assoc, opt)) {
      ls.verdict = reloc::LoopVerdict::kAgreed;
      state_.pending = 0;
      state_.agreed = std::min(state_.agreed + 1, reloc::kLoopSettleScans);
      return Status::kOk;
    }
    const T margin = cfg.loop_margin_nats;
    // Three hypotheses, each by its log posterior: no closure, the association's, the alignment's.
    // One that leads both others by the margin is taken (the association's only with as many pairs
    // as the alignment needs, or two the prior determines: one fixes no pose); none: the disputed
    // observations are held.
    const T ll_align = alternative ? ls.ll_alignment : -std::numeric_limits<T>::infinity();
    const bool few = !alternative && assoc_pairs >= 2 && assoc_pairs < cfg.loop_min_inliers &&
                     determined(cfg, obs, pred, map, assoc, margin);
    const bool by_association =
        (few || assoc_pairs >= cfg.loop_min_inliers) && ls.ll_association >= std::max(ls.ll_none, ll_align) + margin;
    const bool by_alignment = ll_align >= std::max(ls.ll_none, ls.ll_association) + margin;
    if ((!alternative && fits_as_is) || (by_association && !reloc::distinct(x_assoc, xp, opt))) {
      ls.verdict = reloc::LoopVerdict::kConsistent;  // the association stands (a correction within 1 m, 0.2 rad)
      state_.pending = 0;
      return Status::kOk;
    }
    state_.agreed = 0;
    bool commit_now = false;
    const Pose2<T> xw = by_association ? x_assoc : x_align;
    if (!by_association && !by_alignment) {
      ls.verdict = alternative ? reloc::LoopVerdict::kKept : reloc::LoopVerdict::kNoAlternative;
      state_.pending = 0;
    } else {  // a correction beyond the distinct scale: confirmed, then committed as a closure
      const bool same = state_.pending > 0 && !reloc::distinct(reloc::corrected(state_.correction, xp), xw, opt);
      state_.pending = same ? state_.pending + 1 : 1;
      state_.correction = reloc::correction_between(xp, xw);
      commit_now = state_.pending >= cfg.loop_confirm_scans;
      ls.verdict = commit_now ? reloc::LoopVerdict::kCommitted : reloc::LoopVerdict::kPending;
    }
    // The disputed observations (paired with an old landmark by either closure): held, or paired
    // as the committed closure says (the association's: as they are).
    const bool keep_association = commit_now && by_association;
    for (int i = 0; i < m && !keep_association; ++i) {  // <= kMaxObservations
      const int k = map.slot_of(assoc.feature[i]);
      const bool disputed = ws.pick[i] >= 0 || (k >= 0 && old(k));
      if (!disputed) continue;
      ++ls.held;
      if (commit_now && ws.pick[i] >= 0) {
        pair(assoc, pred, i, map.id(scratch.slot_sorted(ws.pick[i])), ws.pick_d2[i]);
      } else {
        unpair(assoc, i);
      }
    }
    if (!commit_now) return Status::kOk;
    const T dx = xw.x - xp.x, dy = xw.y - xp.y, dth = wrap_angle(xw.theta - xp.theta);
    Mat3<T> Q = by_association ? cov_assoc : a.cov;
    Q(0, 0) += dx * dx;
    Q(1, 1) += dy * dy;
    Q(2, 2) += dth * dth;
    close.Q = cfg.loop_inflation * Q;
    close.at = xw;
    close.commit = true;
    state_ = reloc::LoopState<T>{};
    ls.verdict = reloc::LoopVerdict::kCommitted;
    return Status::kOk;
  }

 private:
  /// Each pair of the association with an old landmark is determined by the prior: its landmark's
  /// likelihood with the filter's covariance, N(z; h, H P H^T + R), leads every other candidate's of
  /// the local region by `margin` nats (a drifted pose with one landmark in reach, not a look-alike
  /// within the pose's uncertainty). Out of line: its loops stay out of run()'s frame.  O(m n)
  [[gnu::noinline, gnu::cold]] bool determined(const AssociationConfig<T, B>& cfg, const Observations<T, B>& obs,
                                               const Prediction<T, B>& pred, const MapView<T, B>& map,
                                               const Association<T, B>& assoc, T margin) const {
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      const int k = map.slot_of(assoc.feature[i]);
      if (k < 0 || map.unseen(k) < cfg.loop_age || !map.confirmed(k) || map.id(k) < surveyed_end_) continue;
      T ll_pair = -std::numeric_limits<T>::infinity(), ll_rival = -std::numeric_limits<T>::infinity();
      for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates
        const Mat2<T> S = pred.C.block(a, a) + obs.R[static_cast<std::size_t>(i)];
        const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
        if (!(det > T(0))) return false;
        const Vec2<T> nu = innovation(obs.z[static_cast<std::size_t>(i)], pred.h[static_cast<std::size_t>(a)]);
        const T d2 =
            (S(1, 1) * nu.x() * nu.x() - (S(0, 1) + S(1, 0)) * nu.x() * nu.y() + S(0, 0) * nu.y() * nu.y()) / det;
        const T ll = T(-0.5) * (d2 + fmath::log(det));
        if (pred.id[static_cast<std::size_t>(a)] == assoc.feature[i]) {
          ll_pair = ll;
        } else {
          ll_rival = std::max(ll_rival, ll);
        }
      }
      if (!(ll_pair >= ll_rival + margin)) return false;
    }
    return true;
  }

  reloc::LoopState<T> state_;
  FeatureId surveyed_end_ = 0;  ///< landmarks with a smaller id are surveyed (surveyed())
};

/// A committed closure's rounds in the update's plan (the loop check's closure or the window's): the
/// paired observations ranked by their landmark's position variance (the landmarks mapped before the
/// drift first), rank k of p in round k rounds / p, the two most certain in the first. Out of line: its loops stay out of the
/// caller's frame.  O(kMaxObservations^2)
template <typename T, class B>
[[gnu::noinline]] void closure_rounds(const MapView<T, B>& map, const Association<T, B>& assoc,
                                      UpdatePlan<T, B>& plan) {
  constexpr int rounds = UpdatePlan<T, B>::kClosureRounds;
  auto& round = plan.round;
  std::array<T, B::kMaxObservations> var{};
  int p = 0;
  for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
    const int k = map.slot_of(assoc.feature[i]);
    round[static_cast<std::size_t>(i)] = 0;
    if (k < 0) continue;  // unpaired, or an unknown id that update() refuses
    var[static_cast<std::size_t>(i)] = map.position_var(k);
    ++p;
  }
  for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
    if (map.slot_of(assoc.feature[i]) < 0) continue;
    int rank = 0;                            // the pairs more certain than i (ties by index)
    for (int k = 0; k < assoc.count; ++k) {  // <= kMaxObservations
      if (k == i || map.slot_of(assoc.feature[k]) < 0) continue;
      const T vk = var[static_cast<std::size_t>(k)], vi = var[static_cast<std::size_t>(i)];
      rank += vk < vi || (vk == vi && k < i);
    }
    // The first round takes two pairs at least (a pose needs two points).
    round[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(rank < 2 ? 0 : rank * rounds / p);
  }
}

}  // namespace geojcbb::node
