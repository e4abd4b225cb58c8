#pragma once
// The offset surface S + d n of a face's surface, for meshing off the surface (--off-surface):
// a mesh that interpolates the offset of a surface bent one way, at twice the deviation, lies
// within the deviation of the surface on both sides, with about half the triangles.

#include <memory>
#include <vector>

#include "core/geom.h"
#include "geometry/surface.h"

namespace rdmesh {

/// Which way the surface bends at the (u,v) `samples`, against its Normal(): +1 where it bends
/// away from the normal everywhere (a sphere with outward normals: its chords lie on the -normal
/// side, so an offset along +normal brackets it), -1 where it bends toward it everywhere, 0 where
/// it bends both ways somewhere (a saddle) or nowhere (a plane). A principal curvature of the
/// other sign below `tolerance` of the largest one counts as none. From second differences of
/// Point(), steps `step_u`, `step_v`.
int BendSide(Surface& surface, const std::vector<Vec2>& samples, double step_u, double step_v,
             double tolerance);

/// Values at the nodes of a regular grid over a (u,v) rectangle, bilinear between them and
/// constant beyond its edges: an offset or a deviation scale that varies over a face.
struct UvGrid {
  double umin = 0, vmin = 0, du = 1, dv = 1;
  int nu = 0, nv = 0;          ///< cells in u and in v; (nu + 1) x (nv + 1) nodes
  std::vector<double> values;  ///< node (i, j) at i * (nv + 1) + j
  double At(double u, double v) const;
};

/// S(u,v) + distance * Normal(u,v), over the same parameters, bounds and knots; the normal is the
/// base's. A sphere, cylinder or cone stays one, of the offset radius, and is offset in closed
/// form. `base` must outlive the result.
std::unique_ptr<Surface> MakeOffsetSurface(Surface* base, double distance);

/// S(u,v) + offsets.At(u,v) * Normal(u,v): an offset that varies over the face (no closed form
/// kept). `base` and `offsets` must outlive the result.
std::unique_ptr<Surface> MakeFieldOffsetSurface(Surface* base, const UvGrid* offsets);

}  // namespace rdmesh
