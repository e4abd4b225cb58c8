// Triangle measures: the early stop of MeasureTriangleBelow is a true lower bound, and when it
// measures in full it gives exactly MeasureTriangle's result; on a B-spline the estimate sees
// what happens between knot lines; on a sphere or cylinder the deviation is exact.
#include "face/measure.h"

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeFace.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_ConicalSurface.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <array>
#include <random>
#include <string>
#include <vector>

namespace rdmesh {
namespace {

// Checks MeasureTriangleBelow against MeasureTriangle: the same result when it measures in
// full (true), a lower bound at or over the limit when it stops (false).
bool BelowAgrees(Surface& s, const Vec2 uv[3], const Vec3 p[3], const FaceCriteria& c,
                 double limit) {
  TriangleMeasure full = MeasureTriangle(s, uv, p, c), m;
  if (!MeasureTriangleBelow(s, uv, p, c, limit, &m)) {
    EXPECT_GE(m.violation, limit);
    EXPECT_LE(m.violation, full.violation);
    return false;
  }
  EXPECT_EQ(m.violation, full.violation);
  EXPECT_EQ(m.deviation, full.deviation);
  EXPECT_EQ(m.rd, full.rd);
  EXPECT_EQ(m.worst_uv.x, full.worst_uv.x);
  EXPECT_EQ(m.worst_uv.y, full.worst_uv.y);
  return true;
}

TEST(MeasureTest, MeasureTriangleBelowStopsOnlyOverTheLimit) {
  std::unique_ptr<Surface> sphere = MakeSphereSurface(1.0);
  FaceCriteria c;
  c.max_deviation = 1e-3;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 6), v(-1.4, 1.4), size(1e-3, 0.5), limit(0, 50);
  int stopped = 0;
  for (int i = 0; i < 2000; ++i) {
    Vec2 q0{u(rng), v(rng)};
    double h = size(rng);
    std::uniform_real_distribution<double> d(-h, h);
    Vec2 uv[3] = {q0, {q0.x + d(rng), q0.y + d(rng)}, {q0.x + d(rng), q0.y + d(rng)}};
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = sphere->Point(uv[k].x, uv[k].y);
    stopped += !BelowAgrees(*sphere, uv, p, c, limit(rng));
  }
  EXPECT_GT(stopped, 200);
}

// z = wave(u) over [0,4]x[0,1]: cubic in u with a simple knot at 1, 2 and 3, linear in v; the
// control points alternate, so each knot span bulges on its own.
std::unique_ptr<Surface> WavySurface() {
  const double z[7] = {0, 0.5, -1, 1, -1, 0.5, 0};
  TColgp_Array2OfPnt poles(1, 7, 1, 2);
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 2; ++j) poles(i + 1, j + 1) = gp_Pnt(4.0 * i / 6, j, z[i]);
  TColStd_Array1OfReal uknots(1, 5), vknots(1, 2);
  TColStd_Array1OfInteger umults(1, 5), vmults(1, 2);
  for (int i = 0; i < 5; ++i) uknots(i + 1) = i, umults(i + 1) = (i == 0 || i == 4) ? 4 : 1;
  vknots(1) = 0, vknots(2) = 1, vmults(1) = vmults(2) = 2;
  Handle(Geom_BSplineSurface) bspline =
      new Geom_BSplineSurface(poles, uknots, vknots, umults, vmults, 3, 1);
  return MakeFaceSurface(BRepBuilderAPI_MakeFace(bspline, 1e-7).Face(), false);
}

// The largest distance of the surface over the triangle from its plane, densely sampled.
double DenseHeight(Surface& s, const Vec2 uv[3], const Vec3 p[3]) {
  Vec3 nh = Normalized(Cross(p[1] - p[0], p[2] - p[0]));
  double worst = 0;
  const int n = 60;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      double b1 = double(i) / n, b2 = double(j) / n;
      Vec2 q = (1 - b1 - b2) * uv[0] + (b1 * uv[1] + b2 * uv[2]);
      worst = std::max(worst, std::fabs(Dot(nh, s.Point(q.x, q.y) - p[0])));
    }
  return worst;
}

