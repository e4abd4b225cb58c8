// Faces whose surface collapses along an iso-line inside them (issue 35: KiCad's HC33 crystal can,
// a surface of revolution whose profile circle crosses its axis; SSO-4's bow-tie B-spline
// chamfers): found, and meshed with no triangle across the line, so none folds.

#include "geometry/singular_lines.h"

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRep_Tool.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <GeomLProp_SLProps.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Circle.hxx>
#include <Geom_SurfaceOfRevolution.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <cmath>
#include <vector>

#include "model/model.h"
#include "rdmesh/engine.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

// An apple torus's quarter: the circle of radius 0.7 about the origin in z = 0 turned about the
// line y = -0.625 along x, which it crosses at x = +-0.3152 (v where 0.7 sin v = -0.625).
TopoDS_Face AppleQuarter() {
  Handle(Geom_Circle) profile = new Geom_Circle(gp_Ax2(gp::Origin(), gp::DZ(), gp::DX()), 0.7);
  Handle(Geom_SurfaceOfRevolution) surface =
      new Geom_SurfaceOfRevolution(profile, gp_Ax1(gp_Pnt(0, -0.625, 0), gp::DX()));
  return BRepBuilderAPI_MakeFace(surface, 0, M_PI / 2, M_PI / 2, 5 * M_PI / 2, 1e-7).Face();
}

// A planar bilinear patch twisted into a bow-tie (SSO-4's chamfers): P10 - P00 = (1, 0, 0) and
// P11 - P01 = (-0.3, 0, 0) run against each other, so the iso-line v = 1 / 1.3 is one point.
TopoDS_Face BowTie() {
  TColgp_Array2OfPnt poles(1, 2, 1, 2);
  poles(1, 1) = gp_Pnt(0, 0, 0), poles(2, 1) = gp_Pnt(1, 0, 0);
  poles(1, 2) = gp_Pnt(0.65, 1, 0.3), poles(2, 2) = gp_Pnt(0.35, 1, 0.3);
  TColStd_Array1OfReal knots(1, 2);
  knots(1) = 0, knots(2) = 1;
  TColStd_Array1OfInteger mults(1, 2);
  mults(1) = mults(2) = 2;
  Handle(Geom_BSplineSurface) surface =
      new Geom_BSplineSurface(poles, knots, knots, mults, mults, 1, 1);
  return BRepBuilderAPI_MakeFace(surface, 1e-7).Face();
}

// The yardstick's rule: a triangle is inverted when its normal opposes the surface normal at
// the foot of its centroid.
int Inverted(const TopoDS_Face& face, const FaceMesh& f) {
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face);
  int bad = 0;
  for (size_t k = 0; k < f.triangles.size(); k += 3) {
    gp_XYZ p[3];
    for (int i = 0; i < 3; ++i) {
      const double* x = &f.xyz[3 * f.triangles[k + i]];
      p[i] = gp_XYZ(x[0], x[1], x[2]);
    }
    const gp_Vec normal = gp_Vec(p[1] - p[0]).Crossed(gp_Vec(p[2] - p[0]));
    GeomAPI_ProjectPointOnSurf foot(gp_Pnt((p[0] + p[1] + p[2]) / 3), surface);
    if (foot.NbPoints() == 0) continue;
    double u, v;
    foot.LowerDistanceParameters(u, v);
    GeomLProp_SLProps props(surface, u, v, 1, 1e-9);
    if (!props.IsNormalDefined()) continue;
    gp_Vec n(props.Normal());
    if (face.Orientation() == TopAbs_REVERSED) n.Reverse();
    bad += normal.Dot(n) < 0;
  }
  return bad;
}

// Triangles with (u,v) corners strictly on both sides of the line.
int Across(const FaceMesh& f, const SingularLine& line) {
  int across = 0;
  for (size_t k = 0; k < f.triangles.size(); k += 3) {
    bool below = false, above = false;
    for (int i = 0; i < 3; ++i) {
      const double c = f.uv[2 * f.triangles[k + i] + (line.axis == 0 ? 1 : 0)] - line.at;
      below = below || c < -1e-9, above = above || c > 1e-9;
    }
    across += below && above;
  }
  return across;
}

