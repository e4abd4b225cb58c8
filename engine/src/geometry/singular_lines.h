#pragma once
// Singular lines of a face's surface: iso-parameter lines inside the face's (u,v) bounds that the
// surface collapses to one 3D point, across which its normal Su x Sv reverses. A surface of
// revolution whose profile crosses the axis (an apple torus, KiCad's HC33 crystal can), and a
// bilinear patch whose opposite edges run antiparallel (a bow-tie, KiCad's SSO leads) have them.
// A triangle that straddles such a line folds on the surface whatever refinement does (issue 35);
// a mesh whose triangles stay on either side of it, touching it at its one point, does not.

#include <TopoDS_Face.hxx>
#include <vector>

#include "geometry/surface.h"

namespace rdmesh {

/// The iso-line {v = at} (axis 0, running along u) or {u = at} (axis 1) of a face's surface.
struct SingularLine {
  int axis = 0;
  double at = 0;
};

/// The singular lines of `face`'s surface strictly inside `bounds` (its (u,v) bounds, as
/// FacePcurves::Bounds), in the face's own parameters. Looked for where they occur: surfaces of
/// revolution (and tori whose tube is wider than their axis is far), cones whose apex lies inside,
/// and non-rational B-spline and Bezier surfaces whose pole rows may coincide; other surfaces
/// have none. An iso-line is singular when its points lie within 1e-9 of the surface's extent of
/// each other.
std::vector<SingularLine> FindSingularLines(const TopoDS_Face& face, const UvBounds& bounds);

}  // namespace rdmesh
