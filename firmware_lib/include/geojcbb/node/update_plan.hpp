// node: the update's plan, what the stages decided for this scan's update and SlamStep::commit()
// applies to the filter in one place (docs/design.md, "The step"). The stages fill it in turn:
//   the loop check or the hypothesis window   close: a committed closure (inflated pose, linearised at `at`)
//   closure_rounds (stages/loop_check.hpp)    round: each pair's round, most certain first
//   Tentative::set_aside                      round kAlone: a pair that moves only its tentative landmark
//   the world model (stages/movers.hpp)       movers: taken out of the association (kMoverFeature)
// apply() then runs the update: round 0 (with the closure's inflation, undone on a refusal), the
// later rounds at the estimate the earlier ones left, and the pairs held alone.
#pragma once

#include <array>
#include <cstdint>

#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/stages/map_view.hpp"

namespace geojcbb::node {

template <typename T, class B>
struct UpdatePlan {
  /// A committed closure's pairs are applied in this many rounds, most certain first; each round
  /// after the first is linearised at the estimate the rounds before it left (an iterated update
  /// with a bounded number of iterations).
  static constexpr int kClosureRounds = 3;
  /// The round of a pair held alone (no round of the filter's update).
  static constexpr std::uint8_t kAlone = 255;

  Closure<T> close;  ///< a stage's committed closure (the loop check's or the window's)
  /// Each pair's round: a closure's (closure_rounds), or kAlone (Tentative::set_aside).
  std::array<std::uint8_t, B::kMaxObservations> round{};
  bool alone = false;  ///< some pair is held alone

  /// A scan begins: no closure, no pair held alone (the rounds are written before they are read).
  void clear() {
    close.commit = false;
    alone = false;
  }

  /// The plan applied to the filter. @return kOk; the statuses of the first round's update (then the
  /// filter is as it was: the closure's inflation undone). A later round or a pair held alone that
  /// the filter refuses is skipped (its pairs stay unused), as update() skips a block after its first.
  [[gnu::noinline]] Status apply(const Observations<T, B>& obs, const Association<T, B>& assoc, ekf::Slam<T, B>& slam,
                                 ekf::SlamWorkspace<T, B>& ws) const {
    const bool closing = close.commit;
    const Mat3<T> before = slam.pose_covariance();
    Status st = closing ? slam.inflate_pose(close.Q) : Status::kOk;
    if (st != Status::kOk) return st;
    const bool rounds = closing || alone;
    st = slam.update(obs, assoc, ws, closing ? &close.at : nullptr, rounds ? round.data() : nullptr, 0);
    if (st != Status::kOk) {
      // Undone: the pose block as it was (it was positive definite, the write cannot fail).
      if (closing) (void)slam.replace_pose_covariance(before);
      return st;
    }
    for (int r = 1; r < kClosureRounds && closing; ++r) {  // <= kClosureRounds
      (void)slam.update(obs, assoc, ws, nullptr, round.data(), r);
    }
    for (int i = 0; i < obs.count && alone; ++i) {  // <= kMaxObservations
      if (round[static_cast<std::size_t>(i)] != kAlone) continue;
      const int j = slam.index_of(assoc.feature[i]);
      T d2 = T(0);
      if (j >= 0) (void)slam.update_alone(j, obs.z[i], obs.R[i], ws, d2);
    }
    return Status::kOk;
  }
};

}  // namespace geojcbb::node
