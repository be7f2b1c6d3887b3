// node/stages: the scan's outcome per observation and the augmentation (docs/design.md, "One
// orchestrator, stages as rooms"). After the update accepted every pair: a paired observation is
// kPaired; one the association left unmatched (ambiguous) kUnmatched; an unpaired one within the
// augmentation gate, or with augmentation off, kNewDropped; the rest become landmarks
// (kNewLandmark), and a full map makes room first when evict_when_full allows (a landmark beyond r
// + d, not in this scan's prediction, so the pairs and the review after it are untouched), or turns
// them away (kNotAugmented). Nothing here can fail: a new landmark's z and R were validated by the
// association. One function, no state across scans. Bounds: O(kMaxObservations (n + evict's O(n))).
#pragma once

#include <limits>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/association_types.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/stages/movers.hpp"
#include "geojcbb/node/step_result.hpp"

namespace geojcbb::node {

/// Writes out.count, d2, feature and outcome for every observation of `assoc` and augments the
/// unpaired ones beyond `gate` (with augment on). added_in_map counts the landmarks added (saturating);
/// @return the landmarks evicted to make room. Always inlined into SlamStep::commit, where it was
/// written before: the images stay as they were (a call of its own cost the default image 168 B).
template <typename T, class B>
[[gnu::always_inline]] inline int augment_unpaired(const Observations<T, B>& obs, const Association<T, B>& assoc,
                                                   const AssociationConfig<T, B>& cfg, T gate, ekf::Slam<T, B>& slam,
                                                   StepResult<T, B>& out, int& added_in_map) {
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
    } else if (f == kMoverFeature) {
      out.outcome[i] = Outcome::kMover;
    } else if (!cfg.augment || !(assoc.d2[i] > gate)) {
      out.outcome[i] = Outcome::kNewDropped;
    } else {
      FeatureId id = -1;
      Status added = slam.augment(obs.z[i], obs.R[i], id);  // only a full map can refuse
      FeatureId gone = -1;
      if (added != Status::kOk && cfg.evict_when_full && slam.evict(cfg.local_radius_m, gone) == Status::kOk) {
        ++evicted;
        added = slam.augment(obs.z[i], obs.R[i], id);
      }
      if (added == Status::kOk) {
        added_in_map += added_in_map < std::numeric_limits<int>::max();
        out.outcome[i] = Outcome::kNewLandmark;
        out.feature[i] = id;
      } else {
        out.outcome[i] = Outcome::kNotAugmented;
      }
    }
  }
  return evicted;
}

}  // namespace geojcbb::node
