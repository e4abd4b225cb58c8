#pragma once

#include <string>
#include <vector>

#include "model/model.h"
#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes `result.mesh` as Gmsh MSH 4.1 ASCII, which Gmsh and meshio 5 both read.
/// - $Entities: every B-rep vertex (point tag = vertex id), edge (curve tag = edge id, bounded by
///   +start and -end vertex) and face (surface tag = face id, bounded by its signed edges),
///   with bounding boxes in model units.
/// - $Nodes: node tag = assembled node id + 1; one block per entity the nodes are classified on
///   (mesh.node_dim / node_entity). Plain x y z, or with `parametric` also the curve parameter
///   t on curves and (u v) on surfaces (MSH parametric nodes; meshio 5 cannot read those).
/// - $Elements: one block of 3-node triangles (type 2) per face with triangles, element tags
///   1..T in face order, nodes counter-clockwise seen from outside; then one block of 2-node
///   lines (type 1) per line of `edges` that is not degenerate, on the curve entity of its edge,
///   in curve order, element tags T+1 on.
/// kIoError naming the path when the file cannot be written, kInternal when the mesh's node
/// classification is missing or out of range.
Status WriteMsh(const Model& model, const MeshResult& result, const std::vector<EdgeLine>& edges,
                bool parametric, const std::string& path);

}  // namespace rdmesh
