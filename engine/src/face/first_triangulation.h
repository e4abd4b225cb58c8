#pragma once
// A face's first triangulation: the constrained triangulation of its boundary and interior seeds
// in scaled (u,v), as a working mesh; and one that follows the surface's turn. The constrained
// Delaunay triangulation knows (u,v) only: on a long cylinder whose seam is split near one end, a
// seam vertex fans over half the circle beside it, and on a B-spline patch with an uneven
// parametrisation triangles reach across a bend. Such triangles fold on the surface, and every
// split of them folds a child, so refinement gets stuck there (issue 35: a potentiometer's shaft,
// a test point's loop). Adding the centroids of the triangles that turn too much, and
// triangulating again, gives a start that refinement can split.

#include <vector>

#include "boundary/face_domain.h"
#include "core/geom.h"
#include "face/work_mesh.h"
#include "geometry/surface.h"
#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// The constrained triangulation of the domain's boundary nodes and `seeds` (interior (u,v)
/// points) in (u,v) scaled by the domain's scales, as a working mesh: boundary nodes fixed, seeds
/// free, pole segments splittable. Fails with the triangulation's reason, or with the context's
/// stop status when it asks to stop (`context` may be null).
Status TriangulateDomain(const FaceDomain& domain, const std::vector<Vec2>& seeds, Surface& surface,
                         Context* context, WorkMesh* mesh);

/// TriangulateDomain, then, for up to `rounds` rounds: every triangle that folds against the
/// surface (agreement below `min_normal_cos`) or whose corners' surface normals turn by more than
/// `max_turn` radians between two of them gets its centroid as one more seed, and the domain is
/// triangulated again. Stops when no triangle needs one, or before the seeds would pass
/// `max_seeds`. Fails as TriangulateDomain does.
Status TurnLimitedTriangulation(const FaceDomain& domain, std::vector<Vec2> seeds, Surface& surface,
                                double min_normal_cos, double max_turn, int rounds,
                                size_t max_seeds, Context* context, WorkMesh* mesh);

}  // namespace rdmesh
