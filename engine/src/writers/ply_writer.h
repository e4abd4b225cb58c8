#pragma once

#include <string>

#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes `result.mesh` as ASCII PLY (ASCII because common readers such as meshio misread extra
/// face properties in binary PLY). Per vertex: double x y z (model units) and float nx ny nz
/// (unit normals averaged over the faces sharing the node). Per face: uchar-int list
/// vertex_indices (counter-clockwise seen from outside) and int face_id (the B-rep face id).
/// kIoError naming the path on failure.
Status WritePly(const MeshResult& result, const std::string& path);

}  // namespace rdmesh
