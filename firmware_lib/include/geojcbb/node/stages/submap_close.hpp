// node/stages: the local map's closing rule (docs/submaps.md). A local map is handed over when it
// holds submap_landmarks landmarks (once it has added one of its own), or the robot has travelled
// submap_distance_m, or it has taken submap_scans scans (0 each off), at a settled pose: tracked,
// no loop closure pending, no hypothesis window open.
// Its state across scans: the metres, scans and landmarks added since the local map began.
//   travelled() / scan() / added   counted by the step's prediction, step() and the augmentation
//   due()      after a scan: whether the map is to be handed over (StepResult::submap_due)
//   carried(), kept()  which landmarks the next map begins with (submap_carry: the confirmed ones of the
//              last scan's local region, so consecutive maps share them)
//   room()     how many landmarks a seeded map may hold (the closing size, or the capacity less a scan)
// Bounds: O(1) but carried(), O(kMaxCandidates).
#pragma once

#include <cstdint>
#include <limits>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/node/stages/map_view.hpp"

namespace geojcbb::node {

template <typename T, class B>
class SubmapClose {
 public:
  /// A local map begins (reset, restart).
  void begin() {
    travelled_m_ = T(0);
    scans_ = 0;
    added = 0;
  }
  /// The robot moved `metres` (a prediction).
  void travelled(T metres) { travelled_m_ += metres; }
  /// A scan was taken.
  void scan() {
    if (scans_ < std::numeric_limits<int>::max()) ++scans_;
  }
  T travelled_m() const { return travelled_m_; }
  int scans() const { return scans_; }

  /// Whether the map is to be handed over now: `settled` (tracked, no closure pending, no window
  /// open) and one of the rule's limits reached. The fill level counts every landmark (the device's
  /// capacity), but only once the map has added one of its own: a map that began fuller (carried
  /// over, seeded) is not closed at once.
  bool due(const AssociationConfig<T, B>& cfg, bool settled, int landmarks) const {
    if (!settled) return false;
    const auto held = static_cast<std::uint32_t>(landmarks);
    const auto scans = static_cast<std::uint32_t>(scans_);
    return (cfg.submap_landmarks > 0 && held >= cfg.submap_landmarks && added > 0) ||
           (cfg.submap_distance_m > T(0) && travelled_m_ >= cfg.submap_distance_m) ||
           (cfg.submap_scans > 0 && scans >= cfg.submap_scans);
  }
  /// Whether the next map keeps landmark k (slot): with submap_carry, a confirmed landmark of the
  /// last scan's region `pred`.  O(kMaxCandidates)
  static bool carried(const AssociationConfig<T, B>& cfg, const MapView<T, B>& map, const Prediction<T, B>& pred,
                      int k) {
    if (!cfg.submap_carry || !map.confirmed(k)) return false;
    for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates: in the last scan's region
      if (pred.id[a] == map.id(k)) return true;
    }
    return false;
  }
  /// The landmarks the next map keeps (carried()), in keep[0 .. return), in order.  O(n kMaxCandidates)
  static int kept(const AssociationConfig<T, B>& cfg, const MapView<T, B>& map, const Prediction<T, B>& pred,
                  std::int16_t (&keep)[B::kMaxLandmarks]) {
    int n = 0;
    for (int k = 0; k < map.size(); ++k) {  // <= kMaxLandmarks
      if (carried(cfg, map, pred, k)) keep[n++] = static_cast<std::int16_t>(k);
    }
    return n;
  }
  /// The landmarks a seeded map may hold: the closing size, or the capacity less one scan's.
  static int room(const AssociationConfig<T, B>& cfg) {
    int limit = B::kMaxLandmarks - B::kMaxObservations;
    if (cfg.submap_landmarks > 0 && static_cast<int>(cfg.submap_landmarks) < limit) {
      limit = static_cast<int>(cfg.submap_landmarks);
    }
    return limit;
  }

  int added = 0;  ///< landmarks augmented since the local map began (the augmentation counts them)

 private:
  T travelled_m_ = T(0);  ///< since the local map began
  int scans_ = 0;         ///< since the local map began
};

}  // namespace geojcbb::node
