#pragma once
// Where a mesh node sits on the B-rep: the classification that face domains give their boundary
// nodes and that assembly merges on.

namespace rdmesh {

/// Where a mesh node sits on the B-rep.
struct NodeRef {
  int dim = 2;     ///< 0 vertex, 1 edge, 2 face interior
  int entity = 0;  ///< vertex id, edge id or face id (1-based)
  double t = 0;    ///< curve parameter on an edge
};

}  // namespace rdmesh
