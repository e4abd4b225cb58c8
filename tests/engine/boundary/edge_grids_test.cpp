// Edge grids of a whole model (grids): the limits that faces beside an edge put on its chords.

#include "boundary/edge_grids.h"

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GC_MakeArcOfCircle.hxx>
#include <GeomAPI_Interpolate.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_Circle.hxx>
#include <TColStd_HArray1OfReal.hxx>
#include <TColgp_HArray1OfPnt.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Wire.hxx>
#include <algorithm>
#include <cmath>
#include <gp_Ax2.hxx>
#include <gp_Circ.hxx>
#include <gp_Pln.hxx>
#include <vector>

#include "domain_fixture.h"
#include "model/model.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

constexpr double kHole = 2.15, kRim = 2.5;
constexpr int kRimArcs = 32;

// A flat ring 0.35 wide, like a countersink's seat: a round hole, and a rim of short arcs that
// need no more than one segment each (as teeth would), so nothing on the rim side follows the
// hole's chords.
TopoDS_Face RingWithFineRim() {
  BRepBuilderAPI_MakeWire rim;
  gp_Circ circle(gp_Ax2(gp::Origin(), gp::DZ()), kRim);
  for (int k = 0; k < kRimArcs; ++k)
    rim.Add(BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(circle, 2 * M_PI * k / kRimArcs,
                                                       2 * M_PI * (k + 1) / kRimArcs, true)
                                        .Value())
                .Edge());
  TopoDS_Wire hole =
      BRepBuilderAPI_MakeWire(
          BRepBuilderAPI_MakeEdge(gp_Circ(gp_Ax2(gp::Origin(), gp::DZ(), -gp::DX()), kHole)).Edge())
          .Wire();
  hole.Reverse();
  BRepBuilderAPI_MakeFace make(gp_Pln(gp::XOY()), rim.Wire());
  make.Add(hole);
  return make.Face();
}

// At a deviation of 0.12 the hole alone would take 10 chords with a sagitta of 0.105: their
// triangles reach over the hole by a third of the ring's width. The ring's area / perimeter is
// 0.175, so its chords may stray by half of that, 0.0875, within the plane.
TEST(GridsTest, ChordsOfANarrowFaceStayWithinAFractionOfItsWidth) {
  auto model = LoadShape(RingWithFineRim(), "narrow_ring");
  ASSERT_TRUE(model);
  GridCriteria criteria;
  criteria.max_deviation = 0.12;
  std::vector<EdgeGrid> grids;
  ASSERT_TRUE(
      BuildEdgeGrids(*model, testing::Pcurves(*model), criteria, 1, {}, nullptr, &grids).ok());
  const double area = M_PI * (kRim * kRim - kHole * kHole);
  const double perimeter = 2 * M_PI * (kRim + kHole);
  const double limit = criteria.narrow_face_fraction * area / perimeter;
  int hole_edges = 0;
  for (const EdgeGrid& g : grids) {
    ASSERT_GE(g.xyz.size(), 2u);
    if (std::fabs(Norm(g.xyz.front()) - kHole) > 1e-6) continue;
    ++hole_edges;
    double sagitta = 0;
    for (size_t k = 0; k + 1 < g.xyz.size(); ++k)
      sagitta = std::max(sagitta, kHole - Norm(0.5 * (g.xyz[k] + g.xyz[k + 1])));
    EXPECT_LE(sagitta, limit * 1.02);
    EXPECT_GT(sagitta, 0.5 * limit);  // no finer than it needs
  }
  EXPECT_EQ(hole_edges, 1);
}

