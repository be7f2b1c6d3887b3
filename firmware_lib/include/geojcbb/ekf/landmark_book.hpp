// ekf: the landmark book, one record per landmark of the map in index order (its id, first
// estimate and covariance, its log-odds of existence and the review's counters), and the
// bookkeeping that reads nothing but the book: add, remove keeping the order, index_of, the
// review's evidence and keep-or-remove rules (LandmarkPolicy, ExistenceEvidence).
//   add, count O(1);  index_of O(log n);  choose_kept, retain O(n);  n <= MaxLandmarks
// Ids are stable: add() hands out increasing ids and removal keeps the order, so the id of index j
// only ever grows with j, and index_of() is a binary search. The filter's state and covariance are
// not here (ekf/slam.hpp keeps them in the same index order). No heap.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/fmath.hpp"
#include "geojcbb/core/math.hpp"
#include "geojcbb/core/settings.hpp"
#include "geojcbb/ekf/motion_test.hpp"

namespace geojcbb::ekf {

/// Existence by evidence (docs/design.md, "Landmarks that exist by evidence"): each landmark keeps
/// the log-odds [nats] that it exists, a sequential probability ratio test in the style of the track
/// initiation of multi-target trackers. Added at 0 (a detection nothing explains is as likely a new
/// landmark as clutter), then on each review where it is paired or expected in view:
///   paired              + log(p_D / p_FA)
///   in view, missed     + log((1 - p_D) / (1 - p_FA))
/// p_D = p_detect: a landmark in view is detected; p_FA: a clutter detection falls in its gate,
/// clutter_density (per m^2) times the gate's area, pi gate_d2 sqrt|S| r in (range, bearing) at the
/// predicted range r (S = H P H^T + R; ExistenceEvidence). The log-odds saturates at confirm_nats +
/// reserve_nats (a landmark seen for an hour can still leave); it is confirmed (for good) once it reaches
/// confirm_nats and removed at or below delete_nats, confirmed or not. An M-of-N rule is the special
/// case of constant increments: with p_D = 0.9, p_FA ~ 0.002 a pairing adds ~6.1 nats and a miss
/// ~-2.3, so one re-sighting confirms and two misses remove a new landmark (confirm_hits 2,
/// max_misses 2 before). A landmark that stays tentative max_tentative_reviews reviews (it left the
/// view undecided) is removed: the test truncated. A known landmark (a surveyed map) is confirmed
/// and never removed by the evidence.
/// Objects that move (another robot) also leave by the static gate (0: off):
///   static_gate_d2    paired, but its estimate has moved further than refining a static point can:
///                     (l - l0)^T (P0 - P + f I)^-1 (l - l0) > static_gate_d2, with l0 and P0 the
///                     landmark's position and covariance when it was added, P its covariance now
///                     (for a static point l - l0 has covariance P0 - P) and f = (1 cm)^2.
struct LandmarkPolicy {
  float confirm_nats = 4.6f;
  float delete_nats = -4.0f;
  float reserve_nats = 1000.0f;
  int max_tentative_reviews = 10;
  float p_detect = 0.9f;
  float clutter_density = 0.003f;
  float gate_d2 = 9.21f;  ///< the association's individual gate (the area p_FA is taken over)
  float static_gate_d2 = 0.0f;
  /// A miss counts only where p_D is at least this (0: every miss): a landmark the sensor can hardly
  /// see is no evidence of absence (ekf/detection.hpp).
  float detection_floor = 0.0f;
  bool learn_detection = false;  ///< p_D per range bin learned from the scans (ekf/detection.hpp)
  bool learn_clutter = false;    ///< the clutter density learned from the scans (ekf/detection.hpp)
  /// The log-odds a landmark can bank (confirm_nats + reserve_nats), in T: the book's saturation and
  /// a seed's cap (node::seed_map) are the one number.
  template <typename T>
  T max_nats() const {
    return T(confirm_nats) + T(reserve_nats);
  }
  bool valid() const {
    return delete_nats < 0.0f && delete_nats > -1e30f && confirm_nats > 0.0f && confirm_nats < 1e30f &&
           reserve_nats >= 0.0f && reserve_nats < 1e30f && max_tentative_reviews >= 1 && max_tentative_reviews <= 255 &&
           p_detect > 0.0f && p_detect < 1.0f && clutter_density > 0.0f && clutter_density < 1e30f && gate_d2 > 0.0f &&
           gate_d2 < 1e30f && static_gate_d2 >= 0.0f && static_gate_d2 < 1e30f && detection_floor >= 0.0f &&
           detection_floor <= 1.0f;
  }
};
/// LandmarkPolicy's members that are options of the table, (member, option); node::SlamStep::configure
/// sets the others: p_detect and clutter_density from loop_detection_probability and
/// loop_unexplained_density (the set likelihood's, one home for both), gate_d2 the association's
/// individual gate, static_gate_d2 the chi-square quantile of static_gate_level.
// clang-format off
#define GEOJCBB_LANDMARK_POLICY_OPTIONS(F)             \
  F(confirm_nats, landmark_confirm_nats)               \
  F(delete_nats, landmark_delete_nats)                 \
  F(reserve_nats, landmark_reserve_nats)               \
  F(max_tentative_reviews, max_tentative_reviews)      \
  F(detection_floor, detection_floor)                  \
  F(learn_detection, learn_detection)                  \
  F(learn_clutter, learn_clutter)
// clang-format on
/// out's options of the table from the settings `in` (core/settings.hpp, GEOJCBB_BIND_OPTION).
template <class In>
void bind_options(const In& in, LandmarkPolicy& out) {
  GEOJCBB_LANDMARK_POLICY_OPTIONS(GEOJCBB_BIND_OPTION)
}

/// One review's increments of the log-odds of existence, from the policy (LandmarkPolicy): one
/// square root and one logarithm per landmark in view.
template <typename T>
struct ExistenceEvidence {
  T log_pd;      ///< log p_D
  T log_miss;    ///< log(1 - p_D)
  T area_coeff;  ///< clutter_density pi gate_d2: p_FA = area_coeff sqrt(r^2 |S|)
  explicit ExistenceEvidence(const LandmarkPolicy& p)
      : log_pd(fmath::log(T(p.p_detect))),
        log_miss(fmath::log(T(1) - T(p.p_detect))),
        area_coeff(T(p.clutter_density) * kPi<T> * T(p.gate_d2)) {}
  /// The same with p_D and the clutter density of a learned model (ekf/detection.hpp): log p_D and
  /// log(1 - p_D) per landmark then (hit_pd, miss_pd).
  ExistenceEvidence(const LandmarkPolicy& p, T density)
      : log_pd(T(0)), log_miss(T(0)), area_coeff(density * kPi<T> * T(p.gate_d2)) {}
  /// p_FA for a gate of |S| (range, bearing) at range r (r2_det = r^2 |S|), within [1e-9, 0.5]: a
  /// gate half full of clutter makes a detection little evidence, and never evidence against.
  T pfa(T r2_det) const {
    const T p = area_coeff * std::sqrt(std::max(r2_det, T(0)));
    return p > T(0.5) ? T(0.5) : (p > T(1e-9) ? p : T(1e-9));
  }
  T hit(T pfa) const { return log_pd - fmath::log(pfa); }
  T miss(T pfa) const { return log_miss - fmath::log(T(1) - pfa); }
  static T hit_pd(T pd, T pfa) { return fmath::log(pd) - fmath::log(pfa); }
  static T miss_pd(T pd, T pfa) { return fmath::log(T(1) - pd) - fmath::log(T(1) - pfa); }
};

/// What one review did.
struct ReviewStats {
  int expected = 0;        ///< landmarks in the prediction that were in view
  int paired = 0;          ///< of those, paired by the association
  int removed = 0;         ///< landmarks removed (every rule)
  int removed_missed = 0;  ///< of those, confirmed ones removed by the evidence (log-odds at delete_nats)
  int removed_moved = 0;   ///< of those, removed by the static-gate rule
  int merged = 0;          ///< landmarks merged into another (node::SlamStep: a loop closure's duplicates)
  int evicted = 0;         ///< landmarks evicted to make room in a full map (node::SlamStep: evict_when_full)
  int movers = 0;          ///< landmarks that failed the motion test and left as movers (node::SlamStep)
  int confirmed = 0;       ///< landmarks confirmed by this review
};
/// Why the current review removes a landmark whatever its counters say.
enum class Drop : std::uint8_t {
  kNone = 0,
  kMissed,  ///< the evidence: log-odds at or below delete_nats
  kMoved,   ///< the static gate
};

/// Flags of a landmark record.
enum LandmarkFlag : std::uint8_t {
  kConfirmedFlag = 1,  ///< its log-odds reached confirm_nats (for good)
  kKnownFlag = 2,      ///< known beforehand (a surveyed map): never removed by the evidence
};

/// The motion test's part of a landmark record: its evidence (ekf/motion_test.hpp), or nothing in a
/// configuration without the world model (core/capacity.hpp, OptionalStages::kWorldModel; an empty
/// base takes no room).
template <typename T, bool Motion>
struct MotionPart {
  MotionEvidence<T> motion;  ///< the motion test's evidence
};
template <typename T>
struct MotionPart<T, false> {};

/// One landmark. Members ordered by alignment (the motion part's scalars, the scalars, then the id,
/// then the counters), so the only padding is at the end: 35 bytes of members and 1 of padding for
/// float (55 and 1 with the motion part), 59 and 5 for double (99 and 5).
template <typename T, bool Motion = true>
struct LandmarkRecord : MotionPart<T, Motion> {
  T l0[2];                 ///< first estimate [m] (world frame): FEJ's linearisation point, the static gate's l0
  T P0[3];                 ///< its covariance when added [m^2]: xx, xy, yy (the static gate's P0)
  T exist;                 ///< log-odds that it exists [nats] (LandmarkPolicy), saturating
  FeatureId id;            ///< stable, never reused
  std::uint16_t hits;      ///< reviews paired (saturating at 65535; the first sighting counts)
  std::uint16_t expected;  ///< reviews in view or paired (saturating)
  std::uint8_t flags;      ///< LandmarkFlag
  std::uint8_t age;        ///< reviews since added (saturating at 255)
  std::uint8_t unseen;     ///< reviews since it was last paired (saturating at 255): a loop closure's age
  Drop drop;               ///< review scratch: set by count() and the filter's static gate
};
// The device's RAM budget counts on it (GEOJCBB_SLAM_STORAGE_SIZE): no padding.
static_assert(sizeof(LandmarkRecord<float, false>) == 36, "LandmarkRecord<float>: 36 bytes of members, no padding");
static_assert(sizeof(LandmarkRecord<float, true>) == 56, "LandmarkRecord<float>: 56 bytes with the motion part");

/// The landmarks removed since LandmarkBook::clear_removed(), by every rule (the review, a merge, an
/// eviction, a restart): how many, and the ids of the first kMaxIds of them. A device reports a
/// scan's in POSE, so the host knows which landmarks the local map still holds (docs/submaps.md).
struct RemovedIds {
  static constexpr int kMaxIds = 8;
  std::array<FeatureId, kMaxIds> ids{};
  std::uint16_t count = 0;  ///< all removed (saturating at 65535); ids holds min(count, kMaxIds)
};

/// @tparam T             scalar of the records
/// @tparam MaxLandmarks  capacity
/// @tparam Motion        the records carry the motion test's evidence (OptionalStages::kWorldModel)
template <typename T, int MaxLandmarks, bool Motion = true>
class LandmarkBook {
 public:
  using Record = LandmarkRecord<T, Motion>;

