// The controller build's entry point: the association pipeline in float at the default bounds,
// compiled once in the geojcbb_pipeline_f32 library (so firmware translation units stay small).
#pragma once

#include "geojcbb/associate.hpp"

namespace geojcbb {

using ObservationsF = Observations<float, DefaultBounds>;
using PredictionF = Prediction<float, DefaultBounds>;
using AssociationConfigF = AssociationConfig<float, DefaultBounds>;
using AssociationWorkspaceF = AssociationWorkspace<float, DefaultBounds>;
using AssociationF = Association<float, DefaultBounds>;

/// associate() for float and DefaultBounds.
[[nodiscard]] Status associate_f32(const ObservationsF& obs, const PredictionF& pred, const AssociationConfigF& cfg,
                                   AssociationWorkspaceF& ws, AssociationF& out);

}  // namespace geojcbb
