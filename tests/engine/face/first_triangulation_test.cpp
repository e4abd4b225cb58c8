// A face's first triangulation (first_triangulation.h), and the face mesher's last retry from a
// start that follows the surface's turn, on a cylinder like a KiCad potentiometer's shaft
// (issue 35): radius 0.23, 5.34 long, its seam split by a vertex 0.46 from the top, where the
// seam vertex fans over half the circle and refinement used to get stuck at 77x the deviation.
#include "face/first_triangulation.h"

#include <gtest/gtest.h>

#include <BRepAdaptor_Surface.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepTools_ReShape.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <Geom2d_Line.hxx>
#include <Geom_Line.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <cmath>
#include <map>
#include <memory>

#include "domain_fixture.h"
#include "face/measure.h"
#include "model/model.h"
#include "rdmesh/engine.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

constexpr double kRadius = 0.23, kLength = 5.34, kSplit = 4.88;

// A seam edge from `a` to `b` (both on the line x = kRadius, y = 0) on `face`, its pcurves at
// u = 2 pi (FORWARD) and u = 0.
TopoDS_Edge SeamPiece(const TopoDS_Vertex& a, const TopoDS_Vertex& b, const TopoDS_Face& face) {
  const gp_Pnt pa = BRep_Tool::Pnt(a), pb = BRep_Tool::Pnt(b);
  BRep_Builder builder;
  TopoDS_Edge edge;
  builder.MakeEdge(edge, new Geom_Line(pa, gp::DZ()), 1e-7);
  builder.Add(edge, a.Oriented(TopAbs_FORWARD));
  builder.Add(edge, b.Oriented(TopAbs_REVERSED));
  builder.Range(edge, 0, pb.Z() - pa.Z());
  builder.UpdateEdge(edge, new Geom2d_Line(gp_Pnt2d(2 * M_PI, pa.Z()), gp::DY2d()),
                     new Geom2d_Line(gp_Pnt2d(0, pa.Z()), gp::DY2d()), face, 1e-7);
  return edge;
}

// The cylinder with its side's seam in two edges, split at z = kSplit.
TopoDS_Shape ShaftWithSplitSeam() {
  const TopoDS_Shape solid = BRepPrimAPI_MakeCylinder(kRadius, kLength).Shape();
  TopoDS_Face side;
  for (TopExp_Explorer fx(solid, TopAbs_FACE); fx.More(); fx.Next())
    if (BRepAdaptor_Surface(TopoDS::Face(fx.Current())).GetType() == GeomAbs_Cylinder)
      side = TopoDS::Face(fx.Current());
  const TopoDS_Face old = TopoDS::Face(side.Oriented(TopAbs_FORWARD));
  TopLoc_Location location;
  BRep_Builder builder;
  TopoDS_Face face;
  builder.MakeFace(face, BRep_Tool::Surface(old, location), location, 1e-7);
  TopoDS_Edge seam;
  std::vector<TopoDS_Edge> circles;
  for (TopExp_Explorer ex(old, TopAbs_EDGE); ex.More(); ex.Next()) {
    const TopoDS_Edge& e = TopoDS::Edge(ex.Current());
    if (BRep_Tool::IsClosed(e, old)) {
      seam = e;
      continue;
    }
    double first, last;
    builder.UpdateEdge(e, BRep_Tool::CurveOnSurface(e, old, first, last), face, 1e-7);
    circles.push_back(e);
  }
  TopoDS_Vertex bottom, top;
  TopExp::Vertices(TopoDS::Edge(seam.Oriented(TopAbs_FORWARD)), bottom, top);
  if (BRep_Tool::Pnt(bottom).Z() > BRep_Tool::Pnt(top).Z()) std::swap(bottom, top);
  TopoDS_Vertex middle;
  builder.MakeVertex(middle, gp_Pnt(kRadius, 0, kSplit), 1e-7);
  const TopoDS_Edge lower = SeamPiece(bottom, middle, face), upper = SeamPiece(middle, top, face);
  TopoDS_Wire wire;
  builder.MakeWire(wire);
  for (const TopoDS_Edge& c : circles) {
    double first, last;
    const bool at_bottom =
        BRep_Tool::CurveOnSurface(c, old, first, last)->Value(first).Y() < 0.5 * kLength;
    if (!at_bottom) continue;
    builder.Add(wire, c);  // u from 0 to 2 pi at v = 0
    builder.Add(wire, lower);
    builder.Add(wire, upper);
  }
  for (const TopoDS_Edge& c : circles) {
    double first, last;
    if (BRep_Tool::CurveOnSurface(c, old, first, last)->Value(first).Y() < 0.5 * kLength) continue;
    builder.Add(wire, c);  // back from 2 pi to 0 at v = kLength
    builder.Add(wire, upper.Reversed());
    builder.Add(wire, lower.Reversed());
  }
  builder.Add(face, wire);
  Handle(BRepTools_ReShape) reshape = new BRepTools_ReShape;
  reshape->Replace(side, face.Oriented(side.Orientation()));
  return reshape->Apply(solid);
}

