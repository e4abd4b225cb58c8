#pragma once

#include <string>

#include "model.h"
#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes `result.mesh` as Gmsh MSH 4.1 ASCII.
/// - $Entities: every B-rep vertex (point tag = vertex id), edge (curve tag = edge id, bounded by
///   +start and -end vertex) and face (surface tag = face id, bounded by its signed edges),
///   with bounding boxes in model units.
/// - $Nodes: node tag = assembled node id + 1; one block per entity the nodes are classified on
///   (mesh.node_dim / node_entity), parametric on curves (t) and surfaces (u v).
/// - $Elements: one block of 3-node triangles (type 2) per face with triangles; element tags
///   1..T in face order, nodes counter-clockwise seen from outside.
/// kIoError naming the path when the file cannot be written, kInternal when the mesh's node
/// classification is missing or out of range.
Status WriteMsh(const Model& model, const MeshResult& result, const std::string& path);

}  // namespace rdmesh
