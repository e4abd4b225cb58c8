#pragma once

#include <string>

#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes `result.mesh` as a VTK XML UnstructuredGrid (.vtu, ASCII): Float64 points in model
/// units, split per face (SplitNodesByFace: a node shared by faces is a point per face), triangle
/// cells (VTK type 5, counter-clockwise seen from outside), point data Normals (Float32, the
/// face's exact surface normal at the point) and node_id (Int64, the point's 0-based node id in
/// the watertight mesh), and cell data face_id (Int32, the B-rep face id) and, when the mesh
/// carries them, deviation (Float64, the estimated triangle-surface distance, model units).
/// kIoError naming the path on failure.
Status WriteVtu(const MeshResult& result, const std::string& path);

}  // namespace rdmesh
