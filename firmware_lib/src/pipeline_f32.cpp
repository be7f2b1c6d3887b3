#include "geojcbb/pipeline_f32.hpp"

namespace geojcbb {

Status associate_f32(const ObservationsF& obs, const PredictionF& pred, const AssociationConfigF& cfg,
                     AssociationWorkspaceF& ws, AssociationF& out) {
  return associate(obs, pred, cfg, ws, out);
}

}  // namespace geojcbb
