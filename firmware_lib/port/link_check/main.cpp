// A bare Cortex-M4F image that links the float pipeline and the consistency stage at the default
// bounds with picolibc's crt0 and linker script, so the symbol check sees what a real firmware
// would pull in. It is never run (the board port of the firmware port runs the pipeline under
// QEMU); inputs live in .bss like a device's.
#include "geojcbb/consistency_f32.hpp"
#include "geojcbb/pipeline_f32.hpp"

namespace {
geojcbb::ObservationsF g_obs;
geojcbb::PredictionF g_pred;
geojcbb::AssociationConfigF g_cfg;
geojcbb::AssociationWorkspaceF g_ws;
geojcbb::AssociationF g_out;
geojcbb::ConsistencyOptionsF g_copt;
geojcbb::ConsistencyWorkspaceF g_cws;
geojcbb::ConsistencyResultF g_cout;
}  // namespace

int main() {
  using Gate = geojcbb::GateThresholds<float, geojcbb::DefaultBounds::kMaxObservations>;
  if (Gate::from_confidence(0.99, 0.99, g_cfg.gate) != geojcbb::Status::kOk) return 2;
  if (g_copt.set_confidence(0.99999, 0.999) != geojcbb::Status::kOk) return 2;
  if (geojcbb::consistent_hypothesis_f32(g_obs, g_pred, g_copt, g_cws, g_cout) != geojcbb::Status::kOk) return 3;
  return geojcbb::associate_f32(g_obs, g_pred, g_cfg, g_ws, g_out) == geojcbb::Status::kOk ? 0 : 1;
}
