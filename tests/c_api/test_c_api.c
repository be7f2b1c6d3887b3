/* The C API from C99: every strategy on generated scenes answers bit for bit as the C++ float
 * pipeline (reference.cpp) does; a SLAM run through the C API follows the C++ SlamStep bit for bit;
 * bad storage and bad inputs give their statuses. Exit status 0 on success. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "geojcbb.h"

int ref_associate(const geojcbb_settings* p, int m, const float* z, const float* R, int n, const int32_t* ids,
                  const float* h, const float* C, int32_t* feature, float* d2, float* joint_d2, int* pairings,
                  uint32_t* nodes);
int ref_slam_start(const geojcbb_settings* st, const float x0[3], const float P0[9]);
int ref_slam_predict(float v, float w, float dt, float sv, float sw);
int ref_slam_step(int m, const float* z, const float* R, int32_t* feature, uint8_t* outcome, float pose[3]);

static GEOJCBB_ALIGNED_STORAGE(assoc_mem, GEOJCBB_ASSOCIATOR_STORAGE_SIZE);
static GEOJCBB_ALIGNED_STORAGE(slam_mem, GEOJCBB_SLAM_STORAGE_SIZE);

static int failures = 0;
#define CHECK(cond)                                                            \
  do {                                                                         \
    if (!(cond)) {                                                             \
      ++failures;                                                              \
      fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #cond); \
    }                                                                          \
  } while (0)

static uint32_t rng_state = 12345u;
static double uniform(void) { /* xorshift32 in [0, 1) */
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 17;
  rng_state ^= rng_state << 5;
  return (double)rng_state / 4294967296.0;
}
static double gauss(void) {
  double u1 = uniform() + 1e-12, u2 = uniform();
  return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}
static double wrap(double a) {
  while (a > 3.141592653589793) a -= 6.283185307179586;
  while (a <= -3.141592653589793) a += 6.283185307179586;
  return a;
}

/* A scene: n landmarks around the robot (pose uncertain by sp), C = J Pp J^T + sl^2 I, and m
 * observations: true landmarks seen with noise, plus clutter. */
typedef struct scene {
  int m, n;
  float z[2 * GEOJCBB_MAX_OBSERVATIONS], R[4 * GEOJCBB_MAX_OBSERVATIONS];
  int32_t ids[GEOJCBB_MAX_CANDIDATES];
  float h[2 * GEOJCBB_MAX_CANDIDATES];
  float C[4 * GEOJCBB_MAX_CANDIDATES * GEOJCBB_MAX_CANDIDATES];
} scene;

static void make_scene(scene* s, int n, int m) {
  double lx[GEOJCBB_MAX_CANDIDATES], ly[GEOJCBB_MAX_CANDIDATES], J[2 * GEOJCBB_MAX_CANDIDATES][3];
  const double sp[3] = {0.05, 0.05, 0.01}, sr = 0.05, sb = 0.01, sl = 0.03;
  int j, i, r, c;
  s->n = n;
  s->m = m;
  for (j = 0; j < n; ++j) {
    double rr, b;
    lx[j] = -10.0 + 20.0 * uniform();
    ly[j] = -10.0 + 20.0 * uniform();
    rr = sqrt(lx[j] * lx[j] + ly[j] * ly[j]) + 0.5;
    b = atan2(ly[j], lx[j]);
    s->ids[j] = 100 + j;
    s->h[2 * j] = (float)rr;
    s->h[2 * j + 1] = (float)b;
    /* d(range, bearing)/d(x, y, theta) of the robot at the origin */
    J[2 * j][0] = -lx[j] / rr;
    J[2 * j][1] = -ly[j] / rr;
    J[2 * j][2] = 0.0;
    J[2 * j + 1][0] = ly[j] / (rr * rr);
    J[2 * j + 1][1] = -lx[j] / (rr * rr);
    J[2 * j + 1][2] = -1.0;
  }
  for (r = 0; r < 2 * n; ++r)
    for (c = 0; c < 2 * n; ++c) {
      double v = 0.0;
      int k;
      for (k = 0; k < 3; ++k) v += J[r][k] * sp[k] * sp[k] * J[c][k];
      if (r == c) v += sl * sl;
      s->C[r * 2 * n + c] = (float)v;
    }
  for (r = 0; r < 2 * n; ++r) /* exactly symmetric in float */
    for (c = 0; c < r; ++c) s->C[r * 2 * n + c] = s->C[c * 2 * n + r];
  for (i = 0; i < m; ++i) {
    if (i < n && uniform() < 0.8) {
      s->z[2 * i] = (float)(s->h[2 * i] + sr * gauss());
      s->z[2 * i + 1] = (float)wrap(s->h[2 * i + 1] + sb * gauss());
    } else {
      s->z[2 * i] = (float)(1.0 + 12.0 * uniform());
      s->z[2 * i + 1] = (float)wrap(6.283185307179586 * uniform());
    }
    s->R[4 * i] = (float)(sr * sr);
    s->R[4 * i + 1] = 0.f;
    s->R[4 * i + 2] = 0.f;
    s->R[4 * i + 3] = (float)(sb * sb);
  }
}