// Whether the estimate reads the long triangle {u0, v0}, {u1, v1}, {u0 + (u1 - u0) at, v0 + width}
// below 0.75x of its dense deviation.
bool UnderReads(Surface& s, const FaceCriteria& c, double u0, double u1, double v0, double v1,
                double at, double width) {
  Vec2 uv[3] = {{u0, v0}, {u1, v1}, {u0 + (u1 - u0) * at, v0 + width}};
  if (Orient(uv[0], uv[1], uv[2]) < 0) std::swap(uv[1], uv[2]);
  Vec3 p[3];
  for (int k = 0; k < 3; ++k) p[k] = s.Point(uv[k].x, uv[k].y);
  return MeasureTriangle(s, uv, p, c).deviation < 0.75 * DenseHeight(s, uv, p);
}

TEST(MeasureTest, SeesBulgesBetweenKnotLines) {
  std::unique_ptr<Surface> wave = WavySurface();
  ASSERT_EQ(wave->uknots.at.size(), 5u);
  FaceCriteria c;
  c.max_deviation = 1.0;  // large: every one of these triangles is measured in full
  // Long triangles across several knot spans, the kind refinement leaves on such a face: the
  // edge midpoints and centroid alone often fall where the wave crosses the chord plane.
  std::mt19937 shapes(5);
  std::uniform_real_distribution<double> start(0, 1), length(2, 3), across(0, 1), width(0.05, 0.3);
  int low = 0;
  for (int i = 0; i < 400; ++i) {
    double u0 = start(shapes), u1 = std::min(4.0, u0 + length(shapes)), v0 = across(shapes);
    double v1 = across(shapes), at = start(shapes);
    low += UnderReads(*wave, c, u0, u1, v0, v1, at, width(shapes));
  }
  EXPECT_EQ(low, 0);  // 4 of them without the knot-line samples
  // MeasureTriangleBelow agrees with it here too, knot samples included.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 4), v(0, 1), limit(0, 3);
  c.max_deviation = 0.05;
  for (int i = 0; i < 500; ++i) {
    Vec2 uv[3] = {{u(rng), v(rng)}, {u(rng), v(rng)}, {u(rng), v(rng)}};
    if (Orient(uv[0], uv[1], uv[2]) < 0) std::swap(uv[1], uv[2]);
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = wave->Point(uv[k].x, uv[k].y);
    BelowAgrees(*wave, uv, p, c, limit(rng));
  }
}

TEST(MeasureTest, SeesBothHalvesOfOnePiece) {
  std::unique_ptr<Surface> wave = WavySurface();
  FaceCriteria c;
  c.max_deviation = 1.0;
  // Long triangles within one knot span: a cubic piece can turn like an S along them, nearly
  // level with the chord plane at the edge midpoints and the centroid.
  std::mt19937 shapes(3);
  std::uniform_real_distribution<double> span(0, 4), across(0, 1), width(0.05, 0.3), at(0, 1);
  int low = 0;
  for (int i = 0; i < 400; ++i) {
    double u0 = std::floor(span(shapes)) + 0.01, u1 = u0 + 0.98, v0 = across(shapes);
    double v1 = across(shapes), where = at(shapes);
    low += UnderReads(*wave, c, u0, u1, v0, v1, where, width(shapes));
  }
  EXPECT_EQ(low, 0);
}

TEST(MeasureTest, ClosestOnTriangleFindsInteriorEdgeAndCornerPoints) {
  const Vec3 a{0, 0, 0}, b{2, 0, 0}, c{0, 2, 0};
  double w[3];
  EXPECT_DOUBLE_EQ(ClosestOnTriangle({0.5, 0.5, 3}, a, b, c, w), 3.0);  // above the inside
  EXPECT_DOUBLE_EQ(w[0], 0.5);
  EXPECT_DOUBLE_EQ(w[1], 0.25);
  EXPECT_DOUBLE_EQ(w[2], 0.25);
  EXPECT_DOUBLE_EQ(ClosestOnTriangle({1, -1, 0}, a, b, c, w), 1.0);  // beyond edge a-b
  EXPECT_DOUBLE_EQ(w[0], 0.5);
  EXPECT_DOUBLE_EQ(w[1], 0.5);
  EXPECT_DOUBLE_EQ(w[2], 0.0);
  EXPECT_DOUBLE_EQ(ClosestOnTriangle({3, 0, 0}, a, b, c, w), 1.0);  // beyond corner b
  EXPECT_DOUBLE_EQ(w[1], 1.0);
  // Degenerate: three points on a line, the nearest point of the segment they span.
  EXPECT_DOUBLE_EQ(ClosestOnTriangle({1.5, 1, 0}, a, {1, 0, 0}, b, w), 1.0);
  EXPECT_NEAR(w[0] * 0 + w[1] * 1 + w[2] * 2, 1.5, 1e-12);
}

