#pragma once
// The facade's entry with lent face evaluators (engine.cpp), for the levels of detail
// (levels.cpp).

#include "rdmesh/context.h"
#include "rdmesh/mesh.h"
#include "rdmesh/options.h"
#include "rdmesh/status.h"

namespace rdmesh {

class FaceSurfaces;
class Model;

/// MeshModel with face evaluators lent by `surfaces` (may be null); the same result.
Result<MeshResult> MeshModelWith(const Model& model, const MeshOptions& options, Context* context,
                                 FaceSurfaces* surfaces);

}  // namespace rdmesh