static int same_bits(const void* a, const void* b, size_t n) { return memcmp(a, b, n) == 0; }

static void test_strategies_bit_for_bit(void) {
  static scene s;
  int strategy, k, compared = 0;
  for (strategy = GEOJCBB_STRATEGY_ICNN; strategy <= GEOJCBB_STRATEGY_PCJCBB; ++strategy) {
    geojcbb_settings p;
    geojcbb_associator* a = NULL;
    geojcbb_settings_default(&p);
    p.strategy = (geojcbb_strategy)strategy;
    p.local_radius_m = 12.f;
    p.verify = strategy == GEOJCBB_STRATEGY_JCBB; /* an option no preset sets, through the C boundary */
    CHECK(geojcbb_associator_init(&assoc_mem, sizeof assoc_mem, &p, &a) == GEOJCBB_OK);
    for (k = 0; k < 40; ++k) {
      geojcbb_association out;
      int32_t feature[GEOJCBB_MAX_OBSERVATIONS];
      float d2[GEOJCBB_MAX_OBSERVATIONS], joint;
      int pairings, rs;
      uint32_t nodes;
      const int n = 1 + (int)(uniform() * GEOJCBB_MAX_CANDIDATES);
      const int m = (int)(uniform() * (GEOJCBB_MAX_OBSERVATIONS + 1));
      geojcbb_status st;
      make_scene(&s, n, m);
      st = geojcbb_associate(a, s.m, s.z, s.R, s.n, s.ids, s.h, s.C, &out);
      rs = ref_associate(&p, s.m, s.z, s.R, s.n, s.ids, s.h, s.C, feature, d2, &joint, &pairings, &nodes);
      CHECK((int)st == rs);
      if (st != GEOJCBB_OK) continue;
      CHECK(out.count == m);
      CHECK(same_bits(out.feature, feature, sizeof(int32_t) * (size_t)m));
      CHECK(same_bits(out.d2, d2, sizeof(float) * (size_t)m));
      CHECK(same_bits(&out.joint_d2, &joint, sizeof joint));
      CHECK(out.pairings == pairings);
      CHECK(out.diag.jcbb_nodes == nodes);
      ++compared;
    }
  }
  CHECK(compared >= 200);
  printf("associate: %d scenes x strategies compared bit for bit with the C++ float pipeline\n", compared);
}