// The largest |offset(x)| over points x of the triangle p[], densely sampled.
template <typename Offset>
double DenseMaxOffset(const Vec3 p[3], Offset offset) {
  double worst = 0;
  const int n = 80;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      double b1 = double(i) / n, b2 = double(j) / n;
      worst = std::max(worst, std::fabs(offset((1 - b1 - b2) * p[0] + (b1 * p[1] + b2 * p[2]))));
    }
  return worst;
}

// A random triangle on s, corners within a square of up to 0.6 around a point of
// [0, 6] x [-1.2, 1.2], counter-clockwise in (u,v).
void RandomTriangle(Surface& s, std::mt19937& rng, Vec2 uv[3], Vec3 p[3]) {
  std::uniform_real_distribution<double> u(0, 6), v(-1.2, 1.2), size(1e-2, 0.6);
  Vec2 q0{u(rng), v(rng)};
  double h = size(rng);
  std::uniform_real_distribution<double> d(-h, h);
  uv[0] = q0, uv[1] = {q0.x + d(rng), q0.y + d(rng)}, uv[2] = {q0.x + d(rng), q0.y + d(rng)};
  if (Orient(uv[0], uv[1], uv[2]) < 0) std::swap(uv[1], uv[2]);
  for (int k = 0; k < 3; ++k) p[k] = s.Point(uv[k].x, uv[k].y);
}

// The exact measure is never below a densely sampled point, and the samples come within 2% of it.
void ExpectMatchesDense(const TriangleMeasure& m, double dense, const std::string& what) {
  EXPECT_GE(m.deviation, dense * (1 - 1e-9)) << what;
  EXPECT_LE(m.deviation, dense * 1.02 + 1e-12) << what;
}

// Inward distance of x from the cone of reference radius 2 and semi-angle `angle` about the axis
// through o along the unit a: in x's meridian plane, from the cone's generator.
double ConeOffset(Vec3 x, Vec3 o, Vec3 a, double angle) {
  const double z = Dot(x - o, a);
  return (2.0 + z * std::tan(angle) - Norm((x - o) - z * a)) * std::cos(angle);
}

TEST(MeasureTest, SurfaceSideSeesTheSurfaceOverTheTriangle) {
  // A cylinder of radius 1, S(u,v) = (cos u, sin u, v): the triangle of (u,v) corners (0,0),
  // (0.5,0), (0.5,1) lies under an arc of 0.5 rad whose sagitta 1 - cos(0.25) is the surface's
  // largest distance from it, at the middle of the edge u = 0.25..., seen from the surface.
  auto cylinder = MakeCylinderSurface(1.0);
  const Vec2 uv[3] = {{0, 0}, {0.5, 0}, {0.5, 1}};
  Vec3 p[3];
  for (int i = 0; i < 3; ++i) p[i] = cylinder->Point(uv[i].x, uv[i].y);
  Vec2 where;
  const double sagitta = 1 - std::cos(0.25);
  const double d = SurfaceSideDeviation(*cylinder, uv, uv[0], 7, p, 1, 0.0, &where);
  EXPECT_GT(d, 0.9 * sagitta);
  EXPECT_LE(d, sagitta * (1 + 1e-9));
  // A neighbour nearer to some of the surface points can only lower it.
  Vec3 both[6] = {p[0], p[1], p[2], p[0], p[2], cylinder->Point(0, 1)};
  EXPECT_LE(SurfaceSideDeviation(*cylinder, uv, uv[0], 7, both, 2, 0.0, &where), d);
  // On a plane the surface is the triangle.
  auto plane = MakePlaneSurface();
  for (int i = 0; i < 3; ++i) p[i] = plane->Point(uv[i].x, uv[i].y);
  EXPECT_NEAR(SurfaceSideDeviation(*plane, uv, uv[0], 7, p, 1, 0.0, &where), 0, 1e-15);
}

