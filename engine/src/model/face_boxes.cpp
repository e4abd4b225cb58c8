#include "model/face_boxes.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepTools.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <BRep_Tool.hxx>
#include <BndLib_Add2dCurve.hxx>
#include <BndLib_Add3dCurve.hxx>
#include <Bnd_Box2d.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_BezierCurve.hxx>
#include <Geom_BezierSurface.hxx>
#include <Geom_Conic.hxx>
#include <Geom_Line.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_SphericalSurface.hxx>
#include <Geom_SurfaceOfLinearExtrusion.hxx>
#include <Geom_SurfaceOfRevolution.hxx>
#include <Geom_ToroidalSurface.hxx>
#include <Precision.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace rdmesh {

namespace {

// Whether BndLib_Add3dCurve::Add's box of `curve` holds it: exact for lines and conics, the
// convex hull of the poles for Bezier and B-spline curves (others are sampled, which may not).
bool CurveBoxHolds(const Handle(Geom_Curve) & curve) {
  return curve->IsKind(STANDARD_TYPE(Geom_Line)) || curve->IsKind(STANDARD_TYPE(Geom_Conic)) ||
         curve->IsKind(STANDARD_TYPE(Geom_BSplineCurve)) ||
         curve->IsKind(STANDARD_TYPE(Geom_BezierCurve));
}

// Whether some v + 2 pi n lies strictly inside (lo, hi).
bool PeriodicInside(double v, double lo, double hi) {
  const double period = 2 * M_PI;
  const double shifted = v + period * std::ceil((lo - v) / period);
  return shifted > lo && shifted < hi;
}

}  // namespace

// Such faces are otherwise boxed tightly one by one, which costs tens of milliseconds each
// (BndLib_AddSurface::AddOptimal optimises over the swept surface); with a box that holds, the
// model box's pruning skips those that cannot reach it.
Bnd_Box SweptFaceBox(const TopoDS_Face& face) {
  Bnd_Box box;
  TopLoc_Location location;
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face, location);
  if (surface.IsNull()) return box;
  while (auto trimmed = Handle(Geom_RectangularTrimmedSurface)::DownCast(surface))
    surface = trimmed->BasisSurface();
  double u0, u1, v0, v1;
  BRepTools::UVBounds(face, u0, u1, v0, v1);
  if (!(u0 <= u1 && v0 <= v1) || Precision::IsInfinite(u0) || Precision::IsInfinite(u1) ||
      Precision::IsInfinite(v0) || Precision::IsInfinite(v1))
    return box;
  Bnd_Box basis;
  if (auto revolved = Handle(Geom_SurfaceOfRevolution)::DownCast(surface)) {
    // S(u, v) = C(v) turned by u about the axis.
    const Handle(Geom_Curve)& curve = revolved->BasisCurve();
    if (!CurveBoxHolds(curve)) return box;
    BndLib_Add3dCurve::Add(GeomAdaptor_Curve(curve, v0, v1), 0.0, basis);
    if (basis.IsVoid() || basis.IsOpen()) return box;
    const gp_Ax1 axis = revolved->Axis();
    const gp_XYZ o = axis.Location().XYZ(), d = axis.Direction().XYZ();
    double c[6];
    basis.Get(c[0], c[1], c[2], c[3], c[4], c[5]);
    double a = HUGE_VAL, b = -HUGE_VAL, r = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const gp_XYZ p(c[corner & 1 ? 3 : 0], c[corner & 2 ? 4 : 1], c[corner & 4 ? 5 : 2]);
      const double t = (p - o).Dot(d);
      a = std::min(a, t), b = std::max(b, t);
      r = std::max(r, (p - o - t * d).Modulus());
    }
    for (int k = 1; k <= 3; ++k) {
      const double s = r * std::sqrt(std::max(0.0, 1.0 - d.Coord(k) * d.Coord(k)));
      const double lo = o.Coord(k) + std::min(a * d.Coord(k), b * d.Coord(k)) - s;
      const double hi = o.Coord(k) + std::max(a * d.Coord(k), b * d.Coord(k)) + s;
      c[k - 1] = lo, c[k + 2] = hi;
    }
    box.Update(c[0], c[1], c[2], c[3], c[4], c[5]);
  } else if (auto extruded = Handle(Geom_SurfaceOfLinearExtrusion)::DownCast(surface)) {
    // S(u, v) = C(u) + v D.
    const Handle(Geom_Curve)& curve = extruded->BasisCurve();
    if (!CurveBoxHolds(curve)) return box;
    BndLib_Add3dCurve::Add(GeomAdaptor_Curve(curve, u0, u1), 0.0, basis);
    if (basis.IsVoid() || basis.IsOpen()) return box;
    const gp_XYZ d = extruded->Direction().XYZ();
    double c[6];
    basis.Get(c[0], c[1], c[2], c[3], c[4], c[5]);
    for (int k = 1; k <= 3; ++k) {
      c[k - 1] += std::min(v0 * d.Coord(k), v1 * d.Coord(k));
      c[k + 2] += std::max(v0 * d.Coord(k), v1 * d.Coord(k));
    }
    box.Update(c[0], c[1], c[2], c[3], c[4], c[5]);
  } else {
    return box;
  }
  // The face's tolerance, as BRepBndLib::Add enlarges the other kinds' boxes by it.
  box.Enlarge(BRep_Tool::Tolerance(face));
  return location.IsIdentity() ? box : box.Transformed(location.Transformation());
}

