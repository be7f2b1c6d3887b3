/* core: every option of one SLAM step (association and filter), described once. C and C++ both read
 * this table (an X-macro, as nanopb's FIELDLIST): the C++ settings struct, its defaults and range
 * checks (core/settings.hpp), the C struct and its defaults (geojcbb.h), the Python keyword
 * arguments, the command-line options of geojcbb_eval, the options table of docs/options.md and the
 * wire's CONFIG (protocol/messages.hpp: one field per line, in this order, its wire type from TYPE)
 * all come from it. It lives beside the protocol, which sees only the standard library and this
 * table (as the stage table, protocol/stage_counts.h); the firmware library reads it from there.
 *
 * X(TYPE, name, default, RANGE, unit, cli, meaning)
 *   TYPE     STRATEGY (enum Strategy), F64 (double), REAL (the scalar T of the C++ templates; float in
 *            C), F32 (float), INT (int), U32 (uint32_t), BOOL (bool; int in C)
 *   RANGE    (kind, lo, hi): ANY; GT x > lo; GE x >= lo; OPEN lo < x < hi; LOPEN lo < x <= hi;
 *            ROPEN lo <= x < hi; CLOSED lo <= x <= hi. Capacity limits (groups, node budget, RJC
 *            subset) are checked against the Bounds in make_strategy, besides. 3.1415927410125732 is
 *            pi rounded up to float, so that float pi is in the range.
 *   cli      the geojcbb_eval option ("": the host derives the value, see docs/options.md); a BOOL
 *            gets --name and --no-name
 * A new option is one line here and the stage that reads it; CONFIG carries it (a new field: the
 * schema hash changes, and a host and a device of different tables refuse each other at HELLO). */
#ifndef GEOJCBB_CORE_OPTIONS_H
#define GEOJCBB_CORE_OPTIONS_H