// S(u,v) = (u, v, h exp(-((u - 0.9)^2 + v^2) / w^2)): a bump beside corner (1, 0) of a sliver
// that runs along u, as on gmsh_wrenchnut's face 6 at 1e-3 (issue 36).
class BumpSurface : public Surface {
 public:
  BumpSurface(double height, double width) : height_(height), width_(width) {}
  Vec3 Point(double u, double v) override {
    const double r2 = ((u - 0.9) * (u - 0.9) + v * v) / (width_ * width_);
    return {u, v, height_ * std::exp(-r2)};
  }

 private:
  double height_, width_;
};

TEST(MeasureTest, SurfaceSideFindsABulgeBetweenTheGridsSamples) {
  BumpSurface bump(0.05, 0.08);
  const Vec2 uv[3] = {{0, 0}, {1, 0}, {0, 0.1}};
  Vec3 p[3];
  for (int i = 0; i < 3; ++i) p[i] = bump.Point(uv[i].x, uv[i].y);
  // The surface's largest distance from the triangle, by brute force over a fine grid.
  double truth = 0;
  for (int i = 0; i <= 400; ++i)
    for (int j = 0; i + j <= 400; ++j) {
      const Vec2 q = (1 - (i + j) / 400.0) * uv[0] + (i / 400.0 * uv[1] + j / 400.0 * uv[2]);
      truth = std::max(truth, PointTriangleDistance(bump.Point(q.x, q.y), p[0], p[1], p[2]));
    }
  Vec2 where;
  // The 1/8 grid alone (no limit) steps over the bump's top.
  const double grid = SurfaceSideDeviation(bump, uv, uv[0], 7, p, 1, 0.0, &where);
  EXPECT_LT(grid, 0.9 * truth);
  // Asked whether it passes a limit below the truth, the cells around the bump are split until
  // it is found; the reading never passes the truth (every reading is a real distance).
  const double split = SurfaceSideDeviation(bump, uv, uv[0], 7, p, 1, 0.8 * truth, &where);
  EXPECT_GT(split, 0.97 * truth);
  EXPECT_LE(split, truth * (1 + 1e-9));
  // Far below the readings the cells are not split (nothing to decide there).
  EXPECT_EQ(SurfaceSideDeviation(bump, uv, uv[0], 7, p, 1, 100 * truth, &where), grid);
}

TEST(MeasureTest, SphereAndCylinderDeviationIsExact) {
  for (bool cylinder : {false, true}) {
    const double radius = 2.5;
    std::unique_ptr<Surface> s = cylinder ? MakeCylinderSurface(radius) : MakeSphereSurface(radius);
    FaceCriteria c;
    c.max_deviation = 1e-3;
    std::mt19937 rng(cylinder ? 17 : 19);
    for (int i = 0; i < 300; ++i) {
      Vec2 uv[3];
      Vec3 p[3];
      RandomTriangle(*s, rng, uv, p);
      TriangleMeasure m = MeasureTriangle(*s, uv, p, c);
      double dense = DenseMaxOffset(
          p, [&](Vec3 x) { return radius - (cylinder ? std::hypot(x.x, x.y) : Norm(x)); });
      ExpectMatchesDense(m, dense, (cylinder ? "cylinder " : "sphere ") + std::to_string(i));
    }
  }
}