namespace {

// The face's boundary and domain, for the extremes of the closed forms below.
class FaceExtremes {
 public:
  // Starts the box from the edges' optimal boxes, as AddOptimal takes them, and the points of
  // degenerated edges (poles, which AddOptimal reaches through the surface).
  explicit FaceExtremes(const TopoDS_Face& forward) : face_(forward) {
    Bnd_Box edges;
    for (TopExp_Explorer it(face_, TopAbs_EDGE); it.More(); it.Next()) {
      const TopoDS_Edge& edge = TopoDS::Edge(it.Current());
      if (BRep_Tool::Degenerated(edge)) {
        edges.Add(BRep_Tool::Pnt(TopExp::FirstVertex(edge)));
      } else if (BRep_Tool::IsGeometric(edge)) {
        BndLib_Add3dCurve::AddOptimal(BRepAdaptor_Curve(edge), 0.0, edges);
      }
    }
    valid_ = !edges.IsVoid() && !edges.IsOpen();
    if (!valid_) return;
    edges.Get(lo_[0], lo_[1], lo_[2], hi_[0], hi_[1], hi_[2]);
    BRepTools::UVBounds(face_, u0_, u1_, v0_, v1_);
  }

  bool valid() const { return valid_; }
  // Whether the domain meets the line v (or v + 2 pi n when `periodic`; else v is the surface's
  // last v or first, as a sphere's poles). A connected domain meets every v of its range: the
  // pcurves' 2D box, loose (the poles of B-splines) first, then optimal where the loose one
  // says yes (the optimiser is the slow part here).
  bool MeetsV(double v, bool periodic) {
    auto meets = [&](const std::pair<double, double>& range) {
      const double margin = Precision::PConfusion();
      if (periodic) return PeriodicInside(v, range.first, range.second);
      return v > 0 ? range.second >= v - margin : range.first <= v + margin;
    };
    return meets(VRange(/*optimal=*/false)) && meets(VRange(/*optimal=*/true));
  }

