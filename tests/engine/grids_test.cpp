// Edge grids of a whole model (grids): the limits that faces beside an edge put on its chords.

#include "grids.h"

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <GC_MakeArcOfCircle.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Wire.hxx>
#include <algorithm>
#include <cmath>
#include <gp_Ax2.hxx>
#include <gp_Circ.hxx>
#include <gp_Pln.hxx>
#include <vector>

#include "model.h"
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
  ASSERT_TRUE(BuildEdgeGrids(*model, criteria, 1, {}, nullptr, &grids).ok());
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

}  // namespace
}  // namespace rdmesh
