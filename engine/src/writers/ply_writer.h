#pragma once

#include <string>

#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes `result.mesh` as ASCII PLY (ASCII because common readers such as meshio misread extra
/// face properties in binary PLY). Vertices are split per face (SplitNodesByFace), so a node
/// shared by faces appears once per face. Per vertex: double x y z (model units), float nx ny nz
/// (the face's exact surface normal there) and int node_id (the node's 0-based id in the
/// watertight mesh: vertices with the same node_id are one node). Per face: uchar-int list
/// vertex_indices (counter-clockwise seen from outside), int face_id (the B-rep face id) and,
/// when the mesh carries them, double deviation (the estimated triangle-surface distance).
/// kIoError naming the path on failure.
Status WritePly(const MeshResult& result, const std::string& path);

}  // namespace rdmesh
