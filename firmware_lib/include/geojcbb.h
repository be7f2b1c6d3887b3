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

#include "geojcbb/core/diagnostics.h"
#include "geojcbb/core/options.h"

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
#define GEOJCBB_ASSOCIATOR_STORAGE_SIZE 28816
#define GEOJCBB_SLAM_STORAGE_SIZE 125232
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
  /* JCBB over every candidate (no grouping, no local region) with GEOJCBB's mutual exclusion and optimal
   * criterion; its answer verified by pose-free pairwise consistency (a maximum clique of pairings whose
   * pairwise distances agree) and seeded by that clique when the pose is very uncertain
   * (docs/consistency.md) */
  GEOJCBB_STRATEGY_PCJCBB = 6
} geojcbb_strategy;

/* The settings of one SLAM step (association and filter): one member per line of the option table
 * (geojcbb/core/options.h: type, default, range, meaning), generated from it, as is the C++
 * geojcbb::StepSettings<float>. geojcbb_settings_default() fills the table's defaults. Types: REAL and
 * F32 are float, F64 double, INT int, U32 uint32_t, BOOL int (0 or 1). */
#define GEOJCBB_C_TYPE_STRATEGY geojcbb_strategy
#define GEOJCBB_C_TYPE_F64 double
#define GEOJCBB_C_TYPE_REAL float
#define GEOJCBB_C_TYPE_F32 float
#define GEOJCBB_C_TYPE_INT int
#define GEOJCBB_C_TYPE_U32 uint32_t
#define GEOJCBB_C_TYPE_BOOL int
#define GEOJCBB_C_MEMBER(TYPE, name, def, range, unit, cli, doc) GEOJCBB_C_TYPE_##TYPE name;
typedef struct geojcbb_settings {
  GEOJCBB_OPTIONS(GEOJCBB_C_MEMBER)
} geojcbb_settings;
#undef GEOJCBB_C_MEMBER

void geojcbb_settings_default(geojcbb_settings* s);

/* Mirrors geojcbb::AssociationDiagnostics: one member per line of core/diagnostics.h (a bool as
 * uint8_t 0/1). */
#define GEOJCBB_C_DIAG_U32 uint32_t
#define GEOJCBB_C_DIAG_U16 uint16_t
#define GEOJCBB_C_DIAG_U8 uint8_t
#define GEOJCBB_C_DIAG_BOOL uint8_t
#define GEOJCBB_C_DIAG_MEMBER(TYPE, name, doc) GEOJCBB_C_DIAG_##TYPE name;
typedef struct geojcbb_diagnostics {
  GEOJCBB_DIAGNOSTICS(GEOJCBB_C_DIAG_MEMBER)
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

/* Places an associator configured with settings->strategy and the settings' association options
 * in `storage` (size bytes, GEOJCBB_STORAGE_ALIGN aligned).
 * @return OK; INVALID_INPUT for null pointers, a small or misaligned buffer, or bad parameters; the
 * statuses of make_strategy. *out is set only on OK (a refused configuration leaves the storage
 * holding no usable associator). */
geojcbb_status geojcbb_associator_init(void* storage, size_t size, const geojcbb_settings* settings,
                                       geojcbb_associator** out);

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

/* Mirrors node::Outcome. */
typedef enum geojcbb_outcome {
  GEOJCBB_OUTCOME_PAIRED = 0,
  GEOJCBB_OUTCOME_NEW_LANDMARK = 1,
  GEOJCBB_OUTCOME_NEW_DROPPED = 2,
  GEOJCBB_OUTCOME_UNMATCHED = 3,
  GEOJCBB_OUTCOME_NOT_AUGMENTED = 4,
  GEOJCBB_OUTCOME_MOVER = 5
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
geojcbb_status geojcbb_slam_configure(geojcbb_slam* handle, const geojcbb_settings* settings);
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