// A disc of radius 1 in z = 0 whose rim's 3D curve is the same circle lifted to z = `gap` (its
// pcurve stays on the plane), as in a B-rep whose edges lie off their face within tolerance.
TopoDS_Face DiscWithLiftedRim(double gap) {
  gp_Circ circle(gp_Ax2(gp::Origin(), gp::DZ()), 1.0);
  TopoDS_Face face =
      BRepBuilderAPI_MakeFace(
          gp_Pln(gp::XOY()), BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(circle).Edge()).Wire())
          .Face();
  TopExp_Explorer ex(face, TopAbs_EDGE);
  const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
  Handle(Geom_Circle) lifted = new Geom_Circle(gp_Ax2(gp_Pnt(0, 0, gap), gp::DZ()), 1.0);
  BRep_Builder().UpdateEdge(edge, lifted, std::max(2 * gap, 1e-7));
  return face;
}

// The rim lies 0.004 off the disc's plane against a deviation of 0.01: its chords get the 0.006
// that the gap leaves (29 segments, sagitta 0.0059), not the whole 0.01 (23 segments, 0.0093),
// which with the gap would put the mesh 0.0133 off the face.
TEST(GridsTest, ChordsLeaveRoomForTheGapBetweenAnEdgeAndItsFace) {
  constexpr double kGap = 0.004, kDeviation = 0.01;
  auto model = LoadShape(DiscWithLiftedRim(kGap), "lifted_rim");
  ASSERT_TRUE(model);
  ASSERT_EQ(model->edge_count(), 1);
  GridCriteria criteria;
  criteria.max_deviation = kDeviation;
  std::vector<EdgeGrid> grids;
  ASSERT_TRUE(
      BuildEdgeGrids(*model, testing::Pcurves(*model), criteria, 1, {}, nullptr, &grids).ok());
  const EdgeGrid& g = grids[0];
  ASSERT_GE(g.xyz.size(), 4u);
  double sagitta = 0;
  for (size_t k = 0; k + 1 < g.xyz.size(); ++k) {
    const Vec3 m = 0.5 * (g.xyz[k] + g.xyz[k + 1]);
    EXPECT_NEAR(m.z, kGap, 1e-9);
    sagitta = std::max(sagitta, 1.0 - std::hypot(m.x, m.y));
  }
  EXPECT_LE(sagitta, (kDeviation - kGap) * 1.001);
  EXPECT_GT(sagitta, 0.9 * (kDeviation - kGap));  // no finer than it needs
}

// The largest radial sagitta of the chords of a disc's one rim edge of radius 1, its grid built
// at `deviation`.
void RimSagitta(const TopoDS_Face& disc, double deviation, double* sagitta) {
  auto model = LoadShape(disc, "disc");
  ASSERT_TRUE(model);
  ASSERT_EQ(model->edge_count(), 1);
  GridCriteria criteria;
  criteria.max_deviation = deviation;
  std::vector<EdgeGrid> grids;
  ASSERT_TRUE(
      BuildEdgeGrids(*model, testing::Pcurves(*model), criteria, 1, {}, nullptr, &grids).ok());
  *sagitta = 0;
  for (size_t k = 0; k + 1 < grids[0].xyz.size(); ++k)
    *sagitta = std::max(*sagitta, 1.0 - Norm(0.5 * (grids[0].xyz[k] + grids[0].xyz[k + 1])));
}

// Without the gap the same disc keeps the whole deviation for its chords.
TEST(GridsTest, ChordsOfAnEdgeOnItsFaceTakeTheWholeDeviation) {
  double sagitta = 0;
  ASSERT_NO_FATAL_FAILURE(RimSagitta(DiscWithLiftedRim(0.0), 0.01, &sagitta));
  EXPECT_LE(sagitta, 0.01 * 1.001);
  EXPECT_GT(sagitta, 0.9 * 0.01);
}

// The rim lies up to 0.1 past its surface against a deviation of 0.15: its chords get the 0.05
// that leaves (10 segments or more), not the whole 0.15 (6 segments, sagitta 0.134, which would
// put the mesh up to 0.23 off the face where it ends).
TEST(GridsTest, ChordsLeaveRoomForAnEdgePastItsSurfacesRange) {
  const TopoDS_Face face = testing::DiscPastItsSurface();
  ASSERT_FALSE(face.IsNull());
  double sagitta = 0;
  ASSERT_NO_FATAL_FAILURE(RimSagitta(face, 0.15, &sagitta));
  EXPECT_LE(sagitta, 0.05 * 1.01);
  EXPECT_GT(sagitta, 0.5 * 0.05);
}

