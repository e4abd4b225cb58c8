#include "model/face_area.h"

#include <BRep_Tool.hxx>
#include <Geom2d_Circle.hxx>
#include <Geom2d_Line.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <algorithm>
#include <cmath>
#include <math.hxx>
#include <math_Vector.hxx>
#include <vector>

namespace rdmesh {

// OCCT's Gauss integration of the same curves (BRepGProp::SurfaceProperties) cost a tenth of
// the load of connector models.
std::optional<double> ClosedFormFaceArea(const TopoDS_Face& face) {
  if (std::abs(std::abs(face.Location().Transformation().ScaleFactor()) - 1) > 1e-15)
    return std::nullopt;
  TopLoc_Location location;
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face, location);
  while (auto trimmed = Handle(Geom_RectangularTrimmedSurface)::DownCast(surface))
    surface = trimmed->BasisSurface();
  double element = 0;  // |Su x Sv|
  if (!Handle(Geom_Plane)::DownCast(surface).IsNull()) {
    element = 1;
  } else if (auto cylinder = Handle(Geom_CylindricalSurface)::DownCast(surface)) {
    element = cylinder->Radius();
  } else {
    return std::nullopt;
  }
  // The sum over the pcurves, when each one starts where one ends (within rounding): closed
  // loops, whose area does not depend on the point it is taken about. A face with more pieces
  // than kMaxPieces is left to OCCT (the check is quadratic).
  constexpr size_t kMaxPieces = 256;
  struct Piece {
    gp_XY a, b;  // its ends in the order it runs in the face
  };
  std::vector<Piece> pieces;
  double sum = 0, extent = 0;
  bool first = true;
  gp_XY origin;
  for (TopExp_Explorer it(face, TopAbs_EDGE); it.More(); it.Next()) {
    const TopoDS_Edge& edge = TopoDS::Edge(it.Current());
    double t0, t1;
    Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, face, t0, t1);
    if (pcurve.IsNull()) {
      if (BRep_Tool::Degenerated(edge)) continue;
      return std::nullopt;
    }
    if (auto trimmed = Handle(Geom2d_TrimmedCurve)::DownCast(pcurve))
      pcurve = trimmed->BasisCurve();
    Piece piece{pcurve->Value(t0).XY(), pcurve->Value(t1).XY()};
    if (first) origin = piece.a, first = false;
    double term;  // the integral from t0 to t1, twice over
    if (!Handle(Geom2d_Line)::DownCast(pcurve).IsNull()) {
      term = (piece.a - origin) ^ (piece.b - origin);
    } else if (auto circle = Handle(Geom2d_Circle)::DownCast(pcurve)) {
      // p(t) = c + r (cos t X + sin t Y): (p - o) x p' = (c - o) x p' + r^2 (X x Y).
      const gp_Ax22d& axes = circle->Position();
      const double r = circle->Radius();
      const double turn = axes.XDirection().XY() ^ axes.YDirection().XY();
      term = (circle->Location().XY() - origin) ^ (piece.b - piece.a);
      term += r * r * turn * (t1 - t0);
      extent = std::max(extent, 2 * r);
    } else {
      return std::nullopt;
    }
    if (edge.Orientation() == TopAbs_REVERSED) term = -term, std::swap(piece.a, piece.b);
    sum += term;
    extent = std::max({extent, (piece.a - origin).Modulus(), (piece.b - origin).Modulus()});
    pieces.push_back(piece);
    if (pieces.size() > kMaxPieces) return std::nullopt;
  }
  for (const Piece& piece : pieces) {
    double gap = HUGE_VAL;
    for (const Piece& other : pieces) gap = std::min(gap, (piece.a - other.b).Modulus());
    // Ends that miss each other: the area depends on how the gaps close, left to OCCT's.
    if (gap > 1e-9 * extent) return std::nullopt;
  }
  if (first) return std::nullopt;
  return std::abs(0.5 * sum) * element;
}

