// Refinement on analytic surfaces: plane, cylinder and sphere evaluators, no files.
#include <gtest/gtest.h>

#include <cmath>

#include "analytic_fixture.h"

namespace rdmesh {
namespace {

// A surface measured from samples like a B-spline: `inner`'s points and normals, without its
// closed-form deviation (Surface::quadric), so refinement sees the estimate's split points.
class Sampled final : public Surface {
 public:
  explicit Sampled(std::unique_ptr<Surface> inner) : inner_(std::move(inner)) {}
  Vec3 Point(double u, double v) override { return inner_->Point(u, v); }
  Vec3 Normal(double u, double v) override { return inner_->Normal(u, v); }

 private:
  std::unique_ptr<Surface> inner_;
};

using testing::AnalyticFace;
using testing::MeshRectangle;

TEST(RefineTest, PlaneGetsNoInteriorNodes) {
  AnalyticFace f;
  f.surface = MakePlaneSurface();
  EdgeGridCriteria edge;
  edge.max_sagitta = 1e-3;
  FaceCriteria face;
  face.max_deviation = 1e-3;
  MeshRectangle(&f, 0, 2, 0, 1, false, edge, face);
  // Seeds are only placed on curved faces by the face mesher; here the fixture adds them, and
  // the improvement loop must remove every one: a plane needs no interior node.
  int interior = 0;
  for (int v = 0; v < f.mesh.node_count(); ++v)
    interior += !f.mesh.fixed[v] && f.mesh.node_tri[v] >= 0;
  EXPECT_EQ(interior, 0);
  EXPECT_EQ(f.OutputTriangles(), 2);
}

TEST(RefineTest, PlaneWithMaxLengthGetsInteriorNodes) {
  AnalyticFace f;
  f.surface = MakePlaneSurface();
  EdgeGridCriteria edge;
  edge.max_length = 0.25;
  FaceCriteria face;
  face.max_length = 0.25;
  MeshRectangle(&f, 0, 1, 0, 1, false, edge, face);
  int interior = 0;
  for (int v = 0; v < f.mesh.node_count(); ++v)
    interior += !f.mesh.fixed[v] && f.mesh.node_tri[v] >= 0;
  EXPECT_GT(interior, 0);
  EXPECT_LE(f.stats.max_violation, 1.0);
}

TEST(RefineTest, CylinderUsesLongTrianglesAlongRulings) {
  // Lateral face of a cylinder r = 1, h = 4 at 1e-3 of its solid's bbox diagonal.
  const double delta = 1e-3 * std::sqrt(2 * 2 + 2 * 2 + 4 * 4);
  AnalyticFace f;
  f.surface = MakeCylinderSurface(1.0);
  EdgeGridCriteria edge;
  edge.max_sagitta = delta;
  FaceCriteria face;
  face.max_deviation = delta;
  MeshRectangle(&f, 0, 2 * M_PI, 0, 4, false, edge, face);
  // The circles need n segments with 1 - cos(pi / n) <= delta; the optimum is 2n triangles,
  // every one spanning the full height.
  int n = static_cast<int>(std::ceil(M_PI / std::acos(1 - delta)));
  EXPECT_GE(f.OutputTriangles(), 2 * n);
  EXPECT_LE(f.OutputTriangles(), 2 * n + 4);
  double measured =
      f.MeasuredDeviation([](Vec3 p) { return std::fabs(std::hypot(p.x, p.y) - 1.0); });
  EXPECT_LE(measured, 1.05 * delta);
}

TEST(RefineTest, SplitsThatFoldEveryChildAreRescuedByFlips) {
  // A strip of a cylinder r = 10 spanning 82 degrees, with a notch in one long side, and its
  // initial triangulation (from nist_ctc_02, face 64). Triangle 8-1-2 runs from one long side
  // to the notch corner; with plain splits refinement gets stuck on it, as every split folds a
  // child that leans on a long edge. Splits that flip such children's outer edges refine it.
  // (Measured from samples: the cylinder's exact deviation places splits where none folds.)
  AnalyticFace f;
  f.surface = std::make_unique<Sampled>(MakeCylinderSurface(10.0));
  Surface& s = *f.surface;
  const Vec2 uv[12] = {{4.62512, 293.532}, {4.62512, 313.612}, {4.53093, 315.140},
                       {4.53093, 344.860}, {4.62512, 346.388}, {4.62512, 360.468},
                       {3.90954, 360.468}, {3.19395, 360.468}, {3.19395, 293.532},
                       {3.90954, 293.532}, {3.43248, 327.000}, {3.90954, 327.000}};
  s.umin = 3.19395, s.umax = 4.62512, s.vmin = 293.532, s.vmax = 360.468;
  for (int v = 0; v < 12; ++v)
    f.mesh.AddNode(uv[v], s.Point(uv[v].x, uv[v].y), s.Normal(uv[v].x, uv[v].y), v < 10,
                   v < 10 ? NodeRef{0, v + 1, 0} : NodeRef{});
  const std::vector<std::array<int, 3>> tris = {{3, 6, 7},  {8, 1, 2},   {3, 7, 10},  {4, 5, 6},
                                                {4, 6, 3},  {10, 7, 8},  {1, 9, 0},   {1, 8, 9},
                                                {2, 10, 8}, {11, 3, 10}, {2, 11, 10}, {2, 3, 11}};
  // Boundary edges: consecutive nodes of the loop 0..9.
  std::vector<std::array<bool, 3>> constrained;
  for (const auto& t : tris) {
    std::array<bool, 3> c{};
    for (int i = 0; i < 3; ++i) {
      int a = t[(i + 1) % 3], b = t[(i + 2) % 3];
      c[i] = a < 10 && b < 10 && (b == (a + 1) % 10 || a == (b + 1) % 10);
    }
    constrained.push_back(c);
  }
  InitWorkMesh(tris, constrained, {}, &f.mesh);
  FaceCriteria face;
  face.max_deviation = 1.167;
  RefineFace(&f.mesh, s, face, 10.0, 1.0, 200000, true, nullptr, &f.stats);
  EXPECT_GT(f.stats.rescues, 0);
  EXPECT_LE(f.stats.max_violation, 1.0);
  double measured =
      f.MeasuredDeviation([](Vec3 p) { return std::fabs(std::hypot(p.x, p.y) - 10.0); });
  EXPECT_LE(measured, 1.05 * face.max_deviation);
  EXPECT_LE(f.OutputTriangles(), 24);
}

TEST(RefineTest, StandingFinIsRefinedAway) {
  // A quarter of a cylinder r = 1 whose first triangulation has a fin, as refinement left one on
  // nist_mbe_pmi_11's B-spline faces: a chord a-b across the curved direction, with a thin
  // triangle to c on one side and to d on the other. The fin stands against the surface (its
  // plane holds the arc), so the surface stays close to its plane while the chord lies 0.28
  // inside the cylinder: the estimate must see that and refine the fin away.
  const double delta = 1e-3, u1 = M_PI / 2;
  AnalyticFace f;
  f.surface = MakeCylinderSurface(1.0);
  Surface& s = *f.surface;
  s.umin = 0, s.umax = u1, s.vmin = 0, s.vmax = 1;
  EdgeGridCriteria edge;
  edge.max_sagitta = delta;
  std::vector<Vec2> uv;
  std::vector<std::array<int, 2>> segments;
  const Vec2 corners[4] = {{0, 0}, {u1, 0}, {u1, 1}, {0, 1}};
  for (int side = 0; side < 4; ++side) {
    testing::ParamLine line(s, corners[side], corners[(side + 1) % 4]);
    std::vector<double> ts = DiscretizeCurve(line, 0.0, 1.0, edge);
    for (size_t k = 0; k + 1 < ts.size(); ++k) {
      int n = static_cast<int>(uv.size());
      uv.push_back((1 - ts[k]) * corners[side] + ts[k] * corners[(side + 1) % 4]);
      segments.push_back({n, n + 1});
    }
  }
  segments.back()[1] = 0;
  const int a = static_cast<int>(uv.size()), b = a + 1;
  uv.insert(uv.end(), {{0.05, 0.5}, {u1 - 0.05, 0.502}, {0.8, 0.51}, {0.8, 0.49}});
  // The chord is a constraint of the triangulation only: refinement may flip or split it.
  segments.push_back({a, b});
  CdtResult cdt;
  ASSERT_TRUE(ConstrainedTriangulation(uv, segments, nullptr, &cdt).ok());
  for (size_t t = 0; t < cdt.triangles.size(); ++t)
    for (int i = 0; i < 3; ++i) {
      int p = cdt.triangles[t][(i + 1) % 3], q = cdt.triangles[t][(i + 2) % 3];
      if ((p == a && q == b) || (p == b && q == a)) cdt.constrained[t][i] = false;
    }
  for (int v = 0; v < static_cast<int>(uv.size()); ++v)
    f.mesh.AddNode(uv[v], s.Point(uv[v].x, uv[v].y), s.Normal(uv[v].x, uv[v].y), v < a,
                   v < a ? NodeRef{0, 0, 0} : NodeRef{});
  InitWorkMesh(cdt.triangles, cdt.constrained, {}, &f.mesh);
  FaceCriteria face;
  face.max_deviation = delta;
  RefineFace(&f.mesh, s, face, 1.0, 1.0, 200000, true, nullptr, &f.stats);
  EXPECT_LE(f.stats.max_violation, 1.0);
  double measured =
      f.MeasuredDeviation([](Vec3 p) { return std::fabs(std::hypot(p.x, p.y) - 1.0); });
  EXPECT_LE(measured, 1.05 * delta);
  // The strip needs n segments along the arc and 2n triangles, as a cylinder does.
  int n = static_cast<int>(std::ceil(u1 / 2 / std::acos(1 - delta)));
  EXPECT_LE(f.OutputTriangles(), 2 * n + 4);
}

// A bilinear patch twisted into a bow-tie, as SSO-4's B-spline faces are (issue 35): its
// u-direction edges run against each other (P10 - P00 = (1, 0, 0), P11 - P01 = (-0.3, 0, 0)),
// so Su vanishes on the line v = 1 / 1.3, which maps to one point, and the normal Su x Sv
// reverses across it. Every triangle across that line folds, and so does a child of each split.
class BowTie final : public Surface {
 public:
  Vec3 Point(double u, double v) override {
    const Vec3 p00{0, 0, 0}, p10{1, 0, 0}, p01{0.65, 1, 0.3}, p11{0.35, 1, 0.3};
    return (1 - v) * ((1 - u) * p00 + u * p10) + v * ((1 - u) * p01 + u * p11);
  }
};

TEST(RefineTest, AFoldThatSplitsHandOnIsLeftAndCounted) {
  AnalyticFace f;
  f.surface = std::make_unique<BowTie>();
  EdgeGridCriteria edge;
  edge.max_sagitta = 1e-3;
  FaceCriteria face;
  face.max_deviation = 1e-3;
  MeshRectangle(&f, 0, 1, 0, 1, false, edge, face);
  // Splitting on along the line would go kMaxGeneration deep (25,840 triangles); leaving a fold
  // after kFoldRun splits in a row, 210; one across which the normal jumps after one, 94.
  EXPECT_LE(f.mesh.TriangleCount(), 150);
  EXPECT_GT(f.stats.max_violation, 1.0);
  EXPECT_GT(f.stats.stuck_folds, 0);
  EXPECT_LE(f.stats.stuck_folds, f.stats.over);
  // The folds lie along the line: every triangle left folded has corners on both sides of it or
  // touches it within a split's reach.
  const double line = 1 / 1.3;
  for (int t = 0; t < static_cast<int>(f.mesh.tri.size()); ++t) {
    if (!f.mesh.alive[t]) continue;
    double lo = 1, hi = 0;
    for (int v : f.mesh.tri[t])
      lo = std::min(lo, f.mesh.uv[v].y), hi = std::max(hi, f.mesh.uv[v].y);
    Vec2 uv[3];
    Vec3 p[3], n[3];
    f.mesh.FoldCorners(f.mesh.tri[t], uv, p, n);
    if (TriangleAgreement(uv, p, n) > 0) continue;
    EXPECT_LE(lo, line + 0.25) << t;
    EXPECT_GE(hi, line - 0.25) << t;
  }
}

TEST(RefineTest, SphereNearTheoreticalMinimum) {
  // Unit sphere at 1e-3 of its bbox diagonal: the optimum is 2 * 2.418 / delta triangles.
  const double delta = 1e-3 * 2 * std::sqrt(3.0);
  AnalyticFace f;
  f.surface = MakeSphereSurface(1.0);
  EdgeGridCriteria edge;
  edge.max_sagitta = 0.8 * delta;
  FaceCriteria face;
  face.max_deviation = delta;
  MeshRectangle(&f, 0, 2 * M_PI, -M_PI / 2, M_PI / 2, true, edge, face);
  const double optimum = 2 * 2.418 / delta;
  double measured = f.MeasuredDeviation([](Vec3 p) { return std::fabs(Norm(p) - 1.0); });
  std::printf(
      "sphere: %d triangles (%.3fx optimum %.0f), deviation %.3e (asked %.3e); "
      "splits %ld edge splits %ld flips %ld collapses %ld moves %ld violation %.3f\n",
      f.OutputTriangles(), f.OutputTriangles() / optimum, optimum, measured, delta,
      (long)f.stats.splits, (long)f.stats.edge_splits, (long)f.stats.flips, (long)f.stats.collapses,
      (long)f.stats.moves, f.stats.max_violation);
  EXPECT_GE(f.OutputTriangles(), optimum);
  EXPECT_LE(f.OutputTriangles(), 1.4 * optimum);
  EXPECT_LE(measured, 1.2 * delta);
}

}  // namespace
}  // namespace rdmesh
