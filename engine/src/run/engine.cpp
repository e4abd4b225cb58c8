// MeshModel, the facade: validate the options, resolve the deviation, dispatch to the pipeline
// (pipeline.h: one run at one deviation, which builds the edge lines too) or to the triangle budget
// (budget.h: several runs, the edge lines built here for the one kept).
#include "rdmesh/engine.h"

#include <utility>
#include <vector>

#include "model/model.h"
#include "run/budget.h"
#include "run/facade.h"
#include "run/pipeline.h"

namespace rdmesh {

Result<MeshResult> MeshModel(const Model& model, const MeshOptions& options, Context* context) {
  return MeshModelWith(model, options, context, nullptr);
}

Result<MeshResult> MeshModelWith(const Model& model, const MeshOptions& options, Context* context,
                                 FaceSurfaces* surfaces) {
  Status st = ValidateOptions(options);
  if (!st.ok()) return st;
  Context local;
  if (!context) context = &local;
  if (options.timeout_seconds > 0) context->SetTimeout(options.timeout_seconds);
  double deviation = options.max_deviation > 0 ? options.max_deviation
                                               : MaxDeviationRel(options) * model.info.diagonal;
  if (options.max_triangles <= 0 && options.compress) {
    // The writer's rounding of positions takes its share of the deviation (options.h).
    Result<MeshResult> result =
        MeshAtDeviation(model, options, deviation * (1.0 - kCompressRoundingShare), context,
                        surfaces, RunOutput::kMeshAndEdgeLines);
    if (result.ok()) result->summary.requested_deviation = deviation;
    return result;
  }
  if (options.max_triangles <= 0)
    return MeshAtDeviation(model, options, deviation, context, surfaces,
                           RunOutput::kMeshAndEdgeLines);
  Result<MeshResult> result = MeshWithinBudget(model, options, context);
  if (!result.ok()) return result;
  Result<std::vector<EdgeLine>> edges =
      BuildEdgeLines(model, result->mesh, options.sharp_edge_angle, options.threads);
  if (!edges.ok()) return edges.status();
  result->edges = std::move(*edges);
  return result;
}

}  // namespace rdmesh