static void test_bad_inputs(void) {
  static scene s;
  static unsigned char small[64];
  geojcbb_settings p;
  geojcbb_associator* a = NULL;
  geojcbb_association out;
  geojcbb_slam* sl = NULL;
  geojcbb_settings_default(&p);
  p.strategy = GEOJCBB_STRATEGY_JCBB;
  CHECK(geojcbb_associator_init(small, sizeof small, &p, &a) == GEOJCBB_INVALID_INPUT);
  CHECK(geojcbb_associator_init(assoc_mem.bytes + 8, sizeof assoc_mem - 8, &p, &a) == GEOJCBB_INVALID_INPUT);
  CHECK(geojcbb_slam_init(slam_mem.bytes, GEOJCBB_SLAM_STORAGE_SIZE - 1, &sl) == GEOJCBB_INVALID_INPUT);
  p.strategy = (geojcbb_strategy)(GEOJCBB_STRATEGY_PCJCBB + 1);
  CHECK(geojcbb_associator_init(&assoc_mem, sizeof assoc_mem, &p, &a) == GEOJCBB_INVALID_INPUT);
  /* GEOJCBB needs r + d > 0 */
  p.strategy = GEOJCBB_STRATEGY_GEOJCBB;
  p.local_radius_m = 0.f;
  CHECK(geojcbb_associator_init(&assoc_mem, sizeof assoc_mem, &p, &a) == GEOJCBB_INVALID_INPUT);
  CHECK(a == NULL);
  /* an option outside its table range */
  p.strategy = GEOJCBB_STRATEGY_JCBB;
  p.local_radius_m = 12.f;
  p.confidence = 1.0;
  CHECK(geojcbb_associator_init(&assoc_mem, sizeof assoc_mem, &p, &a) == GEOJCBB_INVALID_INPUT);
  CHECK(a == NULL);
  p.confidence = 0.99;
  CHECK(geojcbb_associator_init(&assoc_mem, sizeof assoc_mem, &p, &a) == GEOJCBB_OK);
  make_scene(&s, 4, 4);
  out.count = -7;
  CHECK(geojcbb_associate(a, GEOJCBB_MAX_OBSERVATIONS + 1, s.z, s.R, s.n, s.ids, s.h, s.C, &out) ==
        GEOJCBB_CAPACITY_EXCEEDED);
  CHECK(geojcbb_associate(a, s.m, s.z, s.R, GEOJCBB_MAX_CANDIDATES + 1, s.ids, s.h, s.C, &out) ==
        GEOJCBB_CAPACITY_EXCEEDED);
  CHECK(geojcbb_associate(a, s.m, NULL, s.R, s.n, s.ids, s.h, s.C, &out) == GEOJCBB_INVALID_INPUT);
  s.z[0] = (float)NAN;
  CHECK(geojcbb_associate(a, s.m, s.z, s.R, s.n, s.ids, s.h, s.C, &out) == GEOJCBB_NON_FINITE);
  make_scene(&s, 4, 4);
  s.C[1] += 0.5f; /* C(0, 1) != C(1, 0): candidate 0's own block, refused by the validation */
  CHECK(geojcbb_associate(a, s.m, s.z, s.R, s.n, s.ids, s.h, s.C, &out) == GEOJCBB_NOT_SYMMETRIC);
  make_scene(&s, 4, 4);
  s.C[2] += 0.5f; /* C(0, 2) != C(2, 0): a cross block, refused as the dense C is packed (packed covariance) */
  CHECK(geojcbb_associate(a, s.m, s.z, s.R, s.n, s.ids, s.h, s.C, &out) == GEOJCBB_NOT_SYMMETRIC);
  make_scene(&s, 4, 4);
  s.R[0] = -1.f;
  CHECK(geojcbb_associate(a, s.m, s.z, s.R, s.n, s.ids, s.h, s.C, &out) == GEOJCBB_NOT_POSITIVE_DEFINITE);
  CHECK(out.count == -7); /* untouched on every error */
  CHECK(strcmp(geojcbb_status_name(GEOJCBB_NOT_SYMMETRIC), "not-symmetric") == 0);
}

