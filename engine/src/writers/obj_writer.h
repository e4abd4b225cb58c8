#pragma once

#include <string>

#include "model.h"
#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes Wavefront OBJ (model units, vertex normals, one group per part) through OCCT's
/// RWObj_CafWriter and the model's XCAF document, plus a .mtl file next to it with the parts'
/// colours. Instanced parts are written once per instance, in world coordinates. kIoError naming
/// the path on failure. Thread-safe, as WriteGlb.
Status WriteObj(const Model& model, const MeshResult& result, const std::string& path);

}  // namespace rdmesh