  /// The largest id: add() refuses (full()) once it has been handed out.
  static constexpr FeatureId kMaxId = 0x7fffffff;

  /// Empties the book and starts the ids again at 0.
  void clear() {
    n_ = 0;
    next_id_ = 0;
    clear_removed();
  }
  /// The landmarks removed since clear_removed().
  const RemovedIds& removed() const { return removed_; }
  void clear_removed() { removed_.count = 0; }
  int size() const { return n_; }
  /// The id the next landmark gets (ids grow and are never reused).
  FeatureId next_id() const { return next_id_; }
  /// No room for another landmark: MaxLandmarks are mapped, or the ids are used up.
  bool full() const { return n_ >= MaxLandmarks || next_id_ == kMaxId; }
  const Record& operator[](int j) const { return rec_[j]; }
  Record& operator[](int j) { return rec_[j]; }

  /// The index of the landmark with this id, or -1 when there is none (never mapped, or removed).
  [[gnu::noinline]] int index_of(FeatureId id) const {
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

  /// Appends a landmark first estimated at l with covariance (xx, xy, yy) = P0: tentative, with one
  /// hit and log-odds 0; `known` (a surveyed map): confirmed, and never removed by the evidence.
  /// Precondition: !full().
  /// @return its id
  FeatureId add(const Vec2<T>& l, const Mat2<T>& P0, bool known = false) {
    Record& r = rec_[n_];
    r.l0[0] = l.x();
    r.l0[1] = l.y();
    r.P0[0] = P0(0, 0);
    r.P0[1] = P0(0, 1);
    r.P0[2] = P0(1, 1);
    if constexpr (Motion) r.motion.clear();
    r.exist = T(0);
    r.id = next_id_;
    r.hits = 1;
    r.expected = 1;
    r.flags = known ? static_cast<std::uint8_t>(kConfirmedFlag | kKnownFlag) : std::uint8_t{0};
    r.age = 0;
    r.unseen = 0;
    r.drop = Drop::kNone;
    ++n_;
    return next_id_++;
  }

  /// Landmark j's log-odds has reached confirm_nats (or it is known).
  bool confirmed(int j) const { return (rec_[j].flags & kConfirmedFlag) != 0; }
  /// Landmark j's log-odds of existence [nats].
  T existence(int j) const { return rec_[j].exist; }

  /// Starts a review: no landmark marked for removal, every one a review older.  O(n)
  void start_review() {
    for (int j = 0; j < n_; ++j) {  // <= MaxLandmarks
      rec_[j].drop = Drop::kNone;
      if (rec_[j].unseen < 255) ++rec_[j].unseen;
    }
  }
  /// One review's evidence on landmark j: paired by the association, or expected in view and not
  /// paired (a miss), with the log-odds increment `evidence` (ExistenceEvidence); the log-odds
  /// saturates at confirm_nats + reserve_nats, confirms at confirm_nats and marks the landmark kMissed at delete_nats
  /// unless it is known (LandmarkPolicy).
  /// @return the landmark was confirmed by this review
  bool count(int j, bool in_view, bool paired, T evidence, const LandmarkPolicy& policy) {
    Record& r = rec_[j];
    if (!in_view && !paired) return false;
    if (r.expected < 65535) ++r.expected;
    if (paired) {
      if (r.hits < 65535) ++r.hits;
      r.unseen = 0;
    }
    r.exist = std::min(r.exist + evidence, policy.template max_nats<T>());
    if ((r.flags & kKnownFlag) == 0 && r.exist <= T(policy.delete_nats)) r.drop = Drop::kMissed;
    if ((r.flags & kConfirmedFlag) != 0 || r.exist < T(policy.confirm_nats)) return false;
    r.flags = static_cast<std::uint8_t>(r.flags | kConfirmedFlag);
    return true;
  }
  /// The end of a review: a marked landmark is removed, every one ages, one still tentative after
  /// max_tentative_reviews reviews is removed; the others' indices go to keep, increasing. Counts
  /// the removals in stats.
  /// @return how many are kept
  int choose_kept(const LandmarkPolicy& policy, std::int16_t (&keep)[MaxLandmarks], ReviewStats& stats) {
    int kept = 0;
    for (int j = 0; j < n_; ++j) {  // <= MaxLandmarks
      Record& r = rec_[j];
      if (r.drop != Drop::kNone) {
        stats.removed_missed += r.drop == Drop::kMissed && confirmed(j);
        stats.removed_moved += r.drop == Drop::kMoved;
        continue;
      }
      if (r.age < 255) ++r.age;
      if (!confirmed(j) && r.age >= policy.max_tentative_reviews) continue;
      keep[kept++] = static_cast<std::int16_t>(j);
    }
    stats.removed = n_ - kept;
    return kept;
  }
  /// Record `into` takes the sightings of record `from` (one landmark mapped twice; the filter
  /// removes `from` afterwards): hits and expected add (saturating), unseen takes the smaller, age,
  /// the log-odds and the flags the larger (or: confirmed or known if either is). `into` keeps its
  /// id, first estimate and its P0.
  void absorb(int into, int from) {
    Record& a = rec_[into];
    const Record& b = rec_[from];
    a.hits = static_cast<std::uint16_t>(std::min(65535, int(a.hits) + int(b.hits)));
    a.expected = static_cast<std::uint16_t>(std::min(65535, int(a.expected) + int(b.expected)));
    a.flags = static_cast<std::uint8_t>(a.flags | b.flags);
    a.age = std::max(a.age, b.age);
    a.unseen = std::min(a.unseen, b.unseen);
    a.exist = std::max(a.exist, b.exist);
  }
  /// Keeps the records keep[0 .. kept) (increasing), in that order; the others are removed.
  /// Every source index is at or after its destination, so nothing is overwritten before it is read.
  /// The removed ones are noted (removed()).
  void retain(const std::int16_t (&keep)[MaxLandmarks], int kept) {
    for (int j = 0, k = 0; j < n_; ++j) {  // <= MaxLandmarks: the ones not kept, in order
      if (k < kept && keep[k] == j) {
        ++k;
        continue;
      }
      if (removed_.count < RemovedIds::kMaxIds) removed_.ids[removed_.count] = rec_[j].id;
      if (removed_.count < 65535) ++removed_.count;
    }
    for (int k = 0; k < kept; ++k) rec_[k] = rec_[keep[k]];  // <= MaxLandmarks
    n_ = kept;
  }

 private:
  std::array<Record, MaxLandmarks> rec_{};
  RemovedIds removed_{};
  FeatureId next_id_ = 0;
  int n_ = 0;
};

}  // namespace geojcbb::ekf
