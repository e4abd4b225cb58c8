// The face mesher's reasons for a face meshed over its criteria, and what it leaves folded.
#include "face/face_mesher.h"

#include <gtest/gtest.h>

#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Line.hxx>
#include <Geom_Circle.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Geom_Line.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <cmath>
#include <gp_Ax2.hxx>
#include <gp_Ax3.hxx>
#include <string>

#include "core/geom.h"
#include "domain_fixture.h"
#include "model/model.h"
#include "rdmesh/engine.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

const char kBeyond[] = "beyond that, some triangles could not be refined";

// Gaps of edges off the surface and of pcurves off the edges, and the edges' tolerance.
BrepGaps Gaps(double edges, double trim, double tolerance) {
  BrepGaps g;
  g.edges = edges, g.trim = trim, g.tolerance = tolerance;
  return g;
}

TEST(FaceMesherTest, BrepReasonNamesTheBrepsOffsets) {
  const std::string reason = BrepReason(0.00381, Gaps(0.00761, 0, 0.00589), 0.00761);
  EXPECT_EQ(reason,
            "the B-rep prevents the requested deviation 0.00381: its edge tolerance is up to "
            "0.00589 and its edges lie up to 0.00761 off its surface");
}

TEST(FaceMesherTest, BrepReasonNamesPcurvesThatMissTheirEdges) {
  // NXP_MPL115A1 at 1e-4 (issue 35): edges on the surface, pcurves projected a turn away.
  EXPECT_EQ(BrepReason(0.000597, Gaps(2e-7, 0.366, 0.4), 0),
            "the B-rep prevents the requested deviation 0.000597: its edge tolerance is up to "
            "0.4 and its pcurves lie up to 0.366 from its edges' curves");
  // Both beyond the request: both named.
  EXPECT_EQ(BrepReason(0.001, Gaps(0.002, 0.005, 0.006), 0),
            "the B-rep prevents the requested deviation 0.001: its edge tolerance is up to "
            "0.006 and its edges lie up to 0.002 off its surface, its pcurves up to 0.005 from its "
            "edges' curves");
}

TEST(FaceMesherTest, BrepReasonSaysWhenTheMissIsMoreThanTheBrepExplains) {
  // Request 0.00381, edges 0.00581 off: up to 0.00962 is the B-rep's.
  EXPECT_EQ(BrepReason(0.00381, Gaps(0.00581, 0, 0.00414), 0.0096).find(kBeyond),
            std::string::npos);
  EXPECT_EQ(BrepReason(0.00381, Gaps(0.00581, 0, 0.00414), 0).find(kBeyond), std::string::npos);
  const std::string over = BrepReason(0.00381, Gaps(0.00581, 0, 0.00414), 0.121);
  EXPECT_NE(over.find("its edges lie up to 0.00581 off its surface; " + std::string(kBeyond)),
            std::string::npos)
      << over;
  EXPECT_NE(over.find("without folding (up to 0.121)"), std::string::npos) << over;
  // A coarse tolerance explains as much as a gap does.
  EXPECT_EQ(BrepReason(0.00067, Gaps(0.0003, 0, 0.00886), 0.009).find(kBeyond), std::string::npos);
  EXPECT_NE(BrepReason(0.00067, Gaps(0.0003, 0, 0.00886), 0.01).find(kBeyond), std::string::npos);
}

// Triangles whose normal points against the surface normals at their corners.
int FoldedTriangles(const FaceMesh& f) {
  int folded = 0;
  for (int64_t t = 0; t < f.triangle_count(); ++t) {
    const int32_t* c = &f.triangles[3 * t];
    double e[2][3], n[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i) {
      e[0][i] = f.xyz[3 * c[1] + i] - f.xyz[3 * c[0] + i];
      e[1][i] = f.xyz[3 * c[2] + i] - f.xyz[3 * c[0] + i];
      for (int k = 0; k < 3; ++k) n[i] += f.normals[3 * c[k] + i];
    }
    const double cross[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1],
                             e[0][2] * e[1][0] - e[0][0] * e[1][2],
                             e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    folded += cross[0] * n[0] + cross[1] * n[1] + cross[2] * n[2] < 0;
  }
  return folded;
}

