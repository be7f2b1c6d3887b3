// node: a SLAM step's settings, validated and bound to what its stages read (SlamStep::configure):
// the association's configuration (the strategy's, make_strategy), the augmentation gate, the view,
// the landmark policy, the filter's options, the two alignments and the motion test's threshold.
// bind() checks every option (the ranges of core/options.h, the stages compiled in, each struct's
// own valid()) before it writes anything. No heap; O(1).
#pragma once

#include "geojcbb/core/capacity.hpp"
#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/core/settings.hpp"
#include "geojcbb/core/strategy.hpp"
#include "geojcbb/ekf/motion_test.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/reloc/align.hpp"

namespace geojcbb::node {

/// The step's settings: every option of core/options.h (core/settings.hpp).
using geojcbb::StepSettings;

/// Whether the image compiles in every stage the settings turn on (OptionalStages): a configuration
/// without the window and clusters first, the hand-over, the duplicate merge or the world model
/// refuses their options.
template <class B, typename T>
bool compiled_in(const StepSettings<T>& s) {
  using O = OptionalStages<B>;
  return (O::kHypotheses || (s.hypothesis_rivals == 0 && !s.cluster_first)) &&
         (O::kHandOver || (s.submap_landmarks == 0 && !(s.submap_distance_m > 0) && s.submap_scans == 0)) &&
         (O::kDuplicateMerge || !(s.duplicate_merge_d2 > 0)) &&
         (O::kWorldModel ||
          (!(s.motion_false_alarm > 0) && !s.learn_detection && !s.learn_clutter && !(s.detection_floor > 0.0f)));
}

template <typename T, class B>
struct StepConfig {
  AssociationConfig<T, B> cfg;        ///< the strategy's configuration (make_strategy) and the options it carries
  T gate = T(0);                      ///< the augmentation gate (new_landmark_level, 2 dof): d2 above it is new
  ekf::Visibility<T> view;            ///< the sensor's view (review, lost test)
  ekf::LandmarkPolicy policy;         ///< existence, static gate, detection
  ekf::FilterOptions filter;          ///< the filter's (reset)
  reloc::AlignOptions<T> align;       ///< the relocaliser's alignment
  reloc::AlignOptions<T> loop_align;  ///< the relocaliser's, with loop_min_inliers (loop check, window, clusters)
  T motion_t = T(0);                  ///< the motion test's threshold (0: off)
  Mount<T> mount;                     ///< the sensor on the robot

  /// @return kOk; kInvalidInput for bad parameters (out of range, a stage not compiled in, a bad
  ///         view, policy or alignment); statuses of make_strategy / chi2_inv. Nothing written
  ///         unless kOk.
  [[nodiscard, gnu::cold]] Status bind(const StepSettings<T>& s) {
    // Every option's range, besides the preset (make_strategy refuses the same settings below).
    if (!in_range(s) || !compiled_in<B>(s)) return Status::kInvalidInput;
    double new_gate = 0;
    Status st = chi2_inv(s.new_landmark_level, 2, new_gate);
    if (st != Status::kOk) return st;
    double static_gate = 0;  // 0: the static-gate rule off
    if (s.static_gate_level > 0) {
      st = chi2_inv(s.static_gate_level, 2, static_gate);
      if (st != Status::kOk) return st;
    }
    // The stages' option structs from the table (bind_options: generated, type-checked).
    ekf::LandmarkPolicy p;
    ekf::bind_options(s, p);
    p.static_gate_d2 = static_cast<float>(static_gate);
    p.p_detect = static_cast<float>(s.loop_detection_probability);
    p.clutter_density = static_cast<float>(s.loop_unexplained_density);
    if (!p.valid()) return Status::kInvalidInput;
    reloc::AlignOptions<T> a;
    reloc::bind_options(s, a);
    if (!a.valid()) return Status::kInvalidInput;
    reloc::AlignOptions<T> la;
    reloc::bind_loop_options(s, la);
    if (!la.valid()) return Status::kInvalidInput;
    // Last: make_strategy checks before it writes, so a refusal here changes nothing either.
    st = make_strategy(s.strategy, s, cfg);
    if (st != Status::kOk) return st;
    mount = Mount<T>{s.sensor_x_m, s.sensor_y_m, s.sensor_theta_rad};
    loop_align = la;
    align = a;
    gate = static_cast<T>(new_gate);
    ekf::bind_options(s, view);
    policy = p;
    policy.gate_d2 = static_cast<float>(cfg.gate.individual);  // the area of a landmark's p_FA (> 0)
    ekf::bind_options(s, filter);
    motion_t = ekf::motion_threshold<T>(s.motion_false_alarm);
    return Status::kOk;
  }
};

}  // namespace geojcbb::node
