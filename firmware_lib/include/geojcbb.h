/* geojcbb C API (C99): the float association pipeline and the EKF-SLAM step at the default bounds
 * (24 observations per scan, 32 candidates, 5 groups, 4000 JCBB nodes, 96 landmarks), for C
 * firmware. Inputs and outputs are plain arrays and structs; all working memory is a buffer the
 * caller provides (typically static) of GEOJCBB_*_STORAGE_SIZE bytes aligned to
 * GEOJCBB_STORAGE_ALIGN. No heap, no exceptions escape, nothing is printed. Every call returns a
 * geojcbb_status and writes its outputs only on GEOJCBB_OK. docs/c_api.md.
 * Implementation: firmware_lib/src/c_api.cpp (compiled into geojcbb::pipeline_f32). */
#ifndef GEOJCBB_H
#define GEOJCBB_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Capacities (geojcbb::DefaultBounds). */
#define GEOJCBB_MAX_OBSERVATIONS 24
#define GEOJCBB_MAX_CANDIDATES 32
#define GEOJCBB_MAX_GROUPS 5
#define GEOJCBB_MAX_JCBB_NODES 4000
#define GEOJCBB_MAX_LANDMARKS 96

/* Per-observation answers besides a feature id (>= 0). */
#define GEOJCBB_NEW_FEATURE (-1) /* nothing compatible: a new landmark (or clutter) */
#define GEOJCBB_UNMATCHED (-2)   /* compatible candidates, left unpaired (ambiguous) */

/* Caller-provided storage: sizes in bytes, and the alignment both need. The implementation checks
 * at compile time that these equal the sizes of the objects it places there, and at run time that
 * the buffer given is large and aligned enough. Declare storage as, for example:
 *   static GEOJCBB_ALIGNED_STORAGE(assoc_mem, GEOJCBB_ASSOCIATOR_STORAGE_SIZE);  */
#define GEOJCBB_STORAGE_ALIGN 16
#define GEOJCBB_ASSOCIATOR_STORAGE_SIZE 28384
#define GEOJCBB_SLAM_STORAGE_SIZE 115520
/* C99 has no alignas: GCC and Clang's aligned attribute does it (the union's members give what the
 * ABI aligns anyway to other compilers, which can align a buffer their own way); the init calls
 * check the address in any case. */
#define GEOJCBB_ALIGNED_STORAGE(name, size) \
  union {                                   \
    unsigned char bytes[size];              \
    long double align_ld;                   \
    double align_d;                         \
    uint64_t align_u64;                     \
  } name /* NOLINT(bugprone-macro-parentheses): a declarator */ __attribute__((aligned(GEOJCBB_STORAGE_ALIGN)))

/* Mirrors geojcbb::Status (core/status.hpp), value for value. */
typedef enum geojcbb_status {
  GEOJCBB_OK = 0,
  GEOJCBB_NON_FINITE = 1,            /* a NaN or Inf in an input */
  GEOJCBB_INVALID_INPUT = 2,         /* a value outside its domain, a bad count or option, bad storage */
  GEOJCBB_CAPACITY_EXCEEDED = 3,     /* a count over a capacity above */
  GEOJCBB_NOT_SYMMETRIC = 4,         /* a covariance that is not symmetric */
  GEOJCBB_NOT_POSITIVE_DEFINITE = 5, /* a covariance that is not positive (semi)definite */
  GEOJCBB_NO_CONVERGENCE = 6         /* an iterative solver ran out of its iteration bound */
} geojcbb_status;

/* Short stable name of a status ("ok", "non-finite", ...). */
const char* geojcbb_status_name(geojcbb_status s);

