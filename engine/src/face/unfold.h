#pragma once
// Unfolding a face's first triangulation. The constrained Delaunay triangulation is built in
// scaled (u,v) and is blind to where the surface bends: across a sharp bend, or on a long strip
// whose far parts face other ways, a triangle can reach over so much of the surface that it folds
// in 3D (its normal against the surface normals at its corners). Refinement cannot undo such a
// fold by splitting inside the triangle, as a corner far across the bend keeps its fan. So a face
// that refinement leaves short of its criteria is refined again from its unfolded first
// triangulation (edge flips, then edge bisections where flips alone are stuck), and the better
// of the two results is kept (face_mesher.cpp).

#include "face/work_mesh.h"
#include "geometry/surface.h"

namespace rdmesh {

/// Flips free edges of folded triangles (TriangleAgreement at most 0) where the two triangles on
/// the edge get fewer folds, or as many with a larger smaller agreement. Each flip improves the
/// mesh in that order, so the pass ends; returns the number of flips.
int UnfoldFlips(WorkMesh* mesh);

/// The triangles of the mesh that fold (TriangleAgreement at most 0).
int CountFolds(const WorkMesh& mesh);

/// UnfoldFlips, then, while triangles stay folded, bisects a folded triangle's longest free edge
/// (in (u,v) scaled by scale_u, scale_v) and flips again, keeping a bisection only when the
/// mesh gets fewer folds or a larger smallest agreement. Returns the number of changes (flips of
/// the first UnfoldFlips, bisections kept): 0 leaves the mesh as it was.
int UnfoldInitialMesh(WorkMesh* mesh, Surface& surface, double scale_u, double scale_v);

}  // namespace rdmesh
