// ekf: the landmark book, one record per landmark of the map in index order (its id, first
// estimate and covariance, and the review's counters), and the bookkeeping that reads nothing but
// the book: add, remove keeping the order, index_of, the review's counting and keep-or-remove rules.
//   add, count O(1);  index_of O(log n);  choose_kept, retain O(n);  n <= MaxLandmarks
// Ids are stable: add() hands out increasing ids and removal keeps the order, so the id of index j
// only ever grows with j, and index_of() is a binary search. The filter's state and covariance are
// not here (ekf/slam.hpp keeps them in the same index order). No heap.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/settings.hpp"

namespace geojcbb::ekf {

/// Tentative landmarks: a landmark is confirmed once it has been paired `confirm_hits` times (its
/// first sighting counts). Until then it is removed when it has been expected in view and not
/// paired `max_misses` times, or when `max_tentative_reviews` reviews have passed (it left the view
/// unconfirmed). This keeps clutter that passed the augmentation gate out of the map.
/// Objects that move (another robot) are removed even when confirmed, by two rules (0: off):
///   miss_probability  expected in view and missed so often in a row that a static landmark seen at
///                     this landmark's own rate, p = (hits + 1) / (expected + 2), would be missed
///                     so with a probability below this: (1 - p)^streak < miss_probability;
///   static_gate_d2    paired, but its estimate has moved further than refining a static point can:
///                     (l - l0)^T (P0 - P + f I)^-1 (l - l0) > static_gate_d2, with l0 and P0 the
///                     landmark's position and covariance when it was added, P its covariance now
///                     (for a static point l - l0 has covariance P0 - P) and f = (1 cm)^2.
/// A landmark also needs `confirm_min_reviews` reviews of life to count as confirmed (confirmed()):
/// the time in which the static gate can catch a slow mover before it is trusted; it must be less
/// than max_tentative_reviews, and the tentative rules above apply until then.
struct LandmarkPolicy {
  int confirm_hits = 2;
  int max_misses = 2;
  int max_tentative_reviews = 10;
  float miss_probability = 0.0f;
  float static_gate_d2 = 0.0f;
  int confirm_min_reviews = 0;
  bool valid() const {
    return confirm_hits >= 1 && confirm_hits <= 255 && max_misses >= 1 && max_misses <= 255 &&
           max_tentative_reviews >= 1 && max_tentative_reviews <= 255 && miss_probability >= 0.0f &&
           miss_probability < 1.0f && static_gate_d2 >= 0.0f && static_gate_d2 < 1e30f && confirm_min_reviews >= 0 &&
           confirm_min_reviews < max_tentative_reviews;
  }
};
/// LandmarkPolicy's members that are options of the table, (member, option); static_gate_d2 is the
/// chi-square quantile of static_gate_level (node::SlamStep::configure).
// clang-format off
#define GEOJCBB_LANDMARK_POLICY_OPTIONS(F)        \
  F(confirm_hits, confirm_hits)                   \
  F(max_misses, max_misses)                       \
  F(max_tentative_reviews, max_tentative_reviews) \
  F(miss_probability, miss_probability)           \
  F(confirm_min_reviews, confirm_min_reviews)
// clang-format on
/// out's options of the table from the settings `in` (core/settings.hpp, GEOJCBB_BIND_OPTION).
template <class In>
void bind_options(const In& in, LandmarkPolicy& out) {
  GEOJCBB_LANDMARK_POLICY_OPTIONS(GEOJCBB_BIND_OPTION)
}

struct ReviewStats {
  int expected = 0;        ///< landmarks in the prediction that were in view
  int paired = 0;          ///< of those, paired by the association
  int removed = 0;         ///< landmarks removed (every rule)
  int removed_missed = 0;  ///< of those, confirmed ones removed by the miss-probability rule
  int removed_moved = 0;   ///< of those, removed by the static-gate rule
  int merged = 0;          ///< landmarks merged into another (node::SlamStep: a loop closure's duplicates)
  int evicted = 0;         ///< landmarks evicted to make room in a full map (node::SlamStep: evict_when_full)
};

/// Why the current review removes a landmark whatever its counters say.
enum class Drop : std::uint8_t {
  kNone = 0,
  kMissed,  ///< the miss-probability rule
  kMoved,   ///< the static gate
};

/// One landmark. Members ordered by alignment (scalars, then the id, then the counters), so the
/// only padding is at the end: 35 bytes of members and 1 of padding for float, 59 and 5 for double.
template <typename T>
struct LandmarkRecord {
  T l0[2];                 ///< first estimate [m] (world frame): FEJ's linearisation point, the static gate's l0
  T P0[3];                 ///< its covariance when added [m^2]: xx, xy, yy (the static gate's P0)
  T miss_p;                ///< the miss-probability rule's product over the current streak of misses
  FeatureId id;            ///< stable, never reused
  std::uint16_t hits;      ///< reviews paired (saturating at 65535; the first sighting counts)
  std::uint16_t expected;  ///< reviews in view or paired (saturating)
  std::uint8_t misses;     ///< reviews in view and not paired (saturating at 255)
  std::uint8_t age;        ///< reviews since added (saturating at 255)
  std::uint8_t unseen;     ///< reviews since it was last paired (saturating at 255): a loop closure's age
  Drop drop;               ///< review scratch: set by count() and the filter's static gate
};
// The device's RAM budget counts on it (GEOJCBB_SLAM_STORAGE_SIZE): no padding.
static_assert(sizeof(LandmarkRecord<float>) == 36, "LandmarkRecord<float>: 36 bytes of members, no padding");

/// @tparam T             scalar of the records
/// @tparam MaxLandmarks  capacity
template <typename T, int MaxLandmarks>
class LandmarkBook {
 public:
  /// The largest id: add() refuses (full()) once it has been handed out.
  static constexpr FeatureId kMaxId = 0x7fffffff;

