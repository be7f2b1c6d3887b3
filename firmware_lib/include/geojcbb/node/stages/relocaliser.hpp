// node/stages: the relocaliser (StepSettings::relocalise). Its state across scans: tracking, lost or
// confirming, the scans left to confirm, the doubt (the lost test's CUSUM), the pose covariance when lost.
//   localise()  before the association: lost (told: SlamStep::lost, RELOCALISE) -> the scan aligned
//               against the confirmed landmarks (reloc::align) with the filter's pose as the prior,
//               unless its position spread is wider than the map (then pose-free); doubted (the lost
//               test below) -> the scan aligned pose-free while it is still tracked: an accepted pose
//               within the filter's prior clears the doubt, one beyond it is a kidnap. An accepted
//               alignment is returned as a Relocation for the step to apply
//   confirm()   after the update: the lost test (scan_evidence, a CUSUM against reloc_lost_nats:
//               evidence, never the covariance alone); while confirming, reloc_confirm_scans jointly
//               compatible scans with reloc_min_inliers pairs make the robot found, one without sends
//               it back
// Bounds: one align() call and one fit per lost or doubted scan; scan_evidence O(m n) per tracked scan.
// docs/relocalisation.md.
#pragma once

#include <limits>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/fmath.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/gate/compatibility.hpp"
#include "geojcbb/node/stages/map_view.hpp"
#include "geojcbb/reloc/align.hpp"

namespace geojcbb::node {

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
  bool prior = false;                            ///< the alignment had the filter's pose as its prior (else pose-free)
  bool ambiguous = false;                        ///< a distinct pose within reloc_margin_nats: nothing accepted
  bool unmapped = false;                         ///< "not of the map" within reloc_margin_nats: nothing accepted
  bool doubted = false;  ///< aligned pose-free while tracking: the lost test doubted the tracked pose
  bool cleared = false;  ///< of a doubted scan: the aligned pose lies within the filter's prior (doubt cleared)
  float doubt = 0;       ///< the lost test's CUSUM after the step [nats]; doubted from reloc_lost_nats on
  int inliers = 0, rival_inliers = 0, misses = 0, hypotheses = 0;  ///< of the alignment
};

/// An accepted alignment, for the step to apply: ekf::Slam::relocalise_fitted(x, Pobs, pairs, lm, At)
/// when pairs >= 2, else (or when the filter refuses it) ekf::Slam::relocalise(x, cov).
template <typename T>
struct Relocation {
  Pose2<T> x{};
  Mat3<T> Pobs;  ///< the observations' part of the fit's covariance, inflated
  Mat3<T> cov;   ///< the fit's whole covariance, inflated
  int pairs = 0;
};

/// The lost test's evidence of one tracked scan [nats]: log p(scan | the tracked pose is right) -
/// log p(scan | it is wrong), from the step's association at the tracked pose (its prediction):
///   sum over pairs with confirmed landmarks  log p_j - d2/2 - log|2 pi S|/2 - log(density r_i)
///   + (confirmed landmarks in view, not paired)  log(1 - p_j)
/// p_j = min(p_D, (hits + 1) / (expected + 2)): the landmark's own detection rate (a landmark often
/// missed where it should be seen, occluded or spurious, is little evidence either way).
/// S = C_jj + R_i (range, bearing); density r_i: the unexplained density per m^2 in (range, bearing)
/// at the observation's range. Pose wrong: every observation is unexplained (observations the map
/// does not explain cancel) and the landmarks the map puts in view are not there. Only confirmed
/// landmarks with an id below `before` are evidence: tentative ones, and those mapped since the pose
/// came into doubt, were made at the tracked pose and follow it. Bound: m n (+ n^2 occlusion).
template <typename T, class B>
[[gnu::noinline]] T scan_evidence(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                  const Association<T, B>& assoc, const MapView<T, B>& map, FeatureId before,
                                  const ekf::Visibility<T>& view, const reloc::SetModel<T>& model) {
  const T log_2pi = fmath::log(T(2) * kPi<T>), log_density = fmath::log(model.unexplained_density);
  T e = T(0);
  for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates
    const int k = map.slot_of(pred.id[a]);
    if (pred.id[a] >= before || !map.confirmed(k)) continue;
    const T p = std::min(model.p_detect, (T(map.hits(k)) + T(1)) / (T(map.expected(k)) + T(2)));
    int i = 0;
    while (i < assoc.count && assoc.feature[i] != pred.id[a]) ++i;  // <= kMaxObservations
    if (i == assoc.count) {
      e += ekf::in_view(pred, a, view) ? fmath::log(T(1) - p) : T(0);
      continue;
    }
    const Mat2<T> S = pred.C.block(a, a) + obs.R[i];
    const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    if (!(det > T(0)) || !(obs.z[i].x() > T(0))) continue;  // no evidence either way
    const T d2 = mahalanobis2(innovation(obs.z[i], pred.h[a]), S);
    e += fmath::log(p) - T(0.5) * d2 - log_2pi - T(0.5) * fmath::log(det) - log_density - fmath::log(obs.z[i].x());
  }
  return e;
}

