#pragma once
// The assembled mesh with its nodes split per face, for formats whose normals are per node
// (PLY, VTU): each face gets its own copy of a node it shares, with that face's normal.

#include <cstdint>
#include <vector>

#include "rdmesh/mesh.h"

namespace rdmesh {

/// One vertex per (face, Mesh node) pair that a triangle of `result.mesh` uses, numbered in the
/// order the triangles first use them; the triangles in Mesh order over these vertices.
struct FaceNodes {
  std::vector<int64_t> node;       ///< per vertex: its node id in the watertight Mesh (0-based)
  std::vector<float> normals;      ///< 3 per vertex: unit normal (see SplitNodesByFace)
  std::vector<int64_t> triangles;  ///< 3 per Mesh triangle: vertex indices
  int64_t vertex_count() const { return static_cast<int64_t>(node.size()); }
};

/// Splits the nodes of `result.mesh` per face. A vertex's normal is its face's exact outward
/// surface normal at the node (result.faces[f - 1].normals), or, where the face carries none,
/// the normalised sum of the area-weighted normals of the face's triangles at the node; so
/// normals vary smoothly inside a curved face and jump where faces meet at an angle. Node
/// coordinates stay those of the Mesh (bit-identical copies).
FaceNodes SplitNodesByFace(const MeshResult& result);

}  // namespace rdmesh