  // Takes `value` as coordinate k's when it extends the box and reached() says the face has it.
  template <typename Reached>
  void Consider(int k, double value, Reached&& reached) {
    if ((value < lo_[k] || value > hi_[k]) && reached()) {
      lo_[k] = std::min(lo_[k], value);
      hi_[k] = std::max(hi_[k], value);
    }
  }
  // Whether (u, v), or its copy a whole number of periods (2 pi) on, lies in the domain.
  bool Inside(double u, double v) {
    const double period = 2 * M_PI, margin = Precision::PConfusion();
    u += period * std::ceil((u0_ - margin - u) / period);
    v += period * std::ceil((v0_ - margin - v) / period);
    if (u > u1_ + margin || v > v1_ + margin) return false;
    if (!classifier_) classifier_ = std::make_unique<BRepTopAdaptor_FClass2d>(face_, margin);
    return classifier_->Perform(gp_Pnt2d(u, v)) != TopAbs_OUT;
  }
  // Whether (u, v) itself lies in the domain (no shift by a period).
  bool InsideAsIs(double u, double v) {
    if (!classifier_)
      classifier_ = std::make_unique<BRepTopAdaptor_FClass2d>(face_, Precision::PConfusion());
    return classifier_->Perform(gp_Pnt2d(u, v)) != TopAbs_OUT;
  }
  // The box's side along coordinate k: its largest value when `sign` > 0, else its smallest.
  double Side(int k, int sign) const { return sign > 0 ? hi_[k] : lo_[k]; }
  void UVBounds(double* u0, double* u1, double* v0, double* v1) const {
    *u0 = u0_, *u1 = u1_, *v0 = v0_, *v1 = v1_;
  }
  Bnd_Box Box() const {
    Bnd_Box box;
    box.Update(lo_[0], lo_[1], lo_[2], hi_[0], hi_[1], hi_[2]);
    return box;
  }

 private:
  std::pair<double, double> VRange(bool optimal) {
    std::optional<std::pair<double, double>>& range = v_range_[optimal ? 1 : 0];
    if (!range) {
      Bnd_Box2d domain;
      for (TopExp_Explorer it(face_, TopAbs_EDGE); it.More(); it.Next()) {
        double t0, t1;
        Handle(Geom2d_Curve) pcurve =
            BRep_Tool::CurveOnSurface(TopoDS::Edge(it.Current()), face_, t0, t1);
        if (pcurve.IsNull()) continue;
        if (optimal) {
          BndLib_Add2dCurve::AddOptimal(pcurve, t0, t1, 0.0, domain);
        } else {
          BndLib_Add2dCurve::Add(pcurve, t0, t1, 0.0, domain);
        }
      }
      double u0 = 0, v0 = v0_, u1 = 0, v1 = v1_;
      if (!domain.IsVoid()) domain.Get(u0, v0, u1, v1);
      range = std::make_pair(v0, v1);
    }
    return *range;
  }