/* Mirrors geojcbb::Strategy (core/strategy.hpp). */
typedef enum geojcbb_strategy {
  GEOJCBB_STRATEGY_ICNN = 0,
  GEOJCBB_STRATEGY_JCBB = 1,
  GEOJCBB_STRATEGY_KJCBB = 2,
  GEOJCBB_STRATEGY_DFJCBB = 3,
  GEOJCBB_STRATEGY_GEMJCBB = 4,
  GEOJCBB_STRATEGY_GEOJCBB = 5,
  GEOJCBB_STRATEGY_PCJCBB = 6 /* GEOJCBB + pairwise verify and pose-free seed (docs/consistency.md) */
} geojcbb_strategy;

/* Mirrors geojcbb::StrategyParams<float>; geojcbb_strategy_params_default() fills the defaults. */
typedef struct geojcbb_strategy_params {
  double confidence;           /* chi-square level of the individual and joint tests (0.99) */
  float local_radius_m;        /* r + d [m] (eq. 5); > 0 for GEMJCBB and GEOJCBB */
  int groups;                  /* K for k-means and GMM-EM (3); 0: BIC (EM) */
  float dbscan_eps_m;          /* DBSCAN radius [m] (1.5) */
  int dbscan_min_points;       /* (2) */
  int joint_recheck;           /* bool (1) */
  int condition_groups;        /* bool (0) */
  uint32_t node_budget;        /* 0: GEOJCBB_MAX_JCBB_NODES */
  double ambiguity_margin;     /* 0: off */
  int new_if_candidates_taken; /* bool (0) */
  int verify;                  /* bool (0): pairwise verification in any preset (PCJCBB: always) */
} geojcbb_strategy_params;

void geojcbb_strategy_params_default(geojcbb_strategy_params* p);

/* Mirrors geojcbb::AssociationDiagnostics. */
typedef struct geojcbb_diagnostics {
  uint32_t jcbb_nodes;
  uint16_t candidates_in_region;
  uint16_t compatible_pairs;
  uint8_t node_budget_hit; /* bool */
  uint8_t groups;
  uint16_t cluster_iterations;
  uint8_t cluster_bound_hit; /* bool */
  uint16_t merge_conflicts;
  uint8_t recheck_failed; /* bool */
  uint16_t recheck_dropped;
  uint16_t declined;
} geojcbb_diagnostics;

/* Mirrors geojcbb::Association<float, DefaultBounds>. */
typedef struct geojcbb_association {
  int count;                                   /* = number of observations */
  int32_t feature[GEOJCBB_MAX_OBSERVATIONS];   /* feature id, GEOJCBB_NEW_FEATURE or GEOJCBB_UNMATCHED */
  int16_t candidate[GEOJCBB_MAX_OBSERVATIONS]; /* index of the paired candidate, or -1 */
  float d2[GEOJCBB_MAX_OBSERVATIONS];          /* individual d2 (unpaired: the nearest, or +inf) */
  int pairings;
  float joint_d2;         /* joint Mahalanobis distance of the hypothesis */
  int jointly_compatible; /* bool */
  geojcbb_diagnostics diag;
} geojcbb_association;

/* ---- Association ---- */
typedef struct geojcbb_associator geojcbb_associator; /* opaque: lives in the caller's storage */

/* Places an associator configured with a strategy in `storage` (size bytes, GEOJCBB_STORAGE_ALIGN
 * aligned). @return OK; INVALID_INPUT for null pointers, a small or misaligned buffer, or bad
 * parameters; the statuses of make_strategy. *out is set only on OK. */
geojcbb_status geojcbb_associator_init(void* storage, size_t size, geojcbb_strategy strategy,
                                       const geojcbb_strategy_params* params, geojcbb_associator** out);

/* One association call.
 *   m   observations: z[2m] = (range [m], bearing [rad]) pairs, R[4m] = 2x2 row-major [m^2, rad^2]
 *   n   candidates: ids[n] (>= 0), h[2n] = predicted (range, bearing), C[(2n)^2] = H P H^T,
 *       row-major, candidate j at rows 2j, 2j+1
 * @return OK; CAPACITY_EXCEEDED for m or n over capacity; the statuses of associate() (its
 * validation, NOT_POSITIVE_DEFINITE). *out is written only on OK. */