TEST(MeasureTest, ConeDeviationIsExact) {
  // Semi-angles both ways (the radius growing and shrinking along the axis), reference radius 2.
  for (double angle : {0.5, -0.3}) {
    Handle(Geom_ConicalSurface) cone = new Geom_ConicalSurface(gp_Ax3(), angle, 2.0);
    std::unique_ptr<Surface> s =
        MakeFaceSurface(BRepBuilderAPI_MakeFace(cone, 0, 2 * M_PI, -1.5, 1.5, 1e-7).Face(), false);
    ASSERT_EQ(s->quadric.kind, Surface::Quadric::Kind::kCone);
    FaceCriteria c;
    c.max_deviation = 1e-3;
    std::mt19937 rng(29);
    int exact = 0;
    for (int i = 0; i < 500; ++i) {
      Vec2 uv[3];
      Vec3 p[3];
      RandomTriangle(*s, rng, uv, p);
      TriangleMeasure m = MeasureTriangle(*s, uv, p, c);
      if (!m.exact) continue;  // beyond the apex: the estimate
      ++exact;
      double dense = DenseMaxOffset(p, [&](Vec3 x) {
        return ConeOffset(x, {0, 0, 0}, {0, 0, 1}, angle);
      });
      ExpectMatchesDense(m, dense, std::to_string(angle) + " " + std::to_string(i));
    }
    EXPECT_GT(exact, 400);
  }
}

// A triangle with an edge across the cone's axis (its corners at one height, as on the parallels
// of a structured mesh): the edge's peak is where the quadratic's two roots nearly meet, which a
// discriminant computed as a difference lost to rounding in about half the cases (gmsh_solid_56
// face 11 at 1e-4: 0.049 mm measured, 0.0195 estimated).
TEST(MeasureTest, ConeDeviationIsExactOnEdgesAcrossTheAxis) {
  const double angle = 0.42;
  Handle(Geom_ConicalSurface) cone =
      new Geom_ConicalSurface(gp_Ax3(gp_Pnt(1, -2, 3), gp_Dir(0.4, 0, -0.9)), angle, 2.0);
  std::unique_ptr<Surface> s =
      MakeFaceSurface(BRepBuilderAPI_MakeFace(cone, 0, 2 * M_PI, -1.5, 1.5, 1e-7).Face(), false);
  ASSERT_EQ(s->quadric.kind, Surface::Quadric::Kind::kCone);
  FaceCriteria c;
  c.max_deviation = 1e-3;
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(0, 6), v(-1.2, 1.2), du(0.05, 0.6), dv(0.05, 0.6);
  for (int i = 0; i < 200; ++i) {
    const Vec2 q{u(rng), v(rng)};
    Vec2 uv[3] = {q, {q.x + du(rng), q.y}, {q.x + 0.5 * du(rng), q.y + dv(rng)}};
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = s->Point(uv[k].x, uv[k].y);
    TriangleMeasure m = MeasureTriangle(*s, uv, p, c);
    ASSERT_TRUE(m.exact) << i;
    const Vec3 o{1, -2, 3}, a = (1.0 / std::hypot(0.4, 0.9)) * Vec3{0.4, 0, -0.9};
    double dense = DenseMaxOffset(p, [&](Vec3 x) { return ConeOffset(x, o, a, angle); });
    ExpectMatchesDense(m, dense, std::to_string(i));
  }
}

// z = (x^2 + y^2) / 2 with x = u^3: a parametrisation so uneven that S at a point's (u,v) weights
// lands well beside it on a triangle long in u.
class UnevenParaboloid final : public Surface {
 public:
  UnevenParaboloid() { umin = 0, umax = 2, vmin = -1, vmax = 1; }
  Vec3 Point(double u, double v) override {
    const double x = u * u * u;
    return {x, v, 0.5 * (x * x + v * v)};
  }
};

// The distance from P to the paraboloid: Newton on the squared distance over (x, y).
double ToParaboloid(Vec3 P) {
  double x = P.x, y = P.y;
  for (int k = 0; k < 30; ++k) {
    const double g = 0.5 * (x * x + y * y) - P.z;
    const double fx = x - P.x + g * x, fy = y - P.y + g * y;
    const double hxx = 1 + g + x * x, hyy = 1 + g + y * y, hxy = x * y;
    const double det = hxx * hyy - hxy * hxy;
    x -= (hyy * fx - hxy * fy) / det, y -= (hxx * fy - hxy * fx) / det;
  }
  return Dist(P, {x, y, 0.5 * (x * x + y * y)});
}

