// A bare Cortex-M4F image that links the float pipeline and the consistency stage at the default
// bounds with picolibc's crt0 and linker script, so the symbol check sees what a real firmware would
// pull in. It is never run (the board port of issue 6 runs the pipeline under QEMU); inputs live in
// .bss like a device's.
#include "geojcbb.h"
#include "geojcbb/consistency_f32.hpp"
#include "geojcbb/pipeline_f32.hpp"

namespace {
geojcbb::ObservationsF g_obs;
geojcbb::PredictionF g_pred;
geojcbb::AssociationConfigF g_cfg;
geojcbb::WorkspaceF g_ws;
geojcbb::AssociationF g_out;
geojcbb::ConsistencyOptionsF g_copt;
geojcbb::ConsistencyWorkspaceF g_cws;
geojcbb::ConsistencyResultF g_cout;
// The C API (geojcbb.h) in its caller-provided storage.
alignas(GEOJCBB_STORAGE_ALIGN) unsigned char g_assoc_mem[GEOJCBB_ASSOCIATOR_STORAGE_SIZE];
alignas(GEOJCBB_STORAGE_ALIGN) unsigned char g_slam_mem[GEOJCBB_SLAM_STORAGE_SIZE];
geojcbb_association g_c_out;
geojcbb_step_result g_c_step;
float g_c_z[2 * GEOJCBB_MAX_OBSERVATIONS], g_c_R[4 * GEOJCBB_MAX_OBSERVATIONS];

// Every C entry point, so the image's symbol check and call chains cover them.
int c_api() {
  geojcbb_strategy_params p;
  geojcbb_strategy_params_default(&p);
  p.local_radius_m = 12.f;
  geojcbb_associator* a = nullptr;
  if (geojcbb_associator_init(g_assoc_mem, sizeof g_assoc_mem, GEOJCBB_STRATEGY_GEOJCBB, &p, &a) != GEOJCBB_OK) return 4;
  if (geojcbb_associate(a, 0, g_c_z, g_c_R, 0, nullptr, nullptr, nullptr, &g_c_out) != GEOJCBB_OK) return 5;
  geojcbb_slam_settings st;
  geojcbb_slam_settings_default(&st);
  st.params.local_radius_m = 12.f;
  st.max_range_m = 10.f;
  st.half_fov_rad = 1.f;
  geojcbb_slam* s = nullptr;
  const float x0[3] = {0, 0, 0}, P0[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (geojcbb_slam_init(g_slam_mem, sizeof g_slam_mem, &s) != GEOJCBB_OK) return 6;
  if (geojcbb_slam_configure(s, &st) != GEOJCBB_OK || geojcbb_slam_reset(s, x0, P0) != GEOJCBB_OK ||
      geojcbb_slam_predict(s, 0.1f, 0.f, 0.1f, 0.01f, 0.01f) != GEOJCBB_OK ||
      geojcbb_slam_step(s, 0, g_c_z, g_c_R, &g_c_step) != GEOJCBB_OK) {
    return 7;
  }
  float x[3], xy[2];
  std::int32_t id = 0;
  geojcbb_slam_pose(s, x);
  return geojcbb_slam_landmarks(s) > 0 && geojcbb_slam_landmark(s, 0, &id, xy) != GEOJCBB_OK ? 8 : 0;
}
}  // namespace

int main() {
  using Gate = geojcbb::GateThresholds<float, geojcbb::DefaultBounds::kMaxObservations>;
  if (Gate::from_confidence(0.99, 0.99, g_cfg.gate) != geojcbb::Status::kOk) return 2;
  if (g_copt.set_confidence(0.99999, 0.999) != geojcbb::Status::kOk) return 2;
  if (geojcbb::consistent_hypothesis_f32(g_obs, g_pred, g_copt, g_cws, g_cout) != geojcbb::Status::kOk) return 3;
  if (c_api() != 0) return 4;
  return geojcbb::associate_f32(g_obs, g_pred, g_cfg, g_ws, g_out) == geojcbb::Status::kOk ? 0 : 1;
}