// KiCad's Crystal_HC33-U: faces 3 and 12 are surfaces of revolution whose profile circle
// crosses their axis, so each pinches to a point inside the face and turns inside out there.
// Meshed as if they had no singular lines (FaceJob::singular_lines unset), refinement leaves
// triangles across the pinch folded; flips after it undo them (22 folded without the flips).
TEST(FaceMesherTest, FlipsUndoFoldsThatRefinementLeaves) {
  Context context;
  Result<std::shared_ptr<const Model>> model =
      LoadModel(std::string(RDMESH_TEST_DATA) + "/kicad/Crystal_HC33-U_Horizontal.step", &context);
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  const Model& m = **model;
  const double deviation = 1e-3 * GetModelInfo(m).diagonal;
  const FacePcurves pcurves = testing::Pcurves(m);
  const std::vector<EdgeGrid> grids = testing::Grids(m, deviation);
  FaceJob job;
  job.criteria.max_deviation = deviation;
  job.max_triangles = 1'000'000;
  int folded = 0, over = 0;
  for (int face : {3, 12}) {
    std::vector<NodeRef> refs;
    const FaceMesh f = MeshFace(m, pcurves, face, grids, job, nullptr, &refs);
    ASSERT_EQ(f.status, FaceStatus::kOk) << f.reason;
    EXPECT_EQ(f.surface_type, SurfaceType::kRevolution);
    folded += FoldedTriangles(f);
    over += f.reason.find("could not be refined") != std::string::npos;
  }
  EXPECT_EQ(over, 2);  // the folds are there to undo
  EXPECT_EQ(folded, 0);
}

// The same file as a run meshes it: the pinches are singular lines, kept out of the triangles,
// so nothing folds and no face is left over its criteria.
TEST(FaceMesherTest, SingularLinesLeaveNothingToUndo) {
  Context context;
  Result<std::shared_ptr<const Model>> model =
      LoadModel(std::string(RDMESH_TEST_DATA) + "/kicad/Crystal_HC33-U_Horizontal.step", &context);
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  MeshOptions options;
  options.max_deviation_rel = 1e-3;
  Result<MeshResult> result = MeshModel(**model, options);
  ASSERT_TRUE(result.ok()) << result.status().ToString();
  int folded = 0;
  for (const FaceMesh& f : result->faces) {
    EXPECT_EQ(f.reason, "") << "face " << f.face_id;
    folded += FoldedTriangles(f);
  }
  EXPECT_EQ(folded, 0);
}

