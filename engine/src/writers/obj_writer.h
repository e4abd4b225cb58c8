#pragma once

#include <string>
#include <vector>

#include "model/model.h"
#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes Wavefront OBJ (model units, vertex normals, one group per part) through OCCT's
/// RWObj_CafWriter and the model's XCAF document, plus a .mtl file next to it with the parts'
/// colours. Instanced parts are written once per instance, in world coordinates. Then, when
/// `edges` is not empty, a group "edges": one `l` polyline per line that is not degenerate, in
/// edge id order, over vertex records of its own (one per mesh node on an edge, with its normal
/// when the file has normals), appended after the faces' vertices. kIoError naming the path on
/// failure. Thread-safe, as WriteGlb.
Status WriteObj(const Model& model, const MeshResult& result, const std::vector<EdgeLine>& edges,
                const std::string& path);

}  // namespace rdmesh
