#pragma once
// Faces into one watertight mesh: boundary nodes with the same B-rep classification (a vertex,
// or an edge and a grid parameter) become one node, so faces share their edges exactly.

#include <vector>

#include "node_ref.h"
#include "rdmesh/mesh.h"

namespace rdmesh {

/// Sets every FaceMesh's global_ids and fills `mesh` from the ok faces, in face id order.
/// `refs[i]` classifies the nodes of `faces[i]`.
void Assemble(std::vector<FaceMesh>* faces, const std::vector<std::vector<NodeRef>>& refs,
              Mesh* mesh);

}  // namespace rdmesh
