#include "geojcbb/consistency_f32.hpp"

namespace geojcbb {

Status consistent_hypothesis_f32(const ObservationsF& obs, const PredictionF& pred, const ConsistencyOptionsF& opt,
                                 ConsistencyWorkspaceF& ws, ConsistencyResultF& out) {
  return consistent_hypothesis(obs, pred, opt, ws, out);
}

}  // namespace geojcbb
