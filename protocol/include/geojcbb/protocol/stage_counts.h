/* protocol: the stages of a SLAM step the device times, described once, in wire order. One row per
 * stage: node::StageCounts holds one counter per row (node/step_result.hpp), STATS carries each as
 * instr_<name> (messages.hpp), node::Node copies one into the other, and the instruction-budget tool
 * (geojcbb_qemu --budget) reads them. A new timed stage is one line here and the line that times it.
 *
 * X(name, meaning); counts come from the clock the caller supplies (instructions under QEMU's
 * -icount, DWT CYCCNT on a board), 0 without one. */
#ifndef GEOJCBB_PROTOCOL_STAGE_COUNTS_H
#define GEOJCBB_PROTOCOL_STAGE_COUNTS_H

/* clang-format off */
#define GEOJCBB_STAGE_COUNTS(X) \
  X(predict_local, "the local region's prediction (eq. 5) of the last scan") \
  X(associate, "the association") \
  X(update, "the filter's update") \
  X(augment_review, "new landmarks and the map's review") \
  X(existence, "the landmarks' existence update (log-odds of detections and misses), inside augment_review") \
  X(relocalise, "the relocaliser's alignment: 0 unless the robot was lost") \
  X(loop, "the loop-closure check: 0 when it did not run") \
  X(window, "clusters first and the hypothesis window: 0 when they did not run") \
  X(lost_test, "the lost test's evidence at the tracked pose: 0 unless the relocaliser is on and tracking") \
  X(score, "the posterior scoring (set likelihood) of the alignment, loop check and window, inside their rows") \
  X(step, "the whole step")
/* clang-format on */

#endif