TEST(MeasureTest, DenseDeviationMeasuresFromTheMeshPoints) {
  UnevenParaboloid s;
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u0(0.4, 1.0), length(0.1, 0.2), v0(-0.5, 0.5),
      width(0.01, 0.03), at(0, 1);
  int off = 0;  // triangles whose plain heights at the points' (u,v) miss the truth by over 1%
  for (int i = 0; i < 300; ++i) {
    const double a = u0(rng), b = a + length(rng), v = v0(rng);
    Vec2 uv[3] = {{a, v}, {b, v + width(rng)}, {a + (b - a) * at(rng), v + 0.15}};
    if (Orient(uv[0], uv[1], uv[2]) < 0) std::swap(uv[1], uv[2]);
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = s.Point(uv[k].x, uv[k].y);
    const Vec3 nh = Normalized(Cross(p[1] - p[0], p[2] - p[0]));
    // The truth at the points DenseDeviation samples (all edges), and the plain heights of S at
    // those points' (u,v) weights.
    double truth = 0, naive = 0;
    std::vector<std::array<double, 3>> points = {
        {1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.25, 0.25}, {0.25, 0.5, 0.25}, {0.25, 0.25, 0.5}};
    for (int e = 0; e < 3; ++e)
      for (double t : {0.25, 0.5, 0.75}) {
        std::array<double, 3> bw = {0, 0, 0};
        bw[(e + 1) % 3] = 1 - t, bw[(e + 2) % 3] = t;
        points.push_back(bw);
      }
    for (const auto& bw : points) {
      const Vec3 P = bw[0] * p[0] + (bw[1] * p[1] + bw[2] * p[2]);
      truth = std::max(truth, ToParaboloid(P));
      const Vec2 q = bw[0] * uv[0] + (bw[1] * uv[1] + bw[2] * uv[2]);
      naive = std::max(naive, std::fabs(Dot(nh, s.Point(q.x, q.y) - p[0])));
    }
    Vec2 where;
    const double dense = DenseDeviation(s, uv, p, 7, HUGE_VAL, &where);
    // Gauss-Newton with derivatives from a grid: within 1% of the distance, or a little over
    // where two steps leave it short of the nearest point.
    EXPECT_GE(dense, 0.99 * truth) << i;
    EXPECT_LE(dense, 1.05 * truth) << i;
    // Every point searched on (as a point over the final check's limit is): within 0.5%.
    const double searched = DenseDeviation(s, uv, p, 7, 0, &where);
    EXPECT_NEAR(searched, truth, 0.005 * truth) << i;
    off += std::fabs(naive - truth) > 0.01 * truth;
  }
  EXPECT_GT(off, 100);  // 122: what the plain heights read
}

// The plane z = 0 with v measured from the parabola y = x^2: S(u, v) = (u, v + u^2, 0).
class ShearedPlane final : public Surface {
 public:
  ShearedPlane() { umin = -1, umax = 2, vmin = -1, vmax = 2; }
  Vec3 Point(double u, double v) override { return {u, v + u * u, 0}; }
};

TEST(MeasureTest, DenseDeviationSearchesAcrossASliverInUV) {
  // Corners on the line v = 0 and just off it: a sliver in (u,v), but a fat triangle in the
  // plane (0,0) (1,1) (0.5,0.2501), so every point of it lies on the surface. The nearest
  // surface point to the middle of its long edge, (0.5, 0.5, 0), is at v = 0.25: some 2,500
  // times the sliver's width in v away from that point's (u,v) weights.
  ShearedPlane s;
  const Vec2 uv[3] = {{0, 0}, {1, 0}, {0.5, 1e-4}};
  Vec3 p[3];
  for (int k = 0; k < 3; ++k) p[k] = s.Point(uv[k].x, uv[k].y);
  Vec2 where;
  // Each point's first steps stay within a quarter of the sliver: 0.25 off at the long edge.
  EXPECT_GT(DenseDeviation(s, uv, p, 7, HUGE_VAL, &where), 0.2);
  // A point over `suspect` is searched in (u,v), as far as the longest side: on the surface.
  EXPECT_LT(DenseDeviation(s, uv, p, 7, 1e-9, &where), 1e-6);
}

}  // namespace
}  // namespace rdmesh