// Triangles of the mesh whose normal opposes the face's at their nodes, and mesh edges used by
// one triangle or by more than two.
struct MeshFlaws {
  int inverted = 0, free = 0, nonmanifold = 0;
};

MeshFlaws Flaws(const MeshResult& r) {
  MeshFlaws flaws;
  for (const FaceMesh& f : r.faces) {
    for (size_t k = 0; k < f.triangles.size(); k += 3) {
      const int32_t* t = &f.triangles[k];
      Vec3 p[3], n;
      for (int i = 0; i < 3; ++i)
        p[i] = {f.xyz[3 * t[i]], f.xyz[3 * t[i] + 1], f.xyz[3 * t[i] + 2]};
      const Vec3 normal = Cross(p[1] - p[0], p[2] - p[0]);
      for (int i = 0; i < 3; ++i) {
        n = {f.normals[3 * t[i]], f.normals[3 * t[i] + 1], f.normals[3 * t[i] + 2]};
        if (Dot(normal, n) < 0) {
          ++flaws.inverted;
          break;
        }
      }
    }
  }
  std::map<std::pair<int, int>, int> uses;
  for (size_t k = 0; k < r.mesh.triangles.size(); k += 3)
    for (int i = 0; i < 3; ++i) {
      const int a = r.mesh.triangles[k + i], b = r.mesh.triangles[k + (i + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  for (const auto& [edge, n] : uses) flaws.free += n == 1, flaws.nonmanifold += n > 2;
  return flaws;
}

TEST(FirstTriangulationTest, TheTurnLimitedStartTurnsLittleAndDoesNotFold) {
  auto model = LoadShape(ShaftWithSplitSeam(), "shaft");
  ASSERT_TRUE(model);
  int side = 0;
  for (int f = 1; f <= model->face_count(); ++f)
    if (BRepAdaptor_Surface(model->face(f)).GetType() == GeomAbs_Cylinder) side = f;
  ASSERT_GT(side, 0);
  const double deviation = 1e-3 * GetModelInfo(*model).diagonal;
  FaceDomain domain;
  ASSERT_TRUE(testing::Domain(*model, side, testing::Grids(*model, deviation), &domain).ok());
  const FacePcurves pcurves = testing::Pcurves(*model);
  std::unique_ptr<Surface> surface =
      MakeFaceSurface(model->face(side), false, pcurves.Bounds(*model, side));
  const std::vector<Vec2> seeds = SeedPoints(domain, *surface);
  // The plain triangulation folds where the seam vertex fans over the circle beside it.
  auto folded = [](const WorkMesh& mesh, double max_turn, int* turned) {
    int folds = 0;
    *turned = 0;
    for (size_t t = 0; t < mesh.tri.size(); ++t) {
      if (!mesh.alive[t]) continue;
      Vec2 uv[3];
      Vec3 p[3], n[3];
      mesh.FoldCorners(mesh.tri[t], uv, p, n);
      folds += TriangleAgreement(uv, p, n) <= 0;
      for (int i = 0; i < 3; ++i)
        if (Dot(n[i], n[(i + 1) % 3]) < std::cos(max_turn) - 1e-12) {
          ++*turned;
          break;
        }
    }
    return folds;
  };
  WorkMesh plain, limited;
  ASSERT_TRUE(TriangulateDomain(domain, seeds, *surface, nullptr, &plain).ok());
  int turned = 0;
  EXPECT_GT(folded(plain, M_PI / 4, &turned), 0);
  ASSERT_TRUE(
      TurnLimitedTriangulation(domain, seeds, *surface, 0.5, M_PI / 4, 12, 2000, nullptr, &limited)
          .ok());
  EXPECT_EQ(folded(limited, M_PI / 4, &turned), 0);
  EXPECT_EQ(turned, 0);
}

TEST(FirstTriangulationTest, AStuckShaftIsRefinedFromTheTurnLimitedStart) {
  auto model = LoadShape(ShaftWithSplitSeam(), "shaft_mesh");
  ASSERT_TRUE(model);
  auto result = MeshModel(*model, MeshOptions());
  ASSERT_TRUE(result.ok()) << result.status().ToString();
  const double deviation = 1e-3 * GetModelInfo(*model).diagonal;
  for (const FaceMesh& f : result->faces) {
    EXPECT_EQ(f.status, FaceStatus::kOk) << f.reason;
    EXPECT_EQ(f.reason, "") << "face " << f.face_id;
    EXPECT_LE(f.max_deviation, deviation * (1 + 1e-9)) << "face " << f.face_id;
    // Straight along the axis: two triangles per segment of the circles (10 at this deviation).
    if (f.surface_type == SurfaceType::kCylinder) EXPECT_LE(f.triangle_count(), 40);
  }
  const MeshFlaws flaws = Flaws(*result);
  EXPECT_EQ(flaws.inverted, 0);
  EXPECT_EQ(flaws.free, 0);
  EXPECT_EQ(flaws.nonmanifold, 0);
}

}  // namespace
}  // namespace rdmesh