  const TopoDS_Face& face_;
  bool valid_ = false;
  double lo_[3] = {}, hi_[3] = {};
  double u0_ = 0, u1_ = 0, v0_ = 0, v1_ = 0;             // BRepTools::UVBounds
  std::optional<std::pair<double, double>> v_range_[2];  // loose, optimal
  std::unique_ptr<BRepTopAdaptor_FClass2d> classifier_;
};

// A torus's frame and radii: coordinate k is c + (R + r cos v) a cos(u - phi) + r sin v dz,
// where (a, phi) is axis k seen in the torus's plane and dz along its axis. Critical where
// u = phi or phi + pi and tan v = dz / (a cos(u - phi)); when a = 0 on the circles v = pi/2
// and 3 pi/2, which the face meets when its v range passes them (a connected domain meets every
// v of its range); and with R <= r where the tube crosses the axis, R + r cos v = 0, a point
// that every u maps to.
Bnd_Box TorusBox(const gp_Torus& torus, FaceExtremes* face) {
  const double R = torus.MajorRadius(), r = torus.MinorRadius();
  const gp_Ax3& frame = torus.Position();
  const gp_XYZ center = frame.Location().XYZ();
  const gp_XYZ x = frame.XDirection().XYZ(), y = frame.YDirection().XYZ(),
               z = frame.Direction().XYZ();
  if (R <= r) {
    const double apex = std::acos(-R / r);
    for (double v : {apex, 2 * M_PI - apex}) {
      const gp_XYZ p = center + r * std::sin(v) * z;
      for (int k = 0; k < 3; ++k)
        face->Consider(k, p.Coord(k + 1), [&] { return face->MeetsV(v, /*periodic=*/true); });
    }
  }
  for (int k = 0; k < 3; ++k) {
    const double dx = x.Coord(k + 1), dy = y.Coord(k + 1), dz = z.Coord(k + 1);
    const double a = std::hypot(dx, dy), c = center.Coord(k + 1);
    if (a < 1e-9) {
      const double top = dz > 0 ? M_PI / 2 : 3 * M_PI / 2;
      face->Consider(k, c + r * std::abs(dz), [&] { return face->MeetsV(top, /*periodic=*/true); });
      face->Consider(k, c - r * std::abs(dz),
                     [&] { return face->MeetsV(top + M_PI, /*periodic=*/true); });
      continue;
    }
    const double phi = std::atan2(dy, dx);
    for (int side : {1, -1}) {
      const double u = side > 0 ? phi : phi + M_PI;
      for (int half = 0; half < 2; ++half) {
        const double v = std::atan2(dz, a * side) + half * M_PI;
        const double value = c + (R + r * std::cos(v)) * a * side + r * std::sin(v) * dz;
        face->Consider(k, value, [&] { return face->Inside(u, v); });
      }
    }
  }
  return face->Box();
}

// A sphere's: coordinate k is extreme at the two points where the normal is axis k, at
// u = phi, v = asin(dz) and its antipode; when a = 0 these are the poles, which the face holds
// when its v range reaches them.
Bnd_Box SphereBox(const gp_Sphere& sphere, FaceExtremes* face) {
  const double r = sphere.Radius();
  const gp_Ax3& frame = sphere.Position();
  const gp_XYZ center = frame.Location().XYZ();
  const gp_XYZ x = frame.XDirection().XYZ(), y = frame.YDirection().XYZ(),
               z = frame.Direction().XYZ();
  for (int k = 0; k < 3; ++k) {
    const double dx = x.Coord(k + 1), dy = y.Coord(k + 1), dz = z.Coord(k + 1);
    const double a = std::hypot(dx, dy), c = center.Coord(k + 1);
    for (int side : {1, -1}) {
      // The point whose outward normal is side * axis k.
      const double v = std::asin(std::clamp(side * dz, -1.0, 1.0));
      face->Consider(k, c + side * r, [&] {
        if (a < 1e-9) return face->MeetsV(v > 0 ? M_PI / 2 : -M_PI / 2, /*periodic=*/false);
        return face->Inside(std::atan2(side * dy, side * dx), v);
      });
    }
  }
  return face->Box();
}

}  // namespace

Bnd_Box ClosedFormFaceBox(const TopoDS_Face& face) {
  const TopoDS_Face forward = TopoDS::Face(face.Oriented(TopAbs_FORWARD));
  TopLoc_Location location;
  Handle(Geom_Surface) surface = BRep_Tool::Surface(forward, location);
  while (auto trimmed = Handle(Geom_RectangularTrimmedSurface)::DownCast(surface))
    surface = trimmed->BasisSurface();
  const gp_Trsf placement = location.Transformation();
  if (auto toroidal = Handle(Geom_ToroidalSurface)::DownCast(surface)) {
    gp_Torus torus = toroidal->Torus();
    if (!location.IsIdentity()) torus.Transform(placement);
    if (!(torus.MajorRadius() >= 0 && torus.MinorRadius() > 0)) return Bnd_Box();
    FaceExtremes extremes(forward);
    return extremes.valid() ? TorusBox(torus, &extremes) : Bnd_Box();
  }
  if (auto spherical = Handle(Geom_SphericalSurface)::DownCast(surface)) {
    gp_Sphere sphere = spherical->Sphere();
    if (!location.IsIdentity()) sphere.Transform(placement);
    if (!(sphere.Radius() > 0)) return Bnd_Box();
    FaceExtremes extremes(forward);
    return extremes.valid() ? SphereBox(sphere, &extremes) : Bnd_Box();
  }
  return Bnd_Box();
}

