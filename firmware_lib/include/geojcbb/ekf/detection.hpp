// ekf: what the map believes about detection and clutter (docs/design.md, "The world model"), learned
// from the scans it reviews, in fixed memory.
//   p_D by range   kDetectionBins bins over [0, max_range]: a Beta prior (mean p_D0, the option
//                  loop_detection_probability, worth kPriorSightings sightings) updated with the
//                  hits and the expected sightings of confirmed landmarks in view, with fading memory
//                  (kDetectionFading a sighting, so about 1/(1 - kDetectionFading) sightings a bin):
//                    p_D(bin) = (a p_D0 + hits) / (a + expected)
//   clutter        a Gamma prior on the density (mean lambda0, the option loop_unexplained_density,
//                  worth kPriorScans scans of the visible area) updated with each scan's unexplained
//                  observations (neither paired nor taken by a mover) over the area in view,
//                  half_fov (max_range^2 - min_range^2):
//                    lambda = (b lambda0 + unexplained) / (b + area)   (both fading kClutterFading a scan)
// A landmark's p_D is its range bin's where the geometry puts it in view (range, field of view, no
// nearer landmark in the way: ekf::in_view), 0 elsewhere. Learning is an option (learn_detection,
// learn_clutter); without it the model is the constants. Bounds: O(1) a landmark, O(kDetectionBins)
// to reset. No heap.
#pragma once

#include <array>

#include "geojcbb/core/fmath.hpp"

namespace geojcbb::ekf {

template <typename T>
class DetectionModel {
 public:
  static constexpr int kDetectionBins = 8;
  /// The prior's weight in sightings of a bin, and in scans of the clutter.
  static constexpr T kPriorSightings = T(10);
  static constexpr T kPriorScans = T(10);
  /// Fading memory: a bin remembers about 1,000 sightings, the clutter about 200 scans.
  static constexpr T kDetectionFading = T(0.999);
  static constexpr T kClutterFading = T(0.995);

  /// The priors (p_D0 in (0, 1), lambda0 > 0 [1/m^2]) and the range the bins span (> 0) [m]; every
  /// learned count forgotten.
  void reset(T pd0, T lambda0, T max_range_m) {
    pd0_ = pd0;
    lambda0_ = lambda0;
    bin_m_ = max_range_m / T(kDetectionBins);
    hits_.fill(T(0));
    expected_.fill(T(0));
    unexplained_ = T(0);
    area_ = T(0);
  }
  /// The bin of range r [m] (the last beyond the range).
  int bin(T r) const {
    const T b = r / bin_m_;
    return b >= T(kDetectionBins - 1) ? kDetectionBins - 1 : (b > T(0) ? static_cast<int>(b) : 0);
  }
  /// p_D of a landmark in view at range r [m].
  T pd(T r) const { return pd_bin(bin(r)); }
  T pd_bin(int b) const {
    const std::size_t k = static_cast<std::size_t>(b);
    return (kPriorSightings * pd0_ + hits_[k]) / (kPriorSightings + expected_[k]);
  }
  /// A bin's width [m].
  T bin_m() const { return bin_m_; }
  /// Sightings expected in bin b (faded), for the host's table.
  T expected_bin(int b) const { return expected_[static_cast<std::size_t>(b)]; }
  /// The clutter density [1/m^2].
  T density() const {
    const T b = kPriorScans * area_scan_;
    return b > T(0) ? (b * lambda0_ + unexplained_) / (b + area_) : lambda0_;
  }

  /// A confirmed landmark in view at range r: detected (paired) or not.
  void sighting(T r, bool detected) {
    const std::size_t k = static_cast<std::size_t>(bin(r));
    hits_[k] = kDetectionFading * hits_[k] + (detected ? T(1) : T(0));
    expected_[k] = kDetectionFading * expected_[k] + T(1);
  }
  /// One scan: `unexplained` observations over `area` m^2 in view.
  void scan(int unexplained, T area) {
    area_scan_ = area;
    unexplained_ = kClutterFading * unexplained_ + T(unexplained);
    area_ = kClutterFading * area_ + area;
  }

 private:
  std::array<T, kDetectionBins> hits_{};
  std::array<T, kDetectionBins> expected_{};
  T unexplained_ = T(0);
  T area_ = T(0);
  T area_scan_ = T(0);  ///< the last scan's area in view: the prior's unit
  T pd0_ = T(0.9);
  T lambda0_ = T(0.003);
  T bin_m_ = T(1);
};

}  // namespace geojcbb::ekf