template <typename T, class B>
class Relocaliser {
 public:
  void reset() {
    state_ = Localisation::kTracking;
    doubt_ = T(0);
    from_doubt_ = false;
  }
  /// The user says so (RELOCALISE, SlamStep::lost): the pose covariance the user set is the prior.
  /// `relocalising` false (the relocaliser off, or not configured): nothing changes.
  void lost(bool relocalising) {
    if (!relocalising) return;
    state_ = Localisation::kLost;
    doubt_ = T(0);
    from_doubt_ = false;
  }
  Localisation state() const { return state_; }
  /// The lost test's doubt (CUSUM, nats).
  T doubt() const { return doubt_; }
  /// The landmarks that are evidence on the pose (scan_evidence's `before`): those mapped before this
  /// scan, or before the pose came into doubt (localise() keeps it).
  FeatureId evidence_before() const { return doubt_from_; }

  /// Before the association. When lost, the scan is aligned against the confirmed landmarks
  /// (scratch.result); an accepted pose is then fit() for the step to apply, which calls relocalised().
  /// @return kOk; the statuses of AlignWorkspace::push_landmark and reloc::align (nothing changes).
  /// `align` gets the scan's prior (reloc::set_prior; none when the position spread is wider than
  /// the map).
  [[nodiscard]] Status localise(const AssociationConfig<T, B>& cfg, reloc::AlignOptions<T>& align,
                                const Observations<T, B>& obs, const MapView<T, B>& map, AlignScratch<T, B>& scratch,
                                RelocStats& rs) {
    rs = RelocStats{};
    rs.state = state_;
    rs.doubt = static_cast<float>(doubt_);
    if (!(doubt_ > T(0))) doubt_from_ = map.next_id();  // frozen while the doubt lasts
    const bool doubted = cfg.relocalise && state_ == Localisation::kTracking && cfg.reloc_lost_nats > T(0) &&
                         doubt_ >= cfg.reloc_lost_nats;
    if (!cfg.relocalise || (state_ != Localisation::kLost && !doubted)) return Status::kOk;
    scratch.clear();
    Vec2<T> lo(std::numeric_limits<T>::infinity(), std::numeric_limits<T>::infinity()), hi = -lo;
    for (int k = 0; k < map.size(); ++k) {  // <= kMaxLandmarks
      // Doubted: the landmarks mapped since the doubt began follow the doubted pose, and are left out.
      if (!map.confirmed(k) || (doubted && map.id(k) >= doubt_from_)) continue;
      const Status st = scratch.push(map, k);
      if (st != Status::kOk) return st;
      lo = lo.cwiseMin(map.mean(k));
      hi = hi.cwiseMax(map.mean(k));
    }
    // The prior says where to look, unless the scans doubt the pose (the covariance did not show
    // it) or it is wider than the map (a reset that carries no information: its position sigma
    // against the map's half diagonal).
    const T spread2 = map.pose_cov(0, 0) + map.pose_cov(1, 1);
    const T half_diag2 = scratch.ws.n > 0 ? T(0.25) * (hi - lo).squaredNorm() : T(0);
    if (doubted || !(spread2 < half_diag2) || !reloc::set_prior(map.pose(), map.pose_covariance(), align)) {
      align.has_prior = false;
    }
    rs.prior = align.has_prior;
    // The relocaliser's own options: a kidnap onto ground the map has not seen is no coincidence
    // elsewhere (pose-free, "not of the map" is uniform over the map's box and every heading).
    align.test_unmapped = true;
    const Vec2<T> ext = (hi - lo).cwiseMax(Vec2<T>::Constant(T(1)));
    align.free_log_volume = fmath::log(ext.x() * ext.y() * T(2) * kPi<T>);
    const Status st = reloc::align(obs, align, scratch.ws, scratch.result);
    if (st != Status::kOk) return st;
    const reloc::AlignResult<T, B>& a = scratch.result;
    rs.aligned = true;
    rs.inliers = a.inliers;
    rs.rival_inliers = a.rival_inliers;
    rs.misses = a.misses;
    rs.hypotheses = a.hypotheses;
    rs.ambiguous = a.ambiguous;
    rs.unmapped = a.unmapped;
    rs.doubted = doubted;
    if (doubted && scratch.result.accepted) {
      // The tracked pose explains the alignment when it lies within the filter's prior (the gate
      // the prior's candidates are scored in): the doubt cleared, nothing applied.
      reloc::AlignOptions<T> tracked = align;
      if (reloc::set_prior(map.pose(), map.pose_covariance(), tracked) &&
          reloc::prior_d2(tracked, a.pose) <= tracked.prior_gate_d2) {
        scratch.result.accepted = false;
        rs.cleared = true;
        doubt_ = T(0);
        rs.doubt = 0;
      }
    }
    return Status::kOk;
  }
  /// After localise() with scratch.result.accepted: the accepted pose for the step to apply, with the
  /// pose's correlation to the landmarks it was fitted to (their error moves the fit) in At and lm
  /// (slots); the observations' part of its covariance times reloc_inflation. Its own frame: the
  /// alignment's call chain does not carry it.
  [[gnu::noinline]] void fit(const AssociationConfig<T, B>& cfg, const Observations<T, B>& obs,
                             const AlignScratch<T, B>& scratch, Mat23<T>* At, std::int16_t* lm,
                             Relocation<T>& out) const {
    const reloc::AlignResult<T, B>& a = scratch.result;
    Mat3<T> Pobs;  // written by fit_sensitivities when it fits (pairs >= 2)
    out.pairs = reloc::fit_sensitivities(scratch.ws, obs.count, a.pose, At, lm, Pobs);
    for (int k = 0; k < out.pairs; ++k)
      lm[k] = static_cast<std::int16_t>(scratch.slot_sorted(lm[k]));  // <= kMaxObservations
    out.x = a.pose;
    if (out.pairs >= 2) out.Pobs = Pobs * cfg.reloc_inflation;  // else not used (relocalise with cov)
    out.cov = a.cov * cfg.reloc_inflation;
  }
  /// The step applied the Relocation; `lost` and `lost_cov` are the pose and covariance it had before.
  void relocalised(const AssociationConfig<T, B>& cfg, const Pose2<T>& lost, const Mat3<T>& lost_cov, RelocStats& rs) {
    lost_pose_ = lost;
    lost_cov_ = lost_cov;
    rs.relocalised = true;
    from_doubt_ = rs.doubted;  // a failed confirmation goes back to the tracked pose (rejected())
    doubt_lost_ = doubt_;
    doubt_from_lost_ = doubt_from_;
    doubt_ = T(0);
    state_ = cfg.reloc_confirm_scans > 0 ? Localisation::kConfirming : Localisation::kTracking;
    rs.found = state_ == Localisation::kTracking;
    rs.state = state_;
    confirm_left_ = cfg.reloc_confirm_scans;
    skip_confirm_ = true;  // the scan that was aligned does not confirm itself
  }

