// The offset surface and the bend test behind meshing off the surface.
#include "geometry/offset_surface.h"

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepTools.hxx>
#include <Geom_BSplineSurface.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <cmath>
#include <vector>

#include "geometry/surface.h"

namespace rdmesh {
namespace {

std::vector<Vec2> Grid(const Surface& s, int n) {
  std::vector<Vec2> out;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      out.push_back(
          {s.umin + (i + 0.5) / n * (s.umax - s.umin), s.vmin + (j + 0.5) / n * (s.vmax - s.vmin)});
  return out;
}

int Side(Surface& s) {
  return BendSide(s, Grid(s, 5), 1e-4 * (s.umax - s.umin), 1e-4 * (s.vmax - s.vmin), 0.02);
}

TopoDS_Face SphereFace() {
  TopExp_Explorer ex(BRepPrimAPI_MakeSphere(2.0).Shape(), TopAbs_FACE);
  return TopoDS::Face(ex.Current());
}

// z = x y over [-1, 1]^2: a saddle, as a bilinear B-spline patch.
TopoDS_Face SaddleFace() {
  TColgp_Array2OfPnt poles(1, 2, 1, 2);
  for (int i = 1; i <= 2; ++i)
    for (int j = 1; j <= 2; ++j) {
      const double x = i == 1 ? -1 : 1, y = j == 1 ? -1 : 1;
      poles(i, j) = gp_Pnt(x, y, x * y);
    }
  TColStd_Array1OfReal knots(1, 2);
  knots(1) = 0, knots(2) = 1;
  TColStd_Array1OfInteger mults(1, 2);
  mults(1) = mults(2) = 2;
  Handle(Geom_BSplineSurface) s = new Geom_BSplineSurface(poles, knots, knots, mults, mults, 1, 1);
  return BRepBuilderAPI_MakeFace(s, 1e-7);
}

TEST(BendSideTest, SphereBendsOneWaySaddleBothPlaneNone) {
  auto sphere = MakeFaceSurface(SphereFace(), false);
  // OCCT's sphere is parametrised with outward normals: it bends away from them.
  EXPECT_EQ(Side(*sphere), +1);
  auto nurbs = MakeFaceSurface(SphereFace(), true);
  EXPECT_EQ(Side(*nurbs), +1);
  auto saddle = MakeFaceSurface(SaddleFace(), false);
  EXPECT_EQ(Side(*saddle), 0);
  auto plane = MakePlaneSurface();
  EXPECT_EQ(Side(*plane), 0);
  // A cylinder parametrised as S(u,v) = (r cos u, r sin u, v): Su x Sv points outward.
  auto cylinder = MakeCylinderSurface(1.5);
  cylinder->umin = 0, cylinder->umax = 2 * M_PI, cylinder->vmin = 0, cylinder->vmax = 1;
  EXPECT_EQ(Side(*cylinder), +1);
}

TEST(OffsetSurfaceTest, SphereOffsetIsTheSphereOfTheOffsetRadius) {
  for (bool nurbs : {false, true}) {
    auto sphere = MakeFaceSurface(SphereFace(), nurbs);
    auto offset = MakeOffsetSurface(sphere.get(), 0.01);
    if (!nurbs) {
      EXPECT_EQ(offset->quadric.kind, Surface::Quadric::Kind::kSphere);
      EXPECT_NEAR(offset->quadric.radius, 2.01, 1e-15);
    }
    for (Vec2 q : Grid(*sphere, 7)) {
      const Vec3 p = offset->Point(q.x, q.y);
      EXPECT_NEAR(Norm(p), 2.01, nurbs ? 1e-6 : 1e-12) << q.x << " " << q.y;
      const Vec3 n = offset->Normal(q.x, q.y), m = sphere->Normal(q.x, q.y);
      EXPECT_EQ(n.x, m.x);
      EXPECT_EQ(n.z, m.z);
    }
  }
}

TEST(OffsetSurfaceTest, InwardOffsetOfACylinder) {
  auto cylinder = MakeCylinderSurface(1.5);
  auto offset = MakeOffsetSurface(cylinder.get(), -0.25);
  const Vec3 p = offset->Point(0.7, 0.3);
  EXPECT_NEAR(std::hypot(p.x, p.y), 1.25, 1e-6);
  EXPECT_NEAR(p.z, 0.3, 1e-9);
}

// A grid of 2 x 1 cells over [0, 2] x [0, 1]: bilinear inside, its edge values beyond it.
TEST(UvGridTest, BilinearInsideConstantBeyond) {
  UvGrid g{0.0, 0.0, 1.0, 1.0, 2, 1, {}};
  // node (i, j) at i * 2 + j: value i + 10 j
  for (int i = 0; i <= 2; ++i)
    for (int j = 0; j <= 1; ++j) g.values.push_back(i + 10.0 * j);
  EXPECT_DOUBLE_EQ(g.At(0, 0), 0);
  EXPECT_DOUBLE_EQ(g.At(2, 1), 12);
  EXPECT_DOUBLE_EQ(g.At(0.5, 0.5), 5.5);
  EXPECT_DOUBLE_EQ(g.At(1.25, 0.2), 3.25);
  EXPECT_DOUBLE_EQ(g.At(-3, 0.5), 5);  // clamped to u = 0
  EXPECT_DOUBLE_EQ(g.At(9, 2), 12);    // clamped to the far corner
}

// S + offsets(u,v) n on a cylinder: the radius follows the grid, the normal is the base's.
TEST(OffsetSurfaceTest, FieldOffsetFollowsItsGrid) {
  auto cylinder = MakeCylinderSurface(1.5);
  UvGrid g{0.0, 0.0, 1.0, 1.0, 1, 1, {0.0, 0.0, 0.2, 0.2}};  // 0 at u = 0, 0.2 at u = 1
  auto offset = MakeFieldOffsetSurface(cylinder.get(), &g);
  for (double u : {0.0, 0.5, 1.0, 3.0}) {
    const Vec3 p = offset->Point(u, 0.3);
    EXPECT_NEAR(std::hypot(p.x, p.y), 1.5 + 0.2 * std::min(u, 1.0), 1e-6) << u;
    EXPECT_NEAR(p.z, 0.3, 1e-9);
    const Vec3 n = offset->Normal(u, 0.3), m = cylinder->Normal(u, 0.3);
    EXPECT_NEAR(Dist(n, m), 0, 1e-12);
  }
}

}  // namespace
}  // namespace rdmesh