// A quarter of a cylinder of radius 0.2 about the y axis, S(u,v) = (-0.2 sin u, v, -0.2 cos u),
// 5.2 long, as Fuseholder_Schurter_0031.7701's fillet (face 132): an arc at y = -2.6, and two
// lines along it (u = 0 to y = 2.6, u = pi/2 to y = 2.4) that end at one vertex, (-0.1, 2.5,
// -0.1), whose tolerance 0.174 covers both ends' 0.173. That vertex lies a quarter turn around
// the fillet from either pcurve end, and 0.059 inside the cylinder.
TopoDS_Face FilletEndingInAFarVertex() {
  constexpr double kR = 0.2, kTol = 1e-7, kFar = 0.174;
  BRep_Builder b;
  Handle(Geom_CylindricalSurface) cylinder =
      new Geom_CylindricalSurface(gp_Ax3(gp::Origin(), gp::DY(), -gp::DZ()), kR);
  TopoDS_Face face;
  b.MakeFace(face, cylinder, kTol);
  TopoDS_Vertex low0, low1, far;
  b.MakeVertex(low0, gp_Pnt(0, -2.6, -kR), kTol);
  b.MakeVertex(low1, gp_Pnt(-kR, -2.6, 0), kTol);
  b.MakeVertex(far, gp_Pnt(-0.1, 2.5, -0.1), kFar);
  // An edge of `curve` over [t0, t1] from v0 to v1, its pcurve the line (u0, v0) + t (du, dv).
  auto edge = [&](const Handle(Geom_Curve) & curve, double t0, double t1, const TopoDS_Vertex& from,
                  const TopoDS_Vertex& to, gp_Pnt2d at, gp_Dir2d along) {
    TopoDS_Edge e;
    b.MakeEdge(e, curve, kTol);
    b.UpdateEdge(e, new Geom2d_Line(at, along), face, kTol);
    b.Add(e, from.Oriented(TopAbs_FORWARD));
    b.Add(e, to.Oriented(TopAbs_REVERSED));
    b.Range(e, t0, t1);
    b.UpdateVertex(from, t0, e, BRep_Tool::Tolerance(from));
    b.UpdateVertex(to, t1, e, BRep_Tool::Tolerance(to));
    return e;
  };
  const TopoDS_Edge side0 = edge(new Geom_Line(gp_Pnt(0, 0, -kR), gp::DY()), -2.6, 2.6, low0, far,
                                 gp_Pnt2d(0, 0), gp_Dir2d(0, 1));
  const TopoDS_Edge arc = edge(new Geom_Circle(gp_Ax2(gp_Pnt(0, -2.6, 0), gp::DY(), -gp::DZ()), kR),
                               0, M_PI / 2, low0, low1, gp_Pnt2d(0, -2.6), gp_Dir2d(1, 0));
  const TopoDS_Edge side1 = edge(new Geom_Line(gp_Pnt(-kR, 0, 0), gp::DY()), -2.6, 2.4, low1, far,
                                 gp_Pnt2d(M_PI / 2, 0), gp_Dir2d(0, 1));
  TopoDS_Wire wire;
  b.MakeWire(wire);
  b.Add(wire, side0.Reversed());
  b.Add(wire, arc);
  b.Add(wire, side1);
  b.Add(face, wire);
  return face;
}

// Triangles whose normal opposes the cylinder's at the foot of their centroid (the yardstick's
// rule): the radial direction, outward.
int InvertedOnFillet(const FaceMesh& f) {
  int inverted = 0;
  for (int64_t t = 0; t < f.triangle_count(); ++t) {
    const int32_t* c = &f.triangles[3 * t];
    Vec3 p[3];
    for (int i = 0; i < 3; ++i) p[i] = {f.xyz[3 * c[i]], f.xyz[3 * c[i] + 1], f.xyz[3 * c[i] + 2]};
    const Vec3 n = Cross(p[1] - p[0], p[2] - p[0]), centroid = (1.0 / 3) * (p[0] + p[1] + p[2]);
    inverted += n.x * centroid.x + n.z * centroid.z < 0;
  }
  return inverted;
}

// Meshed from the pcurve ends, the lines' nodes near the far vertex lie beside the chord from the
// arc to it on the wrong side, and their triangles fold; the face is meshed again with the vertex
// node at the cylinder's nearest point, and none does.
TEST(FaceMesherTest, AFaceFoldedBesideAFarVertexIsMeshedFromItsNearestSurfacePoint) {
  auto model = LoadShape(FilletEndingInAFarVertex(), "far_vertex");
  ASSERT_TRUE(model);
  MeshOptions options;
  options.max_deviation = 0.0144;  // 1e-3 of the Fuseholder's diagonal
  MeshResult result = MeshOrDie(*model, options);
  ASSERT_EQ(result.faces.size(), 1u);
  const FaceMesh& f = result.faces[0];
  ASSERT_EQ(f.status, FaceStatus::kOk) << f.reason;
  EXPECT_GT(f.triangle_count(), 0);
  EXPECT_EQ(InvertedOnFillet(f), 0);
  EXPECT_NE(f.reason.find("the B-rep prevents"), std::string::npos) << f.reason;
}

}  // namespace
}  // namespace rdmesh
