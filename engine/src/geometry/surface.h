#pragma once
// Geometry evaluators: a surface S(u,v) and a curve C(t). The meshing stages see only these
// interfaces; the OCCT evaluators are the real ones, the analytic plane, cylinder and sphere let
// refinement be unit-tested without files.
//
// Evaluators cache state (OCCT adaptors do): one instance per thread.

#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <memory>
#include <vector>

#include "core/geom.h"

class Adaptor3d_Surface;

namespace rdmesh {

/// A parametric surface. Point() is all refinement needs; Normal() serves fold guards and output.
class Surface {
 public:
  virtual ~Surface() = default;
  /// S(u, v) in world coordinates (model units).
  virtual Vec3 Point(double u, double v) = 0;
  /// Unit normal Su x Sv of the parametrisation (not flipped for reversed faces). Where it is
  /// undefined (a pole), the average of nearby normals. Default: central differences.
  virtual Vec3 Normal(double u, double v);
  /// Parameter bounds of the face (used to keep probes inside and to pick difference steps).
  double umin = 0, umax = 1, vmin = 0, vmax = 1;
  /// Knot lines u = const / v = const of a B-spline, where its polynomial pieces meet (its
  /// shape may turn there, unseen by samples on either side): the distinct knots ascending,
  /// repeated every `period` when that is > 0. Empty for other surfaces.
  struct KnotLines {
    std::vector<double> at;
    double period = 0;
  };
  KnotLines uknots, vknots;
  /// A sphere, circular cylinder or circular cone: the distance from a point to it has a closed
  /// form, so the deviation of a triangle with its corners on it is measured exactly
  /// (measure.cpp) instead of estimated from samples. kNone for every other surface.
  struct Quadric {
    enum class Kind { kNone, kSphere, kCylinder, kCone };
    Kind kind = Kind::kNone;
    Vec3 center;        ///< a sphere's centre; a point on a cylinder's or cone's axis
    Vec3 axis;          ///< a cylinder's or cone's unit axis direction
    double radius = 0;  ///< a cone's radius at `center`
    double cone_sin = 0, cone_cos = 1;  ///< of a cone's semi-angle (its radius grows by
                                        ///< tan(angle) per unit along the axis)
  };
  Quadric quadric;
  /// A plane: every triangle with its corners on it lies in it (the final check passes it by).
  bool planar = false;
};

/// A parametric curve C(t) in world coordinates.
class Curve {
 public:
  virtual ~Curve() = default;
  virtual Vec3 Point(double t) = 0;
  /// What closed forms apply (MeasureSegment): a line (no sagitta, no deficit) or a circle
  /// parametrised by its angle (the farthest point from a chord, and the best split, are at the
  /// middle parameter).
  enum class Shape { kOther, kLine, kCircle };
  Shape shape = Shape::kOther;
};

/// Analytic surfaces for tests. Plane z = 0 over [0,w]x[0,h]; cylinder of radius r along z,
/// S(u,v) = (r cos u, r sin u, v); sphere of radius r, S(u,v) = r(cos v cos u, cos v sin u, sin v).
std::unique_ptr<Surface> MakePlaneSurface();
std::unique_ptr<Surface> MakeCylinderSurface(double radius);
std::unique_ptr<Surface> MakeSphereSurface(double radius);
/// Circle of radius r in the plane z = z0: C(t) = (r cos t, r sin t, z0).
std::unique_ptr<Curve> MakeCircleCurve(double radius, double z0);

/// Wraps `surface` so that Point() remembers recent results: refinement evaluates the same
/// (u,v) many times (an edge's midpoint serves both its triangles and every re-measurement while
/// its end nodes stay put). Exact: a hit returns the very value the surface returned for the
/// same bits of u and v. A bounded, direct-mapped table; Normal() is passed through.
std::unique_ptr<Surface> WithPointCache(std::unique_ptr<Surface> surface);

/// A face's (u,v) bounds, as BRepTools::UVBounds gives them.
struct UvBounds {
  double umin = 0, umax = 0, vmin = 0, vmax = 0;
};

/// OCCT evaluators for a located face / edge (the location is applied: world coordinates).
/// `nurbs` converts the surface to a B-spline first.
std::unique_ptr<Surface> MakeFaceSurface(const TopoDS_Face& face, bool nurbs);
/// The same with the face's BRepTools::UVBounds already at hand (FacePcurves::Bounds).
std::unique_ptr<Surface> MakeFaceSurface(const TopoDS_Face& face, bool nurbs,
                                         const UvBounds& bounds);
/// (u, v) moved into the surface's own parameter range (a B-spline's knot range, a trimmed
/// surface's bounds); periodic and unbounded directions are left as they are. A pcurve may run
/// past that range (gmsh_solid_56: up to 0.014 mm off a B-spline's edge), where OCCT extends the
/// surface, while the face ends at the range.
Vec2 IntoSurfaceRange(const Adaptor3d_Surface& surface, Vec2 uv);

/// Null when the edge has no 3D curve (degenerate edges).
std::unique_ptr<Curve> MakeEdgeCurve(const TopoDS_Edge& edge);

}  // namespace rdmesh
