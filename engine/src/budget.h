#pragma once
// The triangle budget: one deviation threshold for all faces at once, the smallest whose mesh
// has at most max_triangles triangles. Faces stay independent and parallel; the threshold is
// found by a secant search in log-log (triangles ~ 1 / deviation on curved faces).

#include "rdmesh/engine.h"

namespace rdmesh {

/// One run at an absolute deviation (model units); the pipeline in engine.cpp.
Result<MeshResult> MeshAtDeviation(const Model& model, const MeshOptions& options, double deviation,
                                   Context* context);

/// The best mesh with at most options.max_triangles triangles. options.max_deviation, when set,
/// is a floor: the result never goes finer than it.
Result<MeshResult> MeshWithinBudget(const Model& model, const MeshOptions& options,
                                    Context* context);

}  // namespace rdmesh