// `area`: the face's exact area, or 0 for OCCT's.
void ExpectMeshedWithoutFolds(const TopoDS_Face& face, const std::string& name,
                              const std::vector<SingularLine>& lines, double area) {
  auto model = LoadShape(face, name);
  ASSERT_TRUE(model);
  ASSERT_EQ(model->face_count(), 1);
  MeshResult r = MeshOrDie(*model);
  ASSERT_EQ(r.faces.size(), 1u);
  const FaceMesh& f = r.faces[0];
  EXPECT_EQ(f.status, FaceStatus::kOk) << f.reason;
  EXPECT_EQ(f.reason, "");
  EXPECT_GT(f.triangle_count(), 0);
  const double deviation = 1e-3 * GetModelInfo(*model).diagonal;
  EXPECT_LE(f.max_deviation, deviation * (1 + 1e-9));
  for (const SingularLine& line : lines) EXPECT_EQ(Across(f, line), 0) << "line at " << line.at;
  EXPECT_EQ(Inverted(model->face(1), f), 0);
  // The mesh covers the face once: its area within 1% of the exact one.
  if (area == 0) area = f.exact_area;
  EXPECT_NEAR(f.area, area, 0.01 * area);
}

TEST(SingularLinesTest, AnAppleTorusHasTwoWhereItsProfileCrossesTheAxis) {
  const TopoDS_Face face = AppleQuarter();
  const std::vector<SingularLine> lines =
      FindSingularLines(face, {0, M_PI / 2, M_PI / 2, 5 * M_PI / 2});
  ASSERT_EQ(lines.size(), 2u);
  const double s = std::asin(0.625 / 0.7);
  EXPECT_EQ(lines[0].axis, 0);
  EXPECT_EQ(lines[1].axis, 0);
  EXPECT_NEAR(lines[0].at, M_PI + s, 1e-12);
  EXPECT_NEAR(lines[1].at, 2 * M_PI - s, 1e-12);
}

TEST(SingularLinesTest, ABowTieHasOneAndAPlainPatchNone) {
  std::vector<SingularLine> lines = FindSingularLines(BowTie(), {0, 1, 0, 1});
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].axis, 0);
  EXPECT_NEAR(lines[0].at, 1 / 1.3, 1e-12);
  // Turned about the axis it does not cross (a torus's tube clear of its axis): none.
  Handle(Geom_Circle) profile = new Geom_Circle(gp_Ax2(gp::Origin(), gp::DZ(), gp::DX()), 0.5);
  Handle(Geom_SurfaceOfRevolution) clear =
      new Geom_SurfaceOfRevolution(profile, gp_Ax1(gp_Pnt(0, -0.625, 0), gp::DX()));
  EXPECT_TRUE(FindSingularLines(BRepBuilderAPI_MakeFace(clear, 0, 1, 0, 2 * M_PI, 1e-7).Face(),
                                {0, 1, 0, 2 * M_PI})
                  .empty());
}

TEST(SingularLinesTest, AnAppleTorusMeshesWithoutFolds) {
  const TopoDS_Face face = AppleQuarter();
  ExpectMeshedWithoutFolds(face, "apple",
                           FindSingularLines(face, {0, M_PI / 2, M_PI / 2, 5 * M_PI / 2}), 0);
}

TEST(SingularLinesTest, ABowTieMeshesWithoutFolds) {
  const TopoDS_Face face = BowTie();
  // Two triangles, (P00, P10, Q) and (Q, P01, P11) in the plane z = 0.3 y: 0.4377. OCCT's
  // integral of |Su x Sv| reads 1% less (0.4334) across the kink at the line.
  const double v = 1 / 1.3, area = 0.5 * std::sqrt(1.09) * (v + 0.3 * (1 - v));
  ExpectMeshedWithoutFolds(face, "bowtie", FindSingularLines(face, {0, 1, 0, 1}), area);
}

}  // namespace
}  // namespace rdmesh
