// OrderEdgeParameters (model/step/topology.h) against the OCCT 7.6 function it stands in for,
// StepToTopoDS_GeometricTool::UpdateParam3d: the same parameters, and the curve reversed or not
// alike, on every branch (bounded open curves, periodic, closed, B-splines closed within the
// precision or not, lines).

#include <gtest/gtest.h>

#include <GC_MakeArcOfCircle.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_Circle.hxx>
#include <Geom_Line.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <StepToTopoDS_GeometricTool.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array1OfPnt.hxx>
#include <functional>
#include <gp_Ax2.hxx>
#include <gp_Circ.hxx>
#include <gp_Lin.hxx>
#include <string>
#include <vector>

#include "model/step/topology.h"

namespace rdmesh::step {
namespace {

// A cubic B-spline through `points` (uniform knots, clamped ends).
Handle(Geom_Curve) Spline(const std::vector<gp_Pnt>& points) {
  const int n = static_cast<int>(points.size());
  TColgp_Array1OfPnt poles(1, n);
  for (int i = 0; i < n; ++i) poles(i + 1) = points[i];
  const int spans = n - 3;
  TColStd_Array1OfReal knots(1, spans + 1);
  TColStd_Array1OfInteger mults(1, spans + 1);
  for (int i = 1; i <= spans + 1; ++i) {
    knots(i) = i - 1;
    mults(i) = (i == 1 || i == spans + 1) ? 4 : 1;
  }
  return new Geom_BSplineCurve(poles, knots, mults, 3);
}

struct Case {
  std::string name;
  std::function<Handle(Geom_Curve)()> curve;  // a fresh curve for each side
  double w1, w2, preci;
};

TEST(StepEdgeParametersTest, OrdersAsOcctsStepReader) {
  const double preci = 1e-4;
  auto circle = [] { return Handle(Geom_Curve)(new Geom_Circle(gp_Ax2(), 2.0)); };
  auto open_spline = [] {
    return Spline(
        {gp_Pnt(0, 0, 0), gp_Pnt(1, 1, 0), gp_Pnt(2, -1, 0), gp_Pnt(3, 0, 1), gp_Pnt(4, 2, 0)});
  };
  // Ends 1e-5 apart: closed within `preci`, not by the curve's own resolution.
  auto nearly_closed_spline = [] {
    return Spline(
        {gp_Pnt(0, 0, 0), gp_Pnt(1, 1, 0), gp_Pnt(0, 2, 0), gp_Pnt(-1, 1, 0), gp_Pnt(1e-5, 0, 0)});
  };
  auto closed_spline = [] {
    return Spline(
        {gp_Pnt(0, 0, 0), gp_Pnt(1, 1, 0), gp_Pnt(0, 2, 0), gp_Pnt(-1, 1, 0), gp_Pnt(0, 0, 0)});
  };
  auto arc = [] {
    return Handle(Geom_Curve)(GC_MakeArcOfCircle(gp_Circ(gp_Ax2(), 1.0), 0.5, 2.0, true).Value());
  };
  auto line = [] { return Handle(Geom_Curve)(new Geom_Line(gp_Lin(gp::Origin(), gp::DX()))); };
  const std::vector<Case> cases = {
      {"circle increasing", circle, 1.0, 2.0, preci},
      {"circle across its origin", circle, 5.0, 1.0, preci},
      {"circle end at the origin", circle, 3.0, 0.0, preci},
      {"open spline, both past the ends", open_spline, -0.5, 2.5, preci},
      {"open spline, decreasing", open_spline, 1.5, 0.5, preci},
      {"open spline, one point", open_spline, 1.0, 1.0, preci},
      {"open spline, decreasing past the ends", open_spline, 9.0, -3.0, preci},
      {"nearly closed spline, end at first", nearly_closed_spline, 1.0, 0.0, preci},
      {"nearly closed spline, start at last", nearly_closed_spline, 2.0, 1.0, preci},
      {"nearly closed spline, across", nearly_closed_spline, 1.5, 0.5, preci},
      {"nearly closed spline, a coarse precision", nearly_closed_spline, 1.5, 0.5, 1e-7},
      {"closed spline, end at first", closed_spline, 1.0, 0.0, preci},
      {"closed spline, start at last", closed_spline, 2.0, 1.0, preci},
      {"closed spline, across", closed_spline, 1.5, 0.5, preci},
      {"closed spline, one point", closed_spline, 1.0, 1.0, preci},
      {"closed spline, ends within the precision", closed_spline, 1.99999, 1e-6, 1.0},
      {"arc, decreasing", arc, 1.8, 0.7, preci},
      {"arc, past the ends", arc, 0.1, 3.0, preci},
      {"line, decreasing", line, 3.0, -1.0, preci},
      {"line, one point", line, 2.0, 2.0, preci},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Handle(Geom_Curve) ours = c.curve(), occt = c.curve();
    double o1 = c.w1, o2 = c.w2, r1 = c.w1, r2 = c.w2;
    OrderEdgeParameters(ours, o1, o2, c.preci);
    StepToTopoDS_GeometricTool::UpdateParam3d(occt, r1, r2, c.preci);
    EXPECT_EQ(o1, r1);
    EXPECT_EQ(o2, r2);
    // Reversed alike: the same point at the same parameter.
    const double mid = 0.5 * (r1 + r2);
    EXPECT_EQ(ours->Value(mid).X(), occt->Value(mid).X());
    EXPECT_EQ(ours->Value(mid).Y(), occt->Value(mid).Y());
    EXPECT_EQ(ours->Value(mid).Z(), occt->Value(mid).Z());
  }
}

}  // namespace
}  // namespace rdmesh::step
