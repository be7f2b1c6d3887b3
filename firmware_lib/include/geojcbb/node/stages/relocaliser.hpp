// node/stages: the relocaliser (StepSettings::relocalise). Its state across scans: tracking, lost or
// confirming, the scans left to confirm, the failed scans in a row, the pose covariance when lost.
//   localise()  before the association: lost (told: SlamStep::lost, RELOCALISE; or failed scans:
//               evidence, never the covariance alone) -> the scan aligned against the supported
//               landmarks (reloc::align) with the filter's pose as the prior, unless its position
//               spread is wider than the map (then pose-free); an accepted alignment is returned as
//               a Relocation for the step to apply
//   confirm()   after the update: while confirming, reloc_confirm_scans jointly compatible scans with
//               reloc_min_inliers pairs make the robot found, one without sends it back (Verdict)
// Bounds: one align() call and one fit per lost scan; O(m) per tracked scan.
// docs/relocalisation.md.
#pragma once

#include <limits>

#include "geojcbb/core/association_config.hpp"
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

template <typename T, class B>
class Relocaliser {
 public:
  void reset() {
    state_ = Localisation::kTracking;
    failed_scans_ = 0;
    trust_prior_ = true;
  }
  /// The user says so (RELOCALISE, SlamStep::lost): the pose covariance the user set is the prior.
  /// `relocalising` false (the relocaliser off, or not configured): nothing changes.
  void lost(bool relocalising) {
    if (!relocalising) return;
    state_ = Localisation::kLost;
    trust_prior_ = true;
  }
  Localisation state() const { return state_; }

  /// Before the association. When lost, the scan is aligned against the supported landmarks
  /// (scratch.result); an accepted pose is then fit() for the step to apply, which calls relocalised().
  /// @return kOk; the statuses of AlignWorkspace::push_landmark and reloc::align (nothing changes).
  /// `align` gets the scan's prior (reloc::set_prior; none when the position spread is wider than
  /// the map).
  [[nodiscard]] Status localise(const AssociationConfig<T, B>& cfg, reloc::AlignOptions<T>& align,
                                const Observations<T, B>& obs, const MapView<T, B>& map, AlignScratch<T, B>& scratch,
                                RelocStats& rs) {
    rs = RelocStats{};
    rs.state = state_;
    if (!cfg.relocalise || state_ != Localisation::kLost) return Status::kOk;
    scratch.clear();
    Vec2<T> lo(std::numeric_limits<T>::infinity(), std::numeric_limits<T>::infinity()), hi = -lo;
    for (int k = 0; k < map.size(); ++k) {  // <= kMaxLandmarks
      if (!map.supported(k)) continue;
      const Status st = scratch.push(map, k);
      if (st != Status::kOk) return st;
      lo = lo.cwiseMin(map.mean(k));
      hi = hi.cwiseMax(map.mean(k));
    }
    // The prior says where to look, unless the scans declared the pose wrong (lost by failed scans:
    // the covariance did not show it) or it is wider than the map (a reset that carries no
    // information: its position sigma against the map's half diagonal).
    const T spread2 = map.pose_cov(0, 0) + map.pose_cov(1, 1);
    const T half_diag2 = scratch.ws.n > 0 ? T(0.25) * (hi - lo).squaredNorm() : T(0);
    if (!trust_prior_ || !(spread2 < half_diag2) || !reloc::set_prior(map.pose(), map.pose_covariance(), align)) {
      align.has_prior = false;
    }
    rs.prior = align.has_prior;
    // The relocaliser's own options: a kidnap onto ground the map has not seen is no coincidence
    // elsewhere (pose-free, "not of the map" is uniform over the map's box and every heading).
    align.test_unmapped = true;
    const Vec2<T> ext = (hi - lo).cwiseMax(Vec2<T>::Constant(T(1)));
    align.free_log_volume = std::log(ext.x() * ext.y() * T(2) * kPi<T>);
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
  /// The step applied the Relocation; `lost_cov` is the pose covariance it had before.
  void relocalised(const AssociationConfig<T, B>& cfg, const Mat3<T>& lost_cov, RelocStats& rs) {
    lost_cov_ = lost_cov;
    rs.relocalised = true;
    state_ = cfg.reloc_confirm_scans > 0 ? Localisation::kConfirming : Localisation::kTracking;
    rs.found = state_ == Localisation::kTracking;
    rs.state = state_;
    confirm_left_ = cfg.reloc_confirm_scans;
    skip_confirm_ = true;  // the scan that was aligned does not confirm itself
  }

  /// After the update, with the scan's pairs, its observations and candidates. While tracking,
  /// with reloc_lost_failed_scans > 0: a scan that pairs nothing although it has reloc_min_inliers
  /// observations and as many candidates fails; that many in a row make the robot lost (a kidnap
  /// the covariance does not show). @return true when the confirmation failed: the step puts the
  /// pose covariance back to lost_covariance() and, if the filter takes it, calls rejected().
  [[nodiscard]] bool confirm(const AssociationConfig<T, B>& cfg, int paired, int observations, int candidates,
                             bool jointly_compatible, RelocStats& rs) {
    const int need = cfg.reloc_min_inliers;
    const bool failed = paired == 0 && observations >= need && candidates >= need;
    failed_scans_ = state_ == Localisation::kTracking && failed ? failed_scans_ + 1 : 0;
    if (cfg.relocalise && cfg.reloc_lost_failed_scans > 0 && failed_scans_ >= cfg.reloc_lost_failed_scans) {
      state_ = Localisation::kLost;
      failed_scans_ = 0;
      trust_prior_ = false;  // the scans say the pose is wrong, whatever its covariance says
    }
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
  void rejected(RelocStats& rs) {
    state_ = Localisation::kLost;
    rs.rejected = true;
    rs.state = state_;
  }

 private:
  Localisation state_ = Localisation::kTracking;
  int confirm_left_ = 0;
  int failed_scans_ = 0;  ///< scans in a row that paired nothing while tracking (reloc_lost_failed_scans)
  bool skip_confirm_ = false;
  bool trust_prior_ = true;  ///< lost by being told (the pose covariance is the prior), not by failed scans
  Mat3<T> lost_cov_ = Mat3<T>::Identity();
};

}  // namespace geojcbb::node