geojcbb_status geojcbb_associate(geojcbb_associator* handle, int m, const float* z, const float* R, int n,
                                 const int32_t* ids, const float* h, const float* C, geojcbb_association* out);

/* ---- EKF-SLAM step (geojcbb::node::SlamStep<float, DefaultBounds>) ---- */
typedef struct geojcbb_slam geojcbb_slam; /* opaque: lives in the caller's storage */

/* Mirrors node::StepSettings<float>; geojcbb_slam_settings_default() fills the defaults. */
typedef struct geojcbb_slam_settings {
  geojcbb_strategy strategy;      /* (GEOJCBB) */
  geojcbb_strategy_params params; /* params.local_radius_m must be > 0 */
  double new_landmark_level;      /* chi-square level of the augmentation gate (0.999) */
  float min_range_m, max_range_m; /* where a mapped landmark is expected to be seen */
  float half_fov_rad;
  int confirm_hits, max_misses, max_tentative_reviews; /* landmark life cycle (ekf::LandmarkPolicy) */
  float miss_probability, static_gate_d2;
  int first_estimates_jacobians; /* bool (1) */
  int augment;                   /* bool (1): add new landmarks */
} geojcbb_slam_settings;

void geojcbb_slam_settings_default(geojcbb_slam_settings* s);

/* Mirrors node::Outcome. */
typedef enum geojcbb_outcome {
  GEOJCBB_OUTCOME_PAIRED = 0,
  GEOJCBB_OUTCOME_NEW_LANDMARK = 1,
  GEOJCBB_OUTCOME_NEW_DROPPED = 2,
  GEOJCBB_OUTCOME_UNMATCHED = 3,
  GEOJCBB_OUTCOME_NOT_AUGMENTED = 4
} geojcbb_outcome;

typedef struct geojcbb_step_result {
  int count;
  uint8_t outcome[GEOJCBB_MAX_OBSERVATIONS]; /* geojcbb_outcome */
  int32_t feature[GEOJCBB_MAX_OBSERVATIONS]; /* landmark id, -1 when none */
  float d2[GEOJCBB_MAX_OBSERVATIONS];
  geojcbb_diagnostics diag;
} geojcbb_step_result;

/* Places an unconfigured SLAM step in `storage`. @return OK; INVALID_INPUT for bad storage. */
geojcbb_status geojcbb_slam_init(void* storage, size_t size, geojcbb_slam** out);
/* @return OK; INVALID_INPUT for bad settings; the statuses of make_strategy. */
geojcbb_status geojcbb_slam_configure(geojcbb_slam* handle, const geojcbb_slam_settings* settings);
/* Clears the map. x0 = (x [m], y [m], theta [rad]); P0 3x3 row-major. */
geojcbb_status geojcbb_slam_reset(geojcbb_slam* handle, const float x0[3], const float P0[9]);
/* One odometry interval: v [m/s], w [rad/s], dt [s] >= 0, their standard deviations (> 0). */
geojcbb_status geojcbb_slam_predict(geojcbb_slam* handle, float v_mps, float w_radps, float dt_s, float sigma_v_mps,
                                    float sigma_w_radps);
/* One scan (z, R as in geojcbb_associate). *out is written only on OK. */
geojcbb_status geojcbb_slam_step(geojcbb_slam* handle, int m, const float* z, const float* R, geojcbb_step_result* out);
/* The pose estimate (x, y, theta) and the map. */
void geojcbb_slam_pose(const geojcbb_slam* handle, float x[3]);
int geojcbb_slam_landmarks(const geojcbb_slam* handle);
/* Landmark j (0 <= j < geojcbb_slam_landmarks()): its id and position [m]. INVALID_INPUT for a bad j. */
geojcbb_status geojcbb_slam_landmark(const geojcbb_slam* handle, int j, int32_t* id, float xy[2]);

#ifdef __cplusplus
}
#endif

#endif /* GEOJCBB_H */