static void test_slam_bit_for_bit(void) {
  static scene s;
  geojcbb_slam* sl = NULL;
  geojcbb_settings st;
  const float x0[3] = {0.f, 0.f, 0.f}, P0[9] = {1e-4f, 0, 0, 0, 1e-4f, 0, 0, 0, 1e-4f};
  int k, i, steps = 0, landmarks_seen = 0;
  geojcbb_settings_default(&st);
  st.local_radius_m = 20.f;       /* every landmark of the scene (ranges up to 15 m) is a candidate */
  st.landmark_delete_nats = -6.f; /* options set through the C boundary reach the step */
  st.static_gate_level = 0.99;
  st.max_range_m = 15.f;
  st.half_fov_rad = 3.14159f;
  CHECK(geojcbb_slam_init(&slam_mem, sizeof slam_mem, &sl) == GEOJCBB_OK);
  CHECK(geojcbb_slam_reset(sl, x0, P0) == GEOJCBB_OK);
  {
    geojcbb_step_result r0;
    CHECK(geojcbb_slam_step(sl, 0, s.z, s.R, &r0) == GEOJCBB_INVALID_INPUT); /* not configured */
  }
  CHECK(geojcbb_slam_configure(sl, &st) == GEOJCBB_OK);
  CHECK(geojcbb_slam_reset(sl, x0, P0) == GEOJCBB_OK);
  CHECK(ref_slam_start(&st, x0, P0) == 0);
  make_scene(&s, 12, 12); /* a fixed world seen from a robot standing still, observed repeatedly */
  for (k = 0; k < 30; ++k) {
    geojcbb_step_result r;
    int32_t feature[GEOJCBB_MAX_OBSERVATIONS];
    uint8_t outcome[GEOJCBB_MAX_OBSERVATIONS];
    float pose[3], mine[3];
    for (i = 0; i < s.m; ++i) {
      s.z[2 * i] = (float)(s.h[2 * i] + 0.05 * gauss());
      s.z[2 * i + 1] = (float)wrap(s.h[2 * i + 1] + 0.01 * gauss());
    }
    CHECK(geojcbb_slam_predict(sl, 0.f, 0.f, 0.1f, 0.01f, 0.01f) == GEOJCBB_OK);
    CHECK(ref_slam_predict(0.f, 0.f, 0.1f, 0.01f, 0.01f) == 0);
    CHECK(geojcbb_slam_step(sl, s.m, s.z, s.R, &r) == GEOJCBB_OK);
    CHECK(ref_slam_step(s.m, s.z, s.R, feature, outcome, pose) == 0);
    CHECK(same_bits(r.feature, feature, sizeof(int32_t) * (size_t)s.m));
    CHECK(same_bits(r.outcome, outcome, (size_t)s.m));
    geojcbb_slam_pose(sl, mine);
    CHECK(same_bits(mine, pose, sizeof pose));
    ++steps;
  }
  landmarks_seen = geojcbb_slam_landmarks(sl);
  CHECK(landmarks_seen > 0 && landmarks_seen <= s.m); /* seen again and again: no duplicates */
  {
    int32_t id;
    float xy[2];
    CHECK(geojcbb_slam_landmark(sl, 0, &id, xy) == GEOJCBB_OK);
    CHECK(geojcbb_slam_landmark(sl, landmarks_seen, &id, xy) == GEOJCBB_INVALID_INPUT);
  }
  CHECK(geojcbb_slam_predict(sl, (float)NAN, 0.f, 0.1f, 0.01f, 0.01f) == GEOJCBB_NON_FINITE);
  CHECK(geojcbb_slam_predict(sl, 0.f, 0.f, -0.1f, 0.01f, 0.01f) == GEOJCBB_INVALID_INPUT);
  printf("slam: %d steps bit for bit with node::SlamStep, %d landmarks\n", steps, landmarks_seen);
}

int main(void) {
  test_strategies_bit_for_bit();
  test_bad_inputs();
  test_slam_bit_for_bit();
  if (failures != 0) {
    fprintf(stderr, "%d checks failed\n", failures);
    return 1;
  }
  printf("all checks passed\n");
  return 0;
}