namespace {

// Grid points along one parameter of the face's range [t0, t1]: for B-splines and Beziers,
// OCCT's sampling density (AddOptimal's: two per pole, or per degree and span) doubled, for
// other surfaces 65; within [9, 129]. Then Newton's method starts next to every extreme.
int GridPoints(const BRepAdaptor_Surface& surface, bool along_u, double t0, double t1) {
  int n = 33;
  if (surface.GetType() == GeomAbs_BSplineSurface) {
    const Handle(Geom_BSplineSurface) spline = surface.BSpline();
    const int degree = along_u ? spline->UDegree() : spline->VDegree();
    const int knots = along_u ? spline->NbUKnots() : spline->NbVKnots();
    int spans = 1;  // spans that the range meets
    for (int i = 2; i < knots; ++i) {
      const double knot = along_u ? spline->UKnot(i) : spline->VKnot(i);
      if (knot > t0 && knot < t1) ++spans;
    }
    n = 2 * (degree + 1) * spans;
  } else if (surface.GetType() == GeomAbs_BezierSurface) {
    n = 2 * (along_u ? surface.NbUPoles() : surface.NbVPoles());
  }
  return std::clamp(2 * n - 1, 9, 129);
}

// Climbs from (u, v) to a local maximum of sign * coordinate k over [u0, u1] x [v0, v1]:
// Newton's step where the Hessian is negative definite, else along the gradient, each step
// halved until it climbs. Returns the value reached (sign * coordinate) and the point.
double Climb(const BRepAdaptor_Surface& surface, int k, int sign, double u0, double u1, double v0,
             double v1, double* u, double* v) {
  auto value = [&](double a, double b) { return sign * surface.Value(a, b).Coord(k + 1); };
  double f = value(*u, *v);
  const double span = std::max(u1 - u0, v1 - v0);
  for (int iteration = 0; iteration < 40; ++iteration) {
    gp_Pnt p;
    gp_Vec du, dv, duu, dvv, duv;
    surface.D2(*u, *v, p, du, dv, duu, dvv, duv);
    const double gu = sign * du.Coord(k + 1), gv = sign * dv.Coord(k + 1);
    const double huu = sign * duu.Coord(k + 1), hvv = sign * dvv.Coord(k + 1),
                 huv = sign * duv.Coord(k + 1);
    const double det = huu * hvv - huv * huv;
    double su, sv;
    if (huu < 0 && det > 0) {
      su = -(hvv * gu - huv * gv) / det;
      sv = -(huu * gv - huv * gu) / det;
    } else {
      // Along the gradient, a tenth of the range at first.
      const double g = std::hypot(gu, gv);
      if (!(g > 0)) break;
      su = 0.1 * span * gu / g, sv = 0.1 * span * gv / g;
    }
    bool climbed = false;
    for (int halving = 0; halving < 30 && !climbed; ++halving) {
      const double nu = std::clamp(*u + su, u0, u1), nv = std::clamp(*v + sv, v0, v1);
      const double nf = value(nu, nv);
      if (nf > f) {
        climbed = true;
        const bool small = std::abs(nu - *u) + std::abs(nv - *v) < 1e-12 * span;
        *u = nu, *v = nv, f = nf;
        if (small) return f;
      } else {
        su *= 0.5, sv *= 0.5;
      }
    }
    if (!climbed) break;
  }
  return f;
}

// Whether AddOptimal boxes faces on `surface` by their edges alone (OCCT's CanUseEdges: ruled
// surfaces, whose coordinates are extreme on the boundary), which costs little.
bool BoxedByEdges(const Adaptor3d_Surface& surface) {
  switch (surface.GetType()) {
    case GeomAbs_Plane:
    case GeomAbs_Cylinder:
    case GeomAbs_Cone:
    case GeomAbs_SurfaceOfExtrusion:
      return true;
    case GeomAbs_SurfaceOfRevolution:
      return surface.BasisCurve()->GetType() == GeomAbs_Line;
    case GeomAbs_OffsetSurface:
      return BoxedByEdges(*surface.BasisSurface());
    case GeomAbs_BSplineSurface: {
      const Handle(Geom_BSplineSurface) spline = surface.BSpline();
      return (spline->UDegree() == 1 && spline->NbUKnots() == 2) ||
             (spline->VDegree() == 1 && spline->NbVKnots() == 2);
    }
    case GeomAbs_BezierSurface:
      return surface.UDegree() == 1 || surface.VDegree() == 1;
    default:
      return false;
  }
}

}  // namespace

