// The controller build's pose-free consistency stage (consistency/consistent_hypothesis.hpp) in float
// at the default bounds and 64 graph nodes, compiled once in the geojcbb_pipeline_f32 library, so the
// cross build checks its symbols, frames and call chain before associate() calls it.
#pragma once

#include "geojcbb/consistency/consistent_hypothesis.hpp"
#include "geojcbb/pipeline_f32.hpp"

namespace geojcbb {

using ConsistencyOptionsF = ConsistencyOptions<float>;
using ConsistencyWorkspaceF = ConsistencyWorkspace<float, DefaultBounds>;
using ConsistencyResultF = ConsistencyResult<DefaultBounds>;

/// consistent_hypothesis() for float, DefaultBounds and kDefaultGraphNodes.
[[nodiscard]] Status consistent_hypothesis_f32(const ObservationsF& obs, const PredictionF& pred,
                                               const ConsistencyOptionsF& opt, ConsistencyWorkspaceF& ws,
                                               ConsistencyResultF& out);

}  // namespace geojcbb
