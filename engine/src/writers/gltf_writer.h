#pragma once

#include <string>
#include <vector>

#include "model/model.h"
#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes binary glTF 2.0 (.glb) through OCCT's RWGltf_CafWriter and the model's XCAF document,
/// so part names, colours and the assembly tree survive: an instanced part's mesh is stored once
/// and placed by each instance's node (coordinates in metres, +Y up, as glTF requires; each
/// instance counts its triangles). Faces of a part share the mesh of the first ok face of their
/// instance class; NORMAL is each face's exact surface normal at its own copy of the node.
/// Then AddGltfIdsAndEdges gives every triangle vertex its face id (_FACE_ID) and, when `edges`
/// is not empty, adds the edge lines (LINES primitives with _EDGE_ID). kIoError naming the path
/// on failure. With `compress` the file is compressed (WriteOptions::compress, gltf_compress.h).
/// Thread-safe; writers that lend triangulations to the model run one at a time.
Status WriteGlb(const Model& model, const MeshResult& result, const std::vector<EdgeLine>& edges,
                bool compress, const std::string& path);

}  // namespace rdmesh
