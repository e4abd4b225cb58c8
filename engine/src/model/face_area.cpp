#include "model/face_area.h"

#include <BRep_Tool.hxx>
#include <Geom2d_Circle.hxx>
#include <Geom2d_Line.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <algorithm>
#include <cmath>
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

}  // namespace rdmesh
