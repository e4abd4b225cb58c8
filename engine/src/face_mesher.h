#pragma once
// One face, start to end: evaluator, (u,v) domain, constrained triangulation, refinement, and
// the FaceMesh it hands to assembly. Faces are independent once the edge grids exist.

#include <vector>

#include "face_domain.h"
#include "measure.h"
#include "rdmesh/context.h"
#include "rdmesh/mesh.h"

namespace rdmesh {

class Model;

struct FaceJob {
  FaceCriteria criteria;
  int64_t max_triangles = 0;  ///< per-face safety cap
  bool nurbs = false;
  bool improve = true;  ///< run the collapse / flip / smooth loop after refinement
};

/// Meshes face `face_id` of the model. Never throws: OCCT failures and bad loops come back as a
/// kFailed FaceMesh with the reason. Boundary nodes keep their B-rep classification in `refs`
/// (one per FaceMesh node) for assembly.
FaceMesh MeshFace(const Model& model, int face_id, const std::vector<EdgeGrid>& grids,
                  const FaceJob& job, Context* context, std::vector<NodeRef>* refs);

/// The mesh of an instanced copy: the representative's interior nodes moved by the placement,
/// the boundary rebuilt exactly from the copy's own edges.
FaceMesh PlaceCopy(const Model& model, int face_id, const FaceMesh& representative,
                   const std::vector<NodeRef>& representative_refs,
                   const std::vector<EdgeGrid>& grids, std::vector<NodeRef>* refs);

}  // namespace rdmesh