  /// Empties the book and starts the ids again at 0.
  void clear() {
    n_ = 0;
    next_id_ = 0;
  }
  int size() const { return n_; }
  /// The id the next landmark gets (ids grow and are never reused).
  FeatureId next_id() const { return next_id_; }
  /// No room for another landmark: MaxLandmarks are mapped, or the ids are used up.
  bool full() const { return n_ >= MaxLandmarks || next_id_ == kMaxId; }
  const LandmarkRecord<T>& operator[](int j) const { return rec_[j]; }
  LandmarkRecord<T>& operator[](int j) { return rec_[j]; }

  /// The index of the landmark with this id, or -1 when there is none (never mapped, or removed).
  int index_of(FeatureId id) const {
    int lo = 0, hi = n_;  // binary search: ids increase with the index; <= log2(MaxLandmarks) + 1 steps
    while (lo < hi) {
      const int mid = lo + (hi - lo) / 2;
      if (rec_[mid].id < id)
        lo = mid + 1;
      else
        hi = mid;
    }
    return lo < n_ && rec_[lo].id == id ? lo : -1;
  }

  /// Appends a landmark first estimated at l with covariance (xx, xy, yy) = P0; tentative, with one
  /// hit. Precondition: !full().
  /// @return its id
  FeatureId add(const Vec2<T>& l, const Mat2<T>& P0) {
    LandmarkRecord<T>& r = rec_[n_];
    r.l0[0] = l.x();
    r.l0[1] = l.y();
    r.P0[0] = P0(0, 0);
    r.P0[1] = P0(0, 1);
    r.P0[2] = P0(1, 1);
    r.miss_p = T(1);
    r.id = next_id_;
    r.hits = 1;
    r.expected = 1;
    r.misses = 0;
    r.age = 0;
    r.unseen = 0;
    ++n_;
    return next_id_++;
  }

