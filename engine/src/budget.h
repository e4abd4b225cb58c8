#pragma once
// The triangle budget: one deviation threshold for all faces at once, the smallest whose mesh
// has at most max_triangles triangles. Faces stay independent and parallel; the threshold is
// found by a secant search in log-log (triangles ~ 1 / deviation on curved faces).

#include "rdmesh/engine.h"

namespace rdmesh {

class FaceSurfaces;

/// One run at an absolute deviation (model units); the pipeline in engine.cpp. `surfaces`: face
/// evaluators lent by earlier runs on the model (levels of detail), null = made per face.
Result<MeshResult> MeshAtDeviation(const Model& model, const MeshOptions& options, double deviation,
                                   Context* context, FaceSurfaces* surfaces = nullptr);

/// MeshModel with face evaluators lent by `surfaces` (may be null); the same result.
Result<MeshResult> MeshModelWith(const Model& model, const MeshOptions& options, Context* context,
                                 FaceSurfaces* surfaces);

/// The best mesh with at most options.max_triangles triangles. options.max_deviation, when set,
/// is a floor: the result never goes finer than it.
Result<MeshResult> MeshWithinBudget(const Model& model, const MeshOptions& options,
                                    Context* context);

}  // namespace rdmesh
