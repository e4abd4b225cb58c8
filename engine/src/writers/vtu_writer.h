#pragma once

#include <string>

#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes `result.mesh` as a VTK XML UnstructuredGrid (.vtu, ASCII): Float64 points in model
/// units, triangle cells (VTK type 5, counter-clockwise seen from outside), point data Normals
/// (Float32, 3 per node, averaged over the faces sharing the node) and cell data face_id (Int32,
/// the B-rep face id). kIoError naming the path on failure.
Status WriteVtu(const MeshResult& result, const std::string& path);

}  // namespace rdmesh