  /// After the update, with the scan's pairs and its evidence (scan_evidence). The lost test, while
  /// tracking with reloc_lost_nats > 0: doubt = min(2 h, max(0, doubt - evidence)), a CUSUM (Page's
  /// test) of the evidence against the tracked pose; from h = reloc_lost_nats on, the next scans are
  /// aligned pose-free (localise). The cap bounds the scans it takes to trust the pose again.
  /// @return true when the confirmation failed: the step puts the pose back to lost_pose() (a
  /// relocalisation after a doubt: the pose it tracked; told lost: where it is) with
  /// lost_covariance() and, if the filter takes it, calls rejected().
  [[nodiscard]] bool confirm(const AssociationConfig<T, B>& cfg, int paired, T evidence, bool jointly_compatible,
                             RelocStats& rs) {
    const int need = cfg.reloc_min_inliers;
    const T h = cfg.reloc_lost_nats;
    if (cfg.relocalise && state_ == Localisation::kTracking && h > T(0) && std::isfinite(evidence)) {
      doubt_ = std::min(T(2) * h, std::max(T(0), doubt_ - evidence));
    }
    rs.doubt = static_cast<float>(doubt_);
    bool reject = false;
    if (state_ == Localisation::kConfirming && !skip_confirm_) {
      if (paired >= need && jointly_compatible) {
        if (--confirm_left_ <= 0) {
          state_ = Localisation::kTracking;
          rs.found = true;
        }
      } else {
        reject = true;
      }
    }
    skip_confirm_ = false;
    rs.state = state_;
    return reject;
  }
  const Mat3<T>& lost_covariance() const { return lost_cov_; }
  /// Where a failed confirmation puts the pose: the tracked pose when the relocalisation came from
  /// a doubt (one scan did not bear the jump out: tracked again, with the doubt it had, so the next
  /// scan is aligned pose-free again), else `current` (lost: the relocaliser searches on).
  Pose2<T> lost_pose(const Pose2<T>& current) const { return from_doubt_ ? lost_pose_ : current; }
  void rejected(RelocStats& rs) {
    state_ = from_doubt_ ? Localisation::kTracking : Localisation::kLost;
    doubt_ = from_doubt_ ? doubt_lost_ : T(0);
    if (from_doubt_) doubt_from_ = doubt_from_lost_;  // the landmarks mapped since the doubt are still no evidence
    rs.rejected = true;
    rs.state = state_;
    rs.doubt = static_cast<float>(doubt_);
  }

 private:
  Localisation state_ = Localisation::kTracking;
  int confirm_left_ = 0;
  T doubt_ = T(0);            ///< the lost test's CUSUM [nats] (confirm)
  FeatureId doubt_from_ = 0;  ///< the first id mapped since this scan began, or (doubt_ > 0) since the doubt did
  bool skip_confirm_ = false;
  bool from_doubt_ = false;        ///< the last relocalisation came from a doubt, not from being lost
  T doubt_lost_ = T(0);            ///< the doubt when it did
  FeatureId doubt_from_lost_ = 0;  ///< and doubt_from_
  Pose2<T> lost_pose_{};           ///< the pose before the last relocalisation
  Mat3<T> lost_cov_ = Mat3<T>::Identity();
};

}  // namespace geojcbb::node