// A plane's triangle (0,0), (1,0), (0.5,0.5) whose first edge is a B-spline that passes
// through its vertex (1,0) inside its range, runs on in a loop 0.3 long and comes back to
// (1.0005, 0.0005), where its range ends: the vertex's tolerance covers the 7e-4, as a STEP
// reader that projects the vertex onto the curve leaves it when it stops on the loop's return
// (KiCad's Bourns 8100 toroids).
TopoDS_Face TriangleWithOvershootingEdge() {
  const gp_Pnt through[] = {{0, 0, 0},   {0.5, 0, 0},   {1, 0, 0},          {1.2, -0.1, 0},
                            {1.3, 0, 0}, {1.2, 0.1, 0}, {1.0005, 0.0005, 0}};
  const int n = sizeof(through) / sizeof(through[0]);
  Handle(TColgp_HArray1OfPnt) points = new TColgp_HArray1OfPnt(1, n);
  Handle(TColStd_HArray1OfReal) params = new TColStd_HArray1OfReal(1, n);
  for (int i = 0; i < n; ++i) points->SetValue(i + 1, through[i]), params->SetValue(i + 1, i);
  GeomAPI_Interpolate interpolate(points, params, false, 1e-9);
  interpolate.Perform();
  Handle(Geom_BSplineCurve) curve = interpolate.Curve();
  BRep_Builder b;
  TopoDS_Vertex start, end, apex;
  b.MakeVertex(start, through[0], 1e-7);
  b.MakeVertex(end, through[2], 1e-3);
  b.MakeVertex(apex, gp_Pnt(0.5, 0.5, 0), 1e-7);
  TopoDS_Edge overshooting;
  b.MakeEdge(overshooting, curve, 1e-7);
  b.Add(overshooting, start.Oriented(TopAbs_FORWARD));
  b.Add(overshooting, end.Oriented(TopAbs_REVERSED));
  b.Range(overshooting, 0, n - 1);
  b.UpdateVertex(start, 0, overshooting, 1e-7);
  b.UpdateVertex(end, n - 1, overshooting, 1e-3);
  BRepBuilderAPI_MakeWire wire(overshooting, BRepBuilderAPI_MakeEdge(end, apex).Edge(),
                               BRepBuilderAPI_MakeEdge(apex, start).Edge());
  return BRepBuilderAPI_MakeFace(gp_Pln(gp::XOY()), wire.Wire()).Face();
}

// The overshooting edge's grid ends at its vertex, where its curve passes through it (parameter
// 2), and leaves the loop out: the face's triangles along it would fold over the loop's chords.
TEST(GridsTest, AGridEndsWhereItsCurvePassesThroughItsVertex) {
  auto model = LoadShape(TriangleWithOvershootingEdge(), "overshooting");
  ASSERT_TRUE(model);
  ASSERT_EQ(model->edge_count(), 3);
  GridCriteria criteria;
  criteria.max_deviation = 1e-3;
  std::vector<EdgeGrid> grids;
  ASSERT_TRUE(
      BuildEdgeGrids(*model, testing::Pcurves(*model), criteria, 1, {}, nullptr, &grids).ok());
  int overshooting = 0;
  for (const EdgeGrid& g : grids) {
    if (g.t.back() - g.t.front() < 1) continue;  // the lines (parameters up to 0.71)
    ++overshooting;
    EXPECT_NEAR(g.t.back(), 2, 1e-6);  // 6 without the trim
    EXPECT_LT(Dist(g.xyz.back(), Vec3{1, 0, 0}), 1e-9);
    for (const Vec3& x : g.xyz) EXPECT_LE(x.x, 1 + 1e-9);
  }
  EXPECT_EQ(overshooting, 1);
}

}  // namespace
}  // namespace rdmesh
