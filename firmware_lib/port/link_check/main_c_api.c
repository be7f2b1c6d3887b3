/* A bare Cortex-M4F image, written in C99, that calls every entry point of the C API (geojcbb.h)
 * with its storage in .bss, so the symbol check proves what a C firmware pulls in: no heap,
 * exceptions, RTTI or stdio. It is never run (test_c_api.c checks the answers on the host). */
#include "geojcbb.h"

static GEOJCBB_ALIGNED_STORAGE(assoc_mem, GEOJCBB_ASSOCIATOR_STORAGE_SIZE);
static GEOJCBB_ALIGNED_STORAGE(slam_mem, GEOJCBB_SLAM_STORAGE_SIZE);
static geojcbb_association assoc_out;
static geojcbb_step_result step_out;
static float z[2 * GEOJCBB_MAX_OBSERVATIONS], R[4 * GEOJCBB_MAX_OBSERVATIONS];
static int32_t ids[GEOJCBB_MAX_CANDIDATES];
static float h[2 * GEOJCBB_MAX_CANDIDATES], C[4 * GEOJCBB_MAX_CANDIDATES * GEOJCBB_MAX_CANDIDATES];

int main(void) {
  geojcbb_settings p;
  geojcbb_associator* a = 0;
  geojcbb_settings st;
  geojcbb_slam* s = 0;
  const float x0[3] = {0.f, 0.f, 0.f}, P0[9] = {1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f};
  float x[3], xy[2];
  int32_t id = 0;
  geojcbb_settings_default(&p);
  p.local_radius_m = 12.f;
  if (geojcbb_associator_init(&assoc_mem, sizeof assoc_mem, &p, &a) != GEOJCBB_OK) return 1;
  if (geojcbb_associate(a, 1, z, R, 1, ids, h, C, &assoc_out) != GEOJCBB_OK) return 2;
  geojcbb_settings_default(&st);
  st.local_radius_m = 12.f;
  st.max_range_m = 10.f;
  st.half_fov_rad = 1.f;
  if (geojcbb_slam_init(&slam_mem, sizeof slam_mem, &s) != GEOJCBB_OK) return 3;
  if (geojcbb_slam_configure(s, &st) != GEOJCBB_OK || geojcbb_slam_reset(s, x0, P0) != GEOJCBB_OK) return 4;
  if (geojcbb_slam_predict(s, 0.1f, 0.f, 0.1f, 0.01f, 0.01f) != GEOJCBB_OK) return 5;
  if (geojcbb_slam_step(s, 1, z, R, &step_out) != GEOJCBB_OK) return 6;
  geojcbb_slam_pose(s, x);
  if (geojcbb_slam_landmarks(s) > 0 && geojcbb_slam_landmark(s, 0, &id, xy) != GEOJCBB_OK) return 7;
  return geojcbb_status_name(GEOJCBB_OK)[0] == 'o' ? 0 : 8;
}