  /// Landmark j has been paired confirm_hits times and has lived confirm_min_reviews reviews.
  bool confirmed(int j, const LandmarkPolicy& policy) const {
    return rec_[j].hits >= policy.confirm_hits && rec_[j].age >= policy.confirm_min_reviews;
  }

  /// Starts a review: no landmark marked for removal, every one a review older.  O(n)
  void start_review() {
    for (int j = 0; j < n_; ++j) {  // <= MaxLandmarks
      rec_[j].drop = Drop::kNone;
      if (rec_[j].unseen < 255) ++rec_[j].unseen;
    }
  }
  /// One review's evidence on landmark j: paired by the association, or expected in view and not
  /// paired (a miss); with miss_probability set, a confirmed landmark missed too often in a row is
  /// marked kMissed (LandmarkPolicy).
  void count(int j, bool in_view, bool paired, const LandmarkPolicy& policy) {
    LandmarkRecord<T>& r = rec_[j];
    if ((in_view || paired) && r.expected < 65535) ++r.expected;
    if (paired) {
      if (r.hits < 65535) ++r.hits;
      r.miss_p = T(1);
      r.unseen = 0;
    } else if (in_view) {
      if (r.misses < 255) ++r.misses;
      if (policy.miss_probability > 0.0f) {
        const T p = (T(r.hits) + T(1)) / (T(r.expected) + T(2));
        r.miss_p *= T(1) - p;
        if (r.hits >= policy.confirm_hits && r.miss_p < T(policy.miss_probability)) r.drop = Drop::kMissed;
      }
    }
  }
  /// The end of a review: a marked landmark is removed, every one ages, a tentative one is removed after
  /// max_misses misses or max_tentative_reviews reviews; the others' indices go to keep, increasing.
  /// Counts the removals in stats.
  /// @return how many are kept
  int choose_kept(const LandmarkPolicy& policy, std::int16_t (&keep)[MaxLandmarks], ReviewStats& stats) {
    int kept = 0;
    for (int j = 0; j < n_; ++j) {  // <= MaxLandmarks
      LandmarkRecord<T>& r = rec_[j];
      if (r.drop != Drop::kNone) {
        stats.removed_missed += r.drop == Drop::kMissed;
        stats.removed_moved += r.drop == Drop::kMoved;
        continue;
      }
      if (r.age < 255) ++r.age;
      if (!confirmed(j, policy)) {
        if (r.misses >= policy.max_misses || r.age >= policy.max_tentative_reviews) continue;
      }
      keep[kept++] = static_cast<std::int16_t>(j);
    }
    stats.removed = n_ - kept;
    return kept;
  }
  /// Record `into` takes the sightings of record `from` (one landmark mapped twice; the filter
  /// removes `from` afterwards): hits and expected add (saturating), misses and unseen take the
  /// smaller, age the larger, the miss streak restarts. `into` keeps its id, first estimate and its P0.
  void absorb(int into, int from) {
    LandmarkRecord<T>& a = rec_[into];
    const LandmarkRecord<T>& b = rec_[from];
    a.hits = static_cast<std::uint16_t>(std::min(65535, int(a.hits) + int(b.hits)));
    a.expected = static_cast<std::uint16_t>(std::min(65535, int(a.expected) + int(b.expected)));
    a.misses = std::min(a.misses, b.misses);
    a.age = std::max(a.age, b.age);
    a.unseen = std::min(a.unseen, b.unseen);
    a.miss_p = T(1);
  }
  /// Keeps the records keep[0 .. kept) (increasing), in that order; the others are removed.
  /// Every source index is at or after its destination, so nothing is overwritten before it is read.
  void retain(const std::int16_t (&keep)[MaxLandmarks], int kept) {
    for (int k = 0; k < kept; ++k) rec_[k] = rec_[keep[k]];  // <= MaxLandmarks
    n_ = kept;
  }

 private:
  std::array<LandmarkRecord<T>, MaxLandmarks> rec_{};
  FeatureId next_id_ = 0;
  int n_ = 0;
};

}  // namespace geojcbb::ekf