/* clang-format off */
#define GEOJCBB_OPTIONS(X) \
  X(STRATEGY, strategy, 5, (CLOSED, 0, 6), "", "", \
    "association preset: 0 ICNN, 1 JCBB, 2 KJCBB, 3 DFJCBB, 4 GEMJCBB, 5 GEOJCBB, 6 PCJCBB") \
  X(F64, confidence, 0.99, (OPEN, 0, 1), "", "--confidence", \
    "chi-square level of the individual and joint compatibility tests") \
  X(F64, new_landmark_level, 0.999, (OPEN, 0, 1), "", "--new-landmark-gate", \
    "chi-square level (2 dof) an unpaired observation's nearest d2 must exceed to become a landmark") \
  X(REAL, local_radius_m, 10, (GT, 0, 0), "m", "", \
    "local region r + d (2019 paper, eq. 5); the host sets the sensor's range + --compensation") \
  X(INT, groups, 3, (CLOSED, 0, 255), "", "--groups", \
    "K for k-means and GMM-EM, at most the capacity's MaxGroups (0: GMM-EM chooses K by BIC)") \
  X(BOOL, condition_groups, 0, (ANY, 0, 0), "", "--condition-groups", \
    "search the groups one after another, each conditioned on the earlier groups' pairings") \
  X(REAL, dbscan_eps_m, 1.5, (GT, 0, 0), "m", "--dbscan-eps", "DBSCAN neighbourhood radius") \
  X(INT, dbscan_min_points, 2, (CLOSED, 1, 255), "", "--dbscan-min-points", \
    "DBSCAN core-point threshold (the point itself included)") \
  X(U32, node_budget, 0, (GE, 0, 0), "nodes", "--node-budget", \
    "JCBB interpretation-tree nodes per scan, at most the capacity's MaxJcbbNodes (0: that capacity)") \
  X(REAL, min_range_m, 0, (GE, 0, 0), "m", "", \
    "nearest range at which a mapped landmark is expected (host: sensor's + --view-margin)") \
  X(REAL, max_range_m, 10, (GT, 0, 0), "m", "", \
    "farthest range at which a mapped landmark is expected, > min_range_m (host: sensor's - --view-margin)") \
  X(REAL, half_fov_rad, 3.14159265358979, (LOPEN, 0, 3.1415927410125732), "rad", "", \
    "half the bearing span in which a mapped landmark is expected (host: half the FOV less 3 sigma)") \
  X(REAL, sensor_x_m, 0, (CLOSED, -100, 100), "m", "--sensor-x", \
    "where the sensor sits on the robot: ahead of the point the motion model moves") \
  X(REAL, sensor_y_m, 0, (CLOSED, -100, 100), "m", "--sensor-y", "where the sensor sits on the robot: to the left") \
  X(REAL, sensor_theta_rad, 0, (CLOSED, -3.1415927410125732, 3.1415927410125732), "rad", "--sensor-heading", \
    "the sensor's heading on the robot (its bearing 0 in the body frame)") \
  X(F32, landmark_confirm_nats, 4.6, (OPEN, 0, 1e6), "nats", "--confirm-nats", \
    "log-odds of existence (+log(pD/pFA) per pairing, +log((1-pD)/(1-pFA)) per miss) that confirms a landmark") \
  X(F32, landmark_delete_nats, -4, (OPEN, -1e6, 0), "nats", "--delete-nats", \
    "log-odds of existence at or below which a landmark, confirmed or not, is removed (a new one starts at 0)") \
  X(F32, landmark_reserve_nats, 1000, (GE, 0, 0), "nats", "--reserve-nats", \
    "log-odds of existence a landmark holds at most beyond landmark_confirm_nats (MRCLAM's rules: 4.6; 1000: kept)") \
  X(INT, max_tentative_reviews, 10, (CLOSED, 1, 255), "", "--max-tentative-reviews", \
    "reviews a landmark may stay tentative (below landmark_confirm_nats) before it is removed") \
  X(BOOL, tentative_isolated, 0, (ANY, 0, 0), "", "--tentative-isolated", \
    "tentative landmarks are paired after the association, one observation each, and update only themselves") \
  X(BOOL, joint_recheck, 1, (ANY, 0, 0), "", "--joint-recheck", \
    "test the union of the groups' answers jointly and keep its largest jointly compatible subset") \
  X(F64, ambiguity_margin, 0, (ROPEN, 0, 1e6), "", "--ambiguity-margin", \
    "decline: pairings a runner-up within this joint d2 makes differently are left unmatched (0: off)") \
  X(BOOL, new_if_candidates_taken, 0, (ANY, 0, 0), "", "--new-if-taken", \
    "with mutual exclusion, an observation whose compatible features are all taken is new, not unmatched") \
  X(BOOL, verify, 0, (ANY, 0, 0), "", "--verify", \
    "keep the answer's largest pairwise consistent subset (pose-free; PCJCBB: always on)") \
  X(BOOL, full_covariance_check, 0, (ANY, 0, 0), "", "--full-covariance-check", \
    "check every entry of C before the stages (O(n^2)) instead of each where a stage reads it") \
  X(BOOL, papers_em, 0, (ANY, 0, 0), "", "--papers-em", \
    "GMM-EM as the papers: farthest-first start, objective-tolerance stop (off: k-means start, stable stop)") \
  X(REAL, seed_min_position_var_m2, 4, (GT, 0, 0), "m^2", "--seed-min-var", \
    "PCJCBB seeds with the pose-free clique when the best-placed candidate's position variance is this") \
  X(REAL, consistency_wide_d2, 23.025850929940457, (GT, 0, 0), "", "--consistency-wide-d2", \
    "individual d2 of a consistency-graph node, chi2inv(0.99999, 2)") \
  X(REAL, consistency_pair_d2, 10.827566170662733, (GT, 0, 0), "", "--consistency-pair-d2", \
    "pairwise distance test of the consistency graph, chi2inv(0.999, 1)") \
  X(BOOL, rjc, 0, (ANY, 0, 0), "", "--rjc", \
    "randomized joint compatibility for scans with more than rjc_subset compatible observations (JCBB)") \
  X(INT, rjc_tries, 8, (CLOSED, 1, 64), "", "--rjc-tries", "RJC tries, each with node_budget / rjc_tries nodes") \
  X(INT, rjc_subset, 8, (CLOSED, 1, 255), "", "--rjc-subset", \
    "observations searched by JCBB in an RJC try, at most the capacity's MaxObservations") \
  X(REAL, occlusion_rad, 0, (CLOSED, 0, 3.1415927410125732), "rad", "--occlusion", \
    "a landmark with a nearer one within this bearing is hidden, so not expected (0: off)") \
  X(F64, static_gate_level, 0, (ROPEN, 0, 1), "", "--static-gate-level", \
    "remove a landmark whose estimate leaves, at this chi-square level, where it was added (0: off)") \
  X(F64, motion_false_alarm, 0, (ROPEN, 0, 1), "", "--motion-false-alarm", \
    "the motion test's false-alarm rate per pairing: a landmark whose innovations keep one direction becomes a mover (0: off)") \
  X(F32, detection_floor, 0, (CLOSED, 0, 1), "", "--detection-floor", \
    "a miss counts against a landmark only where its p_D is at least this (0: every miss)") \
  X(BOOL, learn_detection, 0, (ANY, 0, 0), "", "--learn-detection", \
    "p_D per range bin learned from the confirmed landmarks in view (prior: loop_detection_probability)") \
  X(BOOL, learn_clutter, 0, (ANY, 0, 0), "", "--learn-clutter", \
    "the clutter density learned from each scan's unexplained observations (prior: loop_unexplained_density)") \
  X(BOOL, first_estimates_jacobians, 1, (ANY, 0, 0), "", "--fej", \
    "first-estimates Jacobians (off: every Jacobian at the current estimate); applied at the next reset") \
  X(BOOL, augment, 1, (ANY, 0, 0), "", "", \
    "add new landmarks (off: a known, fixed map; the host sets it with --known-map)") \
  X(BOOL, relocalise, 0, (ANY, 0, 0), "", "--relocalise", \
    "when lost (told, or reloc_lost_nats), align each scan against the map with the pose prior and resume at a unique, confirmed pose") \
  X(INT, reloc_min_inliers, 5, (CLOSED, 3, 255), "", "--reloc-min-inliers", \
    "landmarks an aligned pose must explain, and a confirming scan pair") \
  X(REAL, reloc_margin_nats, 10, (GE, 0, 0), "nats", "--reloc-margin", \
    "log posterior (set likelihood + log prior) by which an aligned pose must lead the best distinct pose") \
  X(INT, reloc_base_pairs, 4, (CLOSED, 1, 8), "", "--reloc-base-pairs", \
    "observed pairs (the longest) whose matches in the map are tried per lost scan") \
  X(REAL, reloc_inflation, 4, (GE, 1, 0), "", "--reloc-inflation", \
    "the aligned pose's covariance is the fit's times this (the scan is then used again in the update)") \
  X(INT, reloc_confirm_scans, 1, (CLOSED, 0, 16), "", "--reloc-confirm-scans", \
    "scans after the relocalisation that must pair reloc_min_inliers landmarks before the robot is found") \
  X(REAL, reloc_lost_nats, 20, (GE, 0, 0), "nats", "--reloc-lost-nats", \
    "the pose is doubted (aligned pose-free) when the scans' evidence against it, summed (CUSUM), passes this (0: off)") \
  X(BOOL, loop_check, 0, (ANY, 0, 0), "", "--loop-check", \
    "score a closure with old landmarks against a pose-free alignment; commit only a unique, confirmed winner") \
  X(INT, loop_age, 100, (CLOSED, 1, 255), "scans", "--loop-age", \
    "a confirmed landmark is old (a closure's) when it has not been paired for this many scans") \
  X(INT, loop_min_inliers, 3, (CLOSED, 3, 255), "", "--loop-min-inliers", \
    "old landmarks the alignment's pose must explain (reloc_margin_nats and reloc_base_pairs as the relocaliser's)") \
  X(REAL, loop_margin_nats, 3, (GE, 0, 0), "nats", "--loop-margin", \
    "set log-likelihood by which the alignment's closure must beat the association's") \
  X(INT, loop_confirm_scans, 2, (CLOSED, 1, 16), "", "--loop-confirm-scans", \
    "scans in a row the alignment's closure must win, with the same correction, before it is committed") \
  X(REAL, loop_inflation, 4, (GE, 1, 0), "", "--loop-inflation", \
    "a committed closure grows the pose block by this times (the correction squared + the fit's covariance)") \
  X(REAL, loop_detection_probability, 0.9, (OPEN, 0, 1), "", "--loop-pd", \
    "p_D: a landmark in view is observed (set likelihood: relocaliser, loop check, window, lost test; existence)") \
  X(REAL, loop_unexplained_density, 0.003, (GT, 0, 0), "1/m^2", "--loop-density", \
    "observations per m^2 no landmark explains (clutter, newer landmarks): set likelihood; existence's pFA") \
  X(REAL, duplicate_merge_d2, 0, (GE, 0, 0), "", "--duplicate-merge-d2", \
    "two landmarks never observed in one scan whose difference d2 is below this are one: merged (0: off)") \
  X(INT, hypothesis_rivals, 0, (CLOSED, 0, 2), "", "--hypothesis-rivals", \
    "pose hypotheses kept beside the best while a scan is ambiguous, each scored on the scans after (0: off)") \
  X(INT, hypothesis_window_scans, 5, (CLOSED, 1, 32), "scans", "--hypothesis-window", \
    "scans a window of hypotheses lasts at most; ended without a leader, it commits nothing") \
  X(REAL, hypothesis_margin_nats, 3, (GT, 0, 0), "nats", "--hypothesis-margin", \
    "set log-likelihood by which a hypothesis must lead every other to be committed (and rivals open a window)") \
  X(BOOL, hypothesis_hold, 0, (ANY, 0, 0), "", "--hypothesis-hold", \
    "while a window is open, hold the observations its hypotheses pair differently (off: the association's stand)") \
  X(BOOL, cluster_first, 0, (ANY, 0, 0), "", "--cluster-first", \
    "pair each cluster of observations (within dbscan_eps_m) as a unit first, its members at that posterior") \
  X(BOOL, evict_when_full, 0, (ANY, 0, 0), "", "--evict-when-full", \
    "a full map makes room for a new landmark: the least-seen landmark beyond r + d goes (the farthest of equals)") \
  X(U32, submap_landmarks, 0, (CLOSED, 0, 32767), "", "--submap-landmarks", \
    "the local map is closed (handed over, the next begun at the robot) after a scan that leaves it this many landmarks (0: off)") \
  X(REAL, submap_distance_m, 0, (GE, 0, 0), "m", "--submap-distance", \
    "the local map is closed after a scan once the robot has travelled this far in it (0: off)") \
  X(U32, submap_scans, 0, (CLOSED, 0, 1000000), "scans", "--submap-scans", \
    "the local map is closed after this many scans (0: off)") \
  X(BOOL, submap_carry, 1, (ANY, 0, 0), "", "--submap-carry", \
    "the next local map begins with the closed one's confirmed landmarks of the local region, in its frame (off: empty)")
/* clang-format on */

#endif /* GEOJCBB_CORE_OPTIONS_H */