// AddOptimal's optimiser runs a particle swarm and Powell's method from every grid point near
// an extreme, tens of milliseconds per face; here one climb from each local extreme of the grid
// that passes the edges' box.
Bnd_Box SampledFaceBox(const TopoDS_Face& face) {
  const TopoDS_Face forward = TopoDS::Face(face.Oriented(TopAbs_FORWARD));
  FaceExtremes extremes(forward);
  if (!extremes.valid()) return Bnd_Box();
  double u0, u1, v0, v1;
  extremes.UVBounds(&u0, &u1, &v0, &v1);
  if (!(u0 <= u1 && v0 <= v1) || Precision::IsInfinite(u0) || Precision::IsInfinite(u1) ||
      Precision::IsInfinite(v0) || Precision::IsInfinite(v1))
    return Bnd_Box();
  const BRepAdaptor_Surface surface(forward, /*restriction=*/Standard_False);
  if (BoxedByEdges(surface) || surface.GetType() == GeomAbs_Sphere ||
      surface.GetType() == GeomAbs_Torus)
    return Bnd_Box();
  const int nu = GridPoints(surface, /*along_u=*/true, u0, u1);
  const int nv = GridPoints(surface, /*along_u=*/false, v0, v1);
  auto param = [](double t0, double t1, int i, int n) { return t0 + (t1 - t0) * i / (n - 1); };
  std::vector<gp_XYZ> grid(static_cast<size_t>(nu) * nv);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j)
      grid[i * nv + j] = surface.Value(param(u0, u1, i, nu), param(v0, v1, j, nv)).XYZ();
  const double eps = Precision::Confusion();
  for (int k = 0; k < 3; ++k) {
    for (int sign : {1, -1}) {
      // Grid points that pass the side reached so far and are no lower than their neighbours.
      std::vector<std::pair<double, int>> starts;
      for (int i = 0; i < nu; ++i) {
        for (int j = 0; j < nv; ++j) {
          const double f = sign * grid[i * nv + j].Coord(k + 1);
          if (!(f > sign * extremes.Side(k, sign))) continue;
          bool top = true;
          for (int a = std::max(0, i - 1); a <= std::min(nu - 1, i + 1) && top; ++a)
            for (int b = std::max(0, j - 1); b <= std::min(nv - 1, j + 1) && top; ++b)
              top = sign * grid[a * nv + b].Coord(k + 1) <= f;
          if (top) starts.push_back({-f, i * nv + j});
        }
      }
      std::sort(starts.begin(), starts.end());
      for (const auto& [unused, index] : starts) {
        double u = param(u0, u1, index / nv, nu), v = param(v0, v1, index % nv, nv);
        const double f = Climb(surface, k, sign, u0, u1, v0, v1, &u, &v);
        if (!(f > sign * extremes.Side(k, sign)) || !(u > u0 && u < u1 && v > v0 && v < v1))
          continue;
        // Kept where the face has the point, strictly inside its (u, v) bounds: elsewhere the
        // face's extreme is on its boundary, whose edges' box holds it (a point on a pcurve can
        // lie off its 3D edge by the edge's tolerance), or at another start.
        extremes.Consider(k, sign * (f + eps), [&] { return extremes.InsideAsIs(u, v); });
      }
    }
  }
  return extremes.Box();
}

}  // namespace rdmesh
