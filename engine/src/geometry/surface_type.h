#pragma once
// The kind of a face's surface, as ModelInfo reports it and as the face mesher picks its exact
// evaluators by. Internal to the engine.
#include <TopoDS_Face.hxx>

#include "rdmesh/mesh.h"

namespace rdmesh {

/// The kind of a face's surface (from OCCT's GeomAbs type).
SurfaceType FaceSurfaceType(const TopoDS_Face& face);

}  // namespace rdmesh
