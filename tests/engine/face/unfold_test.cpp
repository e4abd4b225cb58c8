// Unfolding the first triangulation (unfold.h) on an analytic cylinder: a seed whose Delaunay fan
// reaches around the cylinder folds in 3D until flips and bisections retract it.
#include "face/unfold.h"

#include <gtest/gtest.h>

#include <cmath>

#include "face/cdt.h"
#include "face/measure.h"
#include "face/refine.h"

namespace rdmesh {
namespace {

int FoldedTriangles(const WorkMesh& m) {
  int folded = 0;
  for (size_t t = 0; t < m.tri.size(); ++t) {
    if (!m.alive[t]) continue;
    Vec2 uv[3];
    Vec3 p[3], n[3];
    m.FoldCorners(m.tri[t], uv, p, n);
    folded += TriangleAgreement(uv, p, n) <= 0;
  }
  return folded;
}

// Three quarters of a cylinder r = 1, 20 long: 19 nodes along each end circle, one segment
// along each straight side, and (with `seed`) one interior node near a side. The domain is a
// tall strip in (u,v), so the Delaunay triangulation fans the seed out to every node of both
// circles.
void BuildStrip(Surface& s, bool seed, WorkMesh* m) {
  const double u1 = 1.5 * M_PI, v1 = 20;
  s.umin = 0, s.umax = u1, s.vmin = 0, s.vmax = v1;
  std::vector<Vec2> uv;
  const int n = 18;
  for (int k = 0; k <= n; ++k) uv.push_back({u1 * k / n, 0});
  for (int k = n; k >= 0; --k) uv.push_back({u1 * k / n, v1});
  std::vector<std::array<int, 2>> segments;
  for (int i = 0; i < static_cast<int>(uv.size()); ++i)
    segments.push_back({i, (i + 1) % static_cast<int>(uv.size())});
  const int boundary = static_cast<int>(uv.size());
  if (seed) uv.push_back({0.2, 10});
  CdtResult cdt;
  ASSERT_TRUE(ConstrainedTriangulation(uv, segments, nullptr, &cdt).ok());
  for (int i = 0; i < static_cast<int>(uv.size()); ++i)
    m->AddNode(uv[i], s.Point(uv[i].x, uv[i].y), s.Normal(uv[i].x, uv[i].y), i < boundary,
               i < boundary ? NodeRef{0, 0, 0} : NodeRef{});
  InitWorkMesh(cdt.triangles, cdt.constrained, {}, m);
}

TEST(UnfoldTest, SeedFanAroundCylinderUnfolds) {
  std::unique_ptr<Surface> s = MakeCylinderSurface(1.0);
  WorkMesh m;
  BuildStrip(*s, true, &m);
  ASSERT_GT(FoldedTriangles(m), 0);  // the reproducer: the fan folds
  EXPECT_GT(UnfoldInitialMesh(&m, *s, 1.0, 1.0), 0);
  EXPECT_EQ(FoldedTriangles(m), 0);
  // Refinement then meets the criteria with no fold left.
  FaceCriteria c;
  c.max_deviation = 1e-2;
  RefineStats stats;
  ASSERT_TRUE(RefineFace(&m, *s, c, 1.0, 1.0, 100000, true, nullptr, &stats).ok());
  EXPECT_LE(stats.max_violation, 1.0);
  EXPECT_EQ(FoldedTriangles(m), 0);
}

TEST(UnfoldTest, FoldFreeMeshIsLeftAlone) {
  std::unique_ptr<Surface> s = MakeCylinderSurface(1.0);
  WorkMesh m;
  BuildStrip(*s, false, &m);
  ASSERT_EQ(FoldedTriangles(m), 0);
  const auto tri = m.tri;
  EXPECT_EQ(UnfoldInitialMesh(&m, *s, 1.0, 1.0), 0);
  EXPECT_EQ(m.tri, tri);
}

}  // namespace
}  // namespace rdmesh
