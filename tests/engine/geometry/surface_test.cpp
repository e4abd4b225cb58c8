// Surface evaluators: the speed-ups (point cache, per-span B-spline adaptors) return exactly the
// values a plain evaluation returns, whatever order the points come in.
#include "geometry/surface.h"

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeRevol.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRep_Tool.hxx>
#include <GeomAPI_Interpolate.hxx>
#include <GeomAPI_PointsToBSplineSurface.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_ToroidalSurface.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TColgp_HArray1OfPnt.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace rdmesh {
namespace {

bool SameBits(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

std::vector<Vec2> Samples(const Surface& s, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(s.umin, s.umax), v(s.vmin, s.vmax);
  std::vector<Vec2> out;
  for (int i = 0; i < n; ++i) out.push_back({u(rng), v(rng)});
  // Repeats and edge midpoints, as refinement asks for them.
  for (int i = 0; i + 1 < n; i += 2) out.push_back(0.5 * (out[i] + out[i + 1]));
  for (int i = 0; i < n; i += 3) out.push_back(out[i]);
  return out;
}

TEST(SurfaceTest, PointCacheReturnsTheSurfaceValues) {
  std::unique_ptr<Surface> plain = MakeSphereSurface(2.0);
  std::unique_ptr<Surface> cached = WithPointCache(MakeSphereSurface(2.0));
  plain->umin = cached->umin = 0, plain->umax = cached->umax = 6.28;
  plain->vmin = cached->vmin = -1.5, plain->vmax = cached->vmax = 1.5;
  // Enough points to make the table grow and overwrite slots.
  for (const Vec2& q : Samples(*plain, 20000, 1)) {
    ASSERT_TRUE(SameBits(plain->Point(q.x, q.y), cached->Point(q.x, q.y)));
    ASSERT_TRUE(SameBits(plain->Normal(q.x, q.y), cached->Normal(q.x, q.y)));
  }
}

TEST(SurfaceTest, BSplineValuesDoNotDependOnTheEvaluationOrder) {
  TopoDS_Shape torus = BRepPrimAPI_MakeTorus(3.0, 1.0).Shape();
  TopoDS_Face face = TopoDS::Face(TopExp_Explorer(torus, TopAbs_FACE).Current());
  std::unique_ptr<Surface> a = MakeFaceSurface(face, true);
  std::unique_ptr<Surface> b = MakeFaceSurface(face, true);
  std::vector<Vec2> points = Samples(*a, 3000, 2);
  std::vector<Vec3> pa, na;
  for (const Vec2& q : points) pa.push_back(a->Point(q.x, q.y)), na.push_back(a->Normal(q.x, q.y));
  // The same points in another order (so other knot spans are cached at each point), one
  // evaluator per point for a few of them.
  std::vector<int> order(points.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::shuffle(order.begin(), order.end(), std::mt19937(3));
  for (int i : order) {
    const Vec2& q = points[i];
    ASSERT_TRUE(SameBits(pa[i], b->Point(q.x, q.y)));
    ASSERT_TRUE(SameBits(na[i], b->Normal(q.x, q.y)));
  }
  // Normals first on a fresh evaluator (its span adaptors see D1 before any D0).
  std::unique_ptr<Surface> c = MakeFaceSurface(face, true);
  for (int i : order) ASSERT_TRUE(SameBits(na[i], c->Normal(points[i].x, points[i].y)));
  for (int i = 0; i < 20; ++i) {
    std::unique_ptr<Surface> fresh = MakeFaceSurface(face, true);
    const Vec2& q = points[order[i]];
    EXPECT_TRUE(SameBits(pa[order[i]], fresh->Point(q.x, q.y)));
  }
  // And they are points of the torus.
  for (const Vec3& p : pa) {
    double ring = std::hypot(p.x, p.y) - 3.0;
    EXPECT_NEAR(std::hypot(ring, p.z), 1.0, 1e-6);
  }
}

// Each face of `shape` of surface type `type`, moved off the origin and tilted, evaluates to
// OCCT's values bit for bit.
void ExpectFacesMatchOcct(const TopoDS_Shape& shape, GeomAbs_SurfaceType type) {
  gp_Trsf move;
  move.SetRotation(gp_Ax1(gp_Pnt(1, 2, 3), gp_Dir(1, 1, 0.3)), 0.7);
  move.SetTranslationPart(gp_Vec(-4.5, 0.25, 12));
  TopoDS_Shape moved = BRepBuilderAPI_Transform(shape, move);
  int faces = 0;
  for (TopExp_Explorer it(moved, TopAbs_FACE); it.More(); it.Next()) {
    TopoDS_Face face = TopoDS::Face(it.Current());
    GeomAdaptor_Surface occt(BRep_Tool::Surface(face));
    if (occt.GetType() != type) continue;
    ++faces;
    std::unique_ptr<Surface> ours = MakeFaceSurface(face, false);
    for (const Vec2& q : Samples(*ours, 5000, 4)) {
      gp_Pnt p = occt.Value(q.x, q.y);
      ASSERT_TRUE(SameBits(ours->Point(q.x, q.y), {p.X(), p.Y(), p.Z()}));
    }
    // Points that share a u or a v with earlier ones (the evaluator remembers cos and sin of
    // recent parameters), in an order that revisits each row and column many times.
    std::vector<Vec2> grid = Samples(*ours, 40, 5);
    for (int pass = 0; pass < 3; ++pass) {
      for (const Vec2& a : grid) {
        for (const Vec2& b : grid) {
          gp_Pnt p = occt.Value(a.x, b.y);
          ASSERT_TRUE(SameBits(ours->Point(a.x, b.y), {p.X(), p.Y(), p.Z()}));
        }
      }
    }
  }
  EXPECT_GT(faces, 0);
}

TEST(SurfaceTest, BSplinePointsMatchOcctBitForBit) {
  // Non-rational, bicubic over many knot spans, and rational (a torus as NURBS, degree 2).
  TColgp_Array2OfPnt grid(1, 9, 1, 7);
  for (int i = 1; i <= 9; ++i)
    for (int j = 1; j <= 7; ++j)
      grid(i, j) = gp_Pnt(1.5 * i, 0.8 * j, std::sin(0.9 * i) * std::cos(1.3 * j));
  Handle(Geom_BSplineSurface) wavy = GeomAPI_PointsToBSplineSurface(grid).Surface();
  Handle(Geom_BSplineSurface) torus = GeomConvert::SurfaceToBSplineSurface(
      new Geom_ToroidalSurface(gp_Ax3(gp_Pnt(0.3, -2, 1), gp_Dir(0.2, -0.4, 1)), 3.0, 1.25));
  for (const Handle(Geom_BSplineSurface) & bspline : {wavy, torus}) {
    TopoDS_Face face = BRepBuilderAPI_MakeFace(bspline, 1e-7);
    std::unique_ptr<Surface> ours = MakeFaceSurface(face, false);
    GeomAdaptor_Surface occt(BRep_Tool::Surface(face));
    ASSERT_EQ(occt.GetType(), GeomAbs_BSplineSurface);
    // Random points, then the same points again in another order (other spans cached), and the
    // knots themselves, where the span a parameter falls in is decided.
    std::vector<Vec2> points = Samples(*ours, 5000, 6);
    std::shuffle(points.begin(), points.end(), std::mt19937(7));
    std::vector<Vec2> more = Samples(*ours, 5000, 6);
    points.insert(points.end(), more.begin(), more.end());
    for (double u : ours->uknots.at)
      for (double v : ours->vknots.at) points.push_back({u, v});
    for (const Vec2& q : points) {
      gp_Pnt p = occt.Value(q.x, q.y);
      ASSERT_TRUE(SameBits(ours->Point(q.x, q.y), {p.X(), p.Y(), p.Z()}));
    }
  }
}

TEST(SurfaceTest, BSplinePointsAtKnotsDoNotDependOnWhatCameBefore) {
  // A point on a knot line, or an ulp beside it, takes one span whatever span the evaluator met
  // last (an OCCT adaptor keeps the span it last built while the point is within it, so there the
  // order could decide which span's polynomial answers), for its point and for its normal.
  // Bicubic, 5 x 4 spans on uneven knots.
  TColgp_Array2OfPnt poles(1, 8, 1, 7);
  for (int i = 1; i <= 8; ++i)
    for (int j = 1; j <= 7; ++j)
      poles(i, j) = gp_Pnt(1.5 * i, 0.8 * j, std::sin(0.9 * i) * std::cos(1.3 * j));
  TColStd_Array1OfReal uknots(1, 6), vknots(1, 5);
  TColStd_Array1OfInteger umults(1, 6), vmults(1, 5);
  const double us[] = {0, 0.7, 1.9, 2.2, 3.6, 5.1}, vs[] = {-1, 0.3, 0.35, 1.8, 2.5};
  for (int i = 1; i <= 6; ++i) uknots(i) = us[i - 1], umults(i) = i == 1 || i == 6 ? 4 : 1;
  for (int i = 1; i <= 5; ++i) vknots(i) = vs[i - 1], vmults(i) = i == 1 || i == 5 ? 4 : 1;
  Handle(Geom_BSplineSurface) wavy =
      new Geom_BSplineSurface(poles, uknots, vknots, umults, vmults, 3, 3);
  TopoDS_Face face = BRepBuilderAPI_MakeFace(wavy, 1e-7);
  std::unique_ptr<Surface> forward = MakeFaceSurface(face, false);
  std::unique_ptr<Surface> backward = MakeFaceSurface(face, false);
  ASSERT_EQ(forward->uknots.at.size(), 6u);
  ASSERT_EQ(forward->vknots.at.size(), 5u);
  std::vector<Vec2> points;
  const double mid_v = 0.5 * (forward->vmin + forward->vmax);
  const double mid_u = 0.5 * (forward->umin + forward->umax);
  for (double k : forward->uknots.at)
    for (double u : {std::nextafter(k, -HUGE_VAL), k, std::nextafter(k, HUGE_VAL)})
      points.push_back({u, mid_v});
  for (double k : forward->vknots.at)
    for (double v : {std::nextafter(k, -HUGE_VAL), k, std::nextafter(k, HUGE_VAL)})
      points.push_back({mid_u, v});
  std::vector<Vec3> ahead, normals;
  for (const Vec2& q : points) {
    ahead.push_back(forward->Point(q.x, q.y));
    normals.push_back(forward->Normal(q.x, q.y));
  }
  for (size_t i = points.size(); i-- > 0;) {
    const Vec2& q = points[i];
    ASSERT_TRUE(SameBits(ahead[i], backward->Point(q.x, q.y))) << i;
    ASSERT_TRUE(SameBits(normals[i], backward->Normal(q.x, q.y))) << i;
    std::unique_ptr<Surface> fresh = MakeFaceSurface(face, false);
    ASSERT_TRUE(SameBits(normals[i], fresh->Normal(q.x, q.y))) << i;
    ASSERT_TRUE(SameBits(ahead[i], fresh->Point(q.x, q.y))) << i;
  }
  // Normals after points spread over every span, so that each slot served other spans first.
  std::unique_ptr<Surface> busy = MakeFaceSurface(face, false);
  for (const Vec2& q : Samples(*busy, 500, 8)) busy->Normal(q.x, q.y);
  for (size_t i = points.size(); i-- > 0;)
    ASSERT_TRUE(SameBits(normals[i], busy->Normal(points[i].x, points[i].y))) << i;
  // Beside a knot the two spans' polynomials agree to rounding: the surface is continuous.
  GeomAdaptor_Surface occt(wavy);
  for (size_t i = 0; i < points.size(); ++i) {
    gp_Pnt p = occt.Value(points[i].x, points[i].y);
    EXPECT_LT(Dist(ahead[i], {p.X(), p.Y(), p.Z()}), 1e-12) << i;
  }
}

TEST(SurfaceTest, SphereMatchesOcctBitForBit) {
  ExpectFacesMatchOcct(BRepPrimAPI_MakeSphere(gp_Pnt(0.3, -2, 1), 7.25).Shape(), GeomAbs_Sphere);
}

TEST(SurfaceTest, TorusMatchesOcctBitForBit) {
  gp_Ax2 axis(gp_Pnt(0.3, -2, 1), gp_Dir(0.2, -0.4, 1));
  ExpectFacesMatchOcct(BRepPrimAPI_MakeTorus(axis, 3.5, 1.25).Shape(), GeomAbs_Torus);
  // Where ElSLib rounds a coordinate near 0 to 0: the quarter turns.
  Handle(Geom_ToroidalSurface) torus = new Geom_ToroidalSurface(gp_Ax3(axis), 3.5, 1.25);
  TopoDS_Face face = BRepBuilderAPI_MakeFace(torus, 1e-7);
  std::unique_ptr<Surface> ours = MakeFaceSurface(face, false);
  for (int i = -4; i <= 4; ++i) {
    for (int j = -4; j <= 4; ++j) {
      const double u = i * M_PI / 2, v = j * M_PI / 2;
      gp_Pnt p = torus->Value(u, v);
      ASSERT_TRUE(SameBits(ours->Point(u, v), {p.X(), p.Y(), p.Z()})) << i << " " << j;
    }
  }
}

TEST(SurfaceTest, PlaneCylinderAndConeMatchOcctBitForBit) {
  gp_Ax2 axis(gp_Pnt(0.3, -2, 1), gp_Dir(0.2, -0.4, 1));
  ExpectFacesMatchOcct(BRepPrimAPI_MakeBox(axis, 3.5, 1.25, 7).Shape(), GeomAbs_Plane);
  ExpectFacesMatchOcct(BRepPrimAPI_MakeCylinder(axis, 2.75, 9.5).Shape(), GeomAbs_Cylinder);
  ExpectFacesMatchOcct(BRepPrimAPI_MakeCone(axis, 3.25, 1.5, 6).Shape(), GeomAbs_Cone);
}

TEST(SurfaceTest, RevolutionMatchesOcctBitForBit) {
  // A B-spline profile beside the axis, turned three quarters of the way round (the sweep makes
  // a Geom_SurfaceOfRevolution of it).
  Handle(TColgp_HArray1OfPnt) points = new TColgp_HArray1OfPnt(1, 6);
  const double xs[] = {1.0, 1.6, 1.3, 2.2, 1.9, 1.2}, zs[] = {0, 0.7, 1.5, 2.1, 3.0, 3.4};
  for (int i = 1; i <= 6; ++i) points->SetValue(i, gp_Pnt(xs[i - 1], 0, zs[i - 1]));
  GeomAPI_Interpolate profile(points, false, 1e-9);
  profile.Perform();
  const TopoDS_Edge edge = BRepBuilderAPI_MakeEdge(profile.Curve()).Edge();
  const TopoDS_Shape turned = BRepPrimAPI_MakeRevol(edge, gp::OZ(), 1.5 * M_PI).Shape();
  ExpectFacesMatchOcct(turned, GeomAbs_SurfaceOfRevolution);
}

}  // namespace
}  // namespace rdmesh
