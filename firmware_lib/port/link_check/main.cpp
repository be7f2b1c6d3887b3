// A bare Cortex-M4F image that links the float pipeline at the default bounds with picolibc's crt0
// and linker script, so the symbol check sees what a real firmware would pull in. It is never run
// (the board port of issue 6 runs the pipeline under QEMU); inputs live in .bss like a device's.
#include "geojcbb/pipeline_f32.hpp"

namespace {
geojcbb::ObservationsF g_obs;
geojcbb::PredictionF g_pred;
geojcbb::AssociationConfigF g_cfg;
geojcbb::WorkspaceF g_ws;
geojcbb::AssociationF g_out;
}  // namespace

int main() {
  using Gate = geojcbb::GateThresholds<float, geojcbb::DefaultBounds::kMaxObservations>;
  if (Gate::from_confidence(0.99, 0.99, g_cfg.gate) != geojcbb::Status::kOk) return 2;
  return geojcbb::associate_f32(g_obs, g_pred, g_cfg, g_ws, g_out) == geojcbb::Status::kOk ? 0 : 1;
}
