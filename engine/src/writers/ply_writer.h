#pragma once

#include <string>

#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes `result.mesh` as binary little-endian PLY. Per vertex: double x y z (model units) and
/// float nx ny nz (unit normals averaged over the faces sharing the node). Per face: uchar-int
/// list vertex_indices (counter-clockwise seen from outside) and int face_id (B-rep face id).
/// kIoError naming the path on failure.
Status WritePly(const MeshResult& result, const std::string& path);

}  // namespace rdmesh
