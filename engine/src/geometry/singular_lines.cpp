#include "geometry/singular_lines.h"

#include <BRep_Tool.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_BezierSurface.hxx>
#include <Geom_ConicalSurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_SurfaceOfRevolution.hxx>
#include <Geom_ToroidalSurface.hxx>
#include <Standard_Failure.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <algorithm>
#include <cmath>

namespace rdmesh {

namespace {

constexpr int kSamples = 24;        // along the line's normal direction, per face
constexpr int kCheckPoints = 9;     // along a candidate line
constexpr double kCollapse = 1e-9;  // of the surface's extent: the line's points coincide
constexpr double kInside = 1e-9;    // of the parameter range: strictly inside the bounds

// Whether the box of the differences between the first two pole rows across `axis` holds 0: a
// line along `axis` (0: v = const, running along u) collapses only where these rows' iso-points
// coincide, a convex combination of the differences.
bool PoleRowsMayMeet(const TColgp_Array2OfPnt& poles, int axis) {
  const int rows = axis == 0 ? poles.ColLength() : poles.RowLength();
  const int along = axis == 0 ? poles.RowLength() : poles.ColLength();
  if (rows < 2) return false;
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (int k = 0; k < along; ++k) {
    const int r0 = axis == 0 ? poles.LowerRow() : poles.LowerRow() + k;
    const int c0 = axis == 0 ? poles.LowerCol() + k : poles.LowerCol();
    const gp_Pnt& a = poles(r0, c0);
    const gp_Pnt& b = axis == 0 ? poles(r0 + 1, c0) : poles(r0, c0 + 1);
    const double d[3] = {b.X() - a.X(), b.Y() - a.Y(), b.Z() - a.Z()};
    for (int i = 0; i < 3; ++i) lo[i] = std::min(lo[i], d[i]), hi[i] = std::max(hi[i], d[i]);
  }
  for (int i = 0; i < 3; ++i)
    if (lo[i] > 0 || hi[i] < 0) return false;
  return true;
}

// Which axes may hold a singular line on `surface` within `bounds` (bit 0: v = const lines,
// bit 1: u = const), before the numeric search.
int CandidateAxes(const Handle(Geom_Surface) & surface, const UvBounds& bounds) {
  if (auto revolution = Handle(Geom_SurfaceOfRevolution)::DownCast(surface))
    return 1;  // the profile may cross the axis at some v
  if (auto torus = Handle(Geom_ToroidalSurface)::DownCast(surface))
    return torus->MinorRadius() > torus->MajorRadius() ? 1 : 0;
  if (auto cone = Handle(Geom_ConicalSurface)::DownCast(surface)) {
    const double apex = -cone->RefRadius() / std::sin(cone->SemiAngle());
    return apex > bounds.vmin && apex < bounds.vmax ? 1 : 0;
  }
  if (auto spline = Handle(Geom_BSplineSurface)::DownCast(surface)) {
    if (spline->IsURational() || spline->IsVRational()) return 0;
    const TColgp_Array2OfPnt& poles = spline->Poles();
    return (PoleRowsMayMeet(poles, 0) ? 1 : 0) | (PoleRowsMayMeet(poles, 1) ? 2 : 0);
  }
  if (auto bezier = Handle(Geom_BezierSurface)::DownCast(surface)) {
    if (bezier->IsURational() || bezier->IsVRational()) return 0;
    TColgp_Array2OfPnt poles(1, bezier->NbUPoles(), 1, bezier->NbVPoles());
    bezier->Poles(poles);
    return (PoleRowsMayMeet(poles, 0) ? 1 : 0) | (PoleRowsMayMeet(poles, 1) ? 2 : 0);
  }
  return 0;
}

// Lines along `axis`: where the chord between two points of an iso-line reverses, the iso-line
// may pass through a single point; it is kept when all its points coincide.
void SearchAxis(const Handle(Geom_Surface) & surface, const UvBounds& b, int axis,
                std::vector<SingularLine>* out) {
  const double s0 = axis == 0 ? b.umin : b.vmin, s1 = axis == 0 ? b.umax : b.vmax;
  const double w0 = axis == 0 ? b.vmin : b.umin, w1 = axis == 0 ? b.vmax : b.umax;
  if (!(s1 > s0) || !(w1 > w0)) return;
  auto point = [&](double s, double w) {
    return axis == 0 ? surface->Value(s, w) : surface->Value(w, s);
  };
  // Not symmetric in the range: a full turn's two ends are one point.
  const double sa = s0 + 0.2 * (s1 - s0), sb = s0 + 0.7 * (s1 - s0);
  auto chord = [&](double w) { return gp_Vec(point(sa, w), point(sb, w)); };
  std::vector<gp_Vec> c(kSamples + 1);
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (int k = 0; k <= kSamples; ++k) {
    const double w = w0 + (w1 - w0) * k / kSamples;
    const gp_Pnt p = point(sa, w), q = point(sb, w);
    c[k] = gp_Vec(p, q);
    for (const gp_Pnt& x : {p, q}) {
      const double xyz[3] = {x.X(), x.Y(), x.Z()};
      for (int i = 0; i < 3; ++i) lo[i] = std::min(lo[i], xyz[i]), hi[i] = std::max(hi[i], xyz[i]);
    }
  }
  const double extent = std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  if (!(extent > 0)) return;
  for (int k = 0; k < kSamples; ++k) {
    if (!(c[k].Dot(c[k + 1]) < 0)) continue;
    // Bisect the chord's component along its direction at the bracket's start.
    const gp_Vec ref = c[k];
    double a = w0 + (w1 - w0) * k / kSamples, z = w0 + (w1 - w0) * (k + 1) / kSamples;
    for (int it = 0; it < 80 && z - a > 1e-16 * (std::fabs(a) + std::fabs(z)); ++it) {
      const double m = 0.5 * (a + z);
      (chord(m).Dot(ref) > 0 ? a : z) = m;
    }
    const double at = 0.5 * (a + z);
    if (!(at > w0 + kInside * (w1 - w0)) || !(at < w1 - kInside * (w1 - w0))) continue;
    const gp_Pnt first = point(s0, at);
    bool collapsed = true;
    for (int j = 1; j < kCheckPoints && collapsed; ++j)
      collapsed =
          first.Distance(point(s0 + (s1 - s0) * j / (kCheckPoints - 1), at)) <= kCollapse * extent;
    if (collapsed) out->push_back({axis, at});
  }
}

}  // namespace

std::vector<SingularLine> FindSingularLines(const TopoDS_Face& face, const UvBounds& bounds) {
  std::vector<SingularLine> lines;
  try {
    TopLoc_Location location;
    Handle(Geom_Surface) surface = BRep_Tool::Surface(face, location);
    while (auto trimmed = Handle(Geom_RectangularTrimmedSurface)::DownCast(surface))
      surface = trimmed->BasisSurface();
    if (surface.IsNull()) return lines;
    const int axes = CandidateAxes(surface, bounds);
    for (int axis = 0; axis < 2; ++axis)
      if (axes & (1 << axis)) SearchAxis(surface, bounds, axis, &lines);
  } catch (const Standard_Failure&) {
    lines.clear();  // none found: the face is meshed as any other
  }
  return lines;
}

}  // namespace rdmesh
