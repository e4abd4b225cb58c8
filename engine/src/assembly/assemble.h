#pragma once
// Faces into one watertight mesh: boundary nodes with the same B-rep classification (a vertex,
// or an edge and a grid parameter) become one node, so faces share their edges exactly.

#include <vector>

#include "boundary/node_ref.h"
#include "rdmesh/mesh.h"

namespace rdmesh {

/// Sets every FaceMesh's global_ids and fills `mesh` from the ok faces, in face id order.
/// `refs[i]` classifies the nodes of `faces[i]`. Node ids are given serially; the nodes and
/// triangles are written on up to `threads` threads (0: all cores), the same for any count.
void Assemble(std::vector<FaceMesh>* faces, const std::vector<std::vector<NodeRef>>& refs,
              Mesh* mesh, int threads = 1);

}  // namespace rdmesh
