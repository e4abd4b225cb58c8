#pragma once
// The triangle budget: one deviation threshold for all faces at once, the smallest whose mesh
// has at most max_triangles triangles. Faces stay independent and parallel; the threshold is
// found by a secant search in log-log (triangles ~ 1 / deviation on curved faces), one pipeline
// run (pipeline.h) per try.

#include "rdmesh/context.h"
#include "rdmesh/mesh.h"
#include "rdmesh/options.h"
#include "rdmesh/status.h"

namespace rdmesh {

class Model;

/// The best mesh with at most options.max_triangles triangles. options.max_deviation, when set,
/// is a floor: the result never goes finer than it.
Result<MeshResult> MeshWithinBudget(const Model& model, const MeshOptions& options,
                                    Context* context);

}  // namespace rdmesh
