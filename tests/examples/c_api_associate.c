/* docs/c_api.md's example, as a C99 program CTest builds and runs (docs.examples_current keeps the
 * doc's block equal to the lines between the doc markers): one observation of one candidate. */
#include <stdio.h>

/* [doc] */
#include "geojcbb.h"
static GEOJCBB_ALIGNED_STORAGE(mem, GEOJCBB_ASSOCIATOR_STORAGE_SIZE);

static int associate_one_scan(int m, const float* z, const float* R, int n, const int32_t* ids, const float* h,
                              const float* C, geojcbb_association* out) {
  geojcbb_settings p;
  geojcbb_associator* a;
  geojcbb_settings_default(&p); /* every option at its default (docs/options.md) */
  p.strategy = GEOJCBB_STRATEGY_GEOJCBB;
  p.local_radius_m = 12.f; /* r + d [m] */
  if (geojcbb_associator_init(&mem, sizeof mem, &p, &a) != GEOJCBB_OK) return 1;
  /* z: m (range [m], bearing [rad]); R: m 2x2 row-major; ids, h: n candidates; C: 2n x 2n row-major */
  if (geojcbb_associate(a, m, z, R, n, ids, h, C, out) != GEOJCBB_OK) return 1;
  /* out->feature[i]: an id, GEOJCBB_NEW_FEATURE or GEOJCBB_UNMATCHED; out is untouched unless OK */
  return 0;
}
/* [/doc] */

int main(void) {
  const float z[2] = {5.f, 0.1f}, R[4] = {0.01f, 0.f, 0.f, 1e-4f};
  const int32_t ids[1] = {7};
  const float h[2] = {5.05f, 0.1f}, C[4] = {0.02f, 0.f, 0.f, 2e-4f};
  geojcbb_association out;
  if (associate_one_scan(1, z, R, 1, ids, h, C, &out) != 0) return 1;
  printf("c_api: observation 0 -> feature %d\n", (int)out.feature[0]);
  return out.feature[0] == 7 ? 0 : 1;
}