std::optional<double> NaturalPatchArea(const TopoDS_Face& face) {
  if (std::abs(std::abs(face.Location().Transformation().ScaleFactor()) - 1) > 1e-15)
    return std::nullopt;
  TopLoc_Location location;
  const Handle(Geom_Surface) surface = BRep_Tool::Surface(face, location);
  if (surface.IsNull()) return std::nullopt;
  Handle(Geom_Surface) basis = surface;
  while (auto trimmed = Handle(Geom_RectangularTrimmedSurface)::DownCast(basis))
    basis = trimmed->BasisSurface();
  const Handle(Geom_BSplineSurface) spline = Handle(Geom_BSplineSurface)::DownCast(basis);
  if (spline.IsNull()) return std::nullopt;
  double u0, u1, v0, v1;
  surface->Bounds(u0, u1, v0, v1);
  if (!(std::isfinite(u0) && std::isfinite(u1) && std::isfinite(v0) && std::isfinite(v1)) ||
      !(u0 < u1 && v0 < v1))
    return std::nullopt;
  int wires = 0;
  for (TopExp_Explorer it(face, TopAbs_WIRE); it.More(); it.Next()) ++wires;
  if (wires != 1) return std::nullopt;
  // Every pcurve an iso-line on the border, running one way, and together as long as the
  // border: the wire goes once round the rectangle.
  const double eu = 1e-9 * (u1 - u0), ev = 1e-9 * (v1 - v0);
  double along = 0;
  for (TopExp_Explorer it(face, TopAbs_EDGE); it.More(); it.Next()) {
    const TopoDS_Edge& edge = TopoDS::Edge(it.Current());
    double t0, t1;
    const Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, face, t0, t1);
    if (pcurve.IsNull()) return std::nullopt;
    const gp_XY a = pcurve->Value(t0).XY(), b = pcurve->Value(t1).XY();
    const gp_XY m = pcurve->Value(0.5 * (t0 + t1)).XY();
    auto on = [](double x, double at, double tol) { return std::abs(x - at) <= tol; };
    auto on_u = [&](double at) {
      return on(a.X(), at, eu) && on(b.X(), at, eu) && on(m.X(), at, eu);
    };
    auto on_v = [&](double at) {
      return on(a.Y(), at, ev) && on(b.Y(), at, ev) && on(m.Y(), at, ev);
    };
    auto one_way = [](double p, double q, double r) {
      return std::min(p, r) <= q && q <= std::max(p, r);
    };
    if ((on_u(u0) || on_u(u1)) && one_way(a.Y(), m.Y(), b.Y())) {
      along += std::abs(b.Y() - a.Y());
    } else if ((on_v(v0) || on_v(v1)) && one_way(a.X(), m.X(), b.X())) {
      along += std::abs(b.X() - a.X());
    } else {
      return std::nullopt;
    }
  }
  const double perimeter = 2 * ((u1 - u0) + (v1 - v0));
  if (!(std::abs(along - perimeter) <= 1e-9 * perimeter)) return std::nullopt;
  // Each knot span integrated with degree + 4 Gauss points each way and with degree + 8: where
  // the two differ by more than kAgree of the span's area it is taken as four quarters, the same
  // way, down to kMaxDepth (a rational or strongly bent span's |Su x Sv| is far from a
  // polynomial of its degree).
  constexpr int kMaxDepth = 5;
  constexpr double kAgree = 1e-9;
  constexpr int kMaxEvaluations = 40000;  // beyond, OCCT's integration as before
  auto cuts = [](int count, const TColStd_Array1OfReal& knots, double lo, double hi) {
    std::vector<double> out{lo};
    for (int i = 1; i <= count; ++i)
      if (knots(i) > lo && knots(i) < hi) out.push_back(knots(i));
    out.push_back(hi);
    return out;
  };
  TColStd_Array1OfReal uknots(1, spline->NbUKnots()), vknots(1, spline->NbVKnots());
  spline->UKnots(uknots);
  spline->VKnots(vknots);
  const std::vector<double> us = cuts(uknots.Length(), uknots, u0, u1);
  const std::vector<double> vs = cuts(vknots.Length(), vknots, v0, v1);
  struct Rule {
    math_Vector pu, wu, pv, wv;
  };
  auto make_rule = [](int nu, int nv) {
    nu = std::min(nu, math::GaussPointsMax()), nv = std::min(nv, math::GaussPointsMax());
    Rule r{math_Vector(1, nu), math_Vector(1, nu), math_Vector(1, nv), math_Vector(1, nv)};
    math::GaussPoints(nu, r.pu), math::GaussWeights(nu, r.wu);
    math::GaussPoints(nv, r.pv), math::GaussWeights(nv, r.wv);
    return r;
  };
  const Rule low = make_rule(spline->UDegree() + 4, spline->VDegree() + 4);
  const Rule high = make_rule(spline->UDegree() + 8, spline->VDegree() + 8);
  // Through the adaptor, whose polynomial of the span at hand serves all its Gauss points: a
  // twentieth of the cost of Geom_BSplineSurface::D1 on degree 6 x 9.
  const GeomAdaptor_Surface patch(spline);
  int evaluations = 0;
  auto integrate = [&](const Rule& r, double a, double b, double c, double d) {
    double sum = 0;
    for (int p = r.pu.Lower(); p <= r.pu.Upper(); ++p) {
      const double u = 0.5 * (a + b) + 0.5 * (b - a) * r.pu(p);
      for (int q = r.pv.Lower(); q <= r.pv.Upper(); ++q) {
        const double v = 0.5 * (c + d) + 0.5 * (d - c) * r.pv(q);
        gp_Pnt x;
        gp_Vec du, dv;
        patch.D1(u, v, x, du, dv);
        sum += r.wu(p) * r.wv(q) * du.Crossed(dv).Magnitude();
      }
    }
    evaluations += r.pu.Length() * r.pv.Length();
    return sum * 0.25 * (b - a) * (d - c);
  };
  // The cell's area; NaN past the budget.
  auto cell = [&](auto&& self, double a, double b, double c, double d, int depth) -> double {
    const double coarse = integrate(low, a, b, c, d), fine = integrate(high, a, b, c, d);
    if (std::abs(fine - coarse) <= kAgree * std::abs(fine) || depth == kMaxDepth) return fine;
    if (evaluations > kMaxEvaluations) return NAN;
    const double m = 0.5 * (a + b), n = 0.5 * (c + d);
    return (self(self, a, m, c, n, depth + 1) + self(self, m, b, c, n, depth + 1)) +
           (self(self, a, m, n, d, depth + 1) + self(self, m, b, n, d, depth + 1));
  };
  double area = 0;
  for (size_t i = 0; i + 1 < us.size(); ++i) {
    for (size_t j = 0; j + 1 < vs.size(); ++j) {
      area += cell(cell, us[i], us[i + 1], vs[j], vs[j + 1], 0);
      if (!(evaluations <= kMaxEvaluations)) return std::nullopt;
    }
  }
  return area;
}

}  // namespace rdmesh
