// Healing of edge grids (heal.h) on whole solids: grids that fit every face are left alone; a
// split lands on the edge's curve, keeps every earlier point and clears the conflicts of all the
// faces on the edge; the result does not depend on the thread count; a stop is honoured.
#include "boundary/heal.h"

#include <gtest/gtest.h>

#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <algorithm>
#include <cmath>
#include <vector>

#include "boundary/edge_grids.h"
#include "boundary/face_domain.h"
#include "domain_fixture.h"
#include "model/model.h"
#include "rdmesh/engine.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

using testing::AllFaces;
using testing::DiscWithHole;
using testing::Domain;
using testing::Grids;
using testing::Pcurves;

int FacesWithConflicts(const Model& model, const std::vector<EdgeGrid>& grids) {
  int n = 0;
  for (int f = 1; f <= model.face_count(); ++f) {
    FaceDomain domain;
    EXPECT_TRUE(Domain(model, f, grids, &domain).ok()) << "face " << f;
    n += !FindConflicts(domain).empty();
  }
  return n;
}

// The disc with a hole, extruded by 1 along z: its top and bottom faces have the disc's
// conflict at a deviation of 1, and share each circle with a cylindrical face.
std::shared_ptr<const Model> Ring() {
  return LoadShape(BRepPrimAPI_MakePrism(DiscWithHole(), gp_Vec(0, 0, 1)).Shape(), "ring");
}

TEST(HealTest, GridsThatFitEveryFaceAreLeftAlone) {
  auto model = LoadShape(BRepPrimAPI_MakeBox(2, 1, 1).Shape(), "box");
  ASSERT_TRUE(model);
  std::vector<EdgeGrid> grids = Grids(*model, 0.01);
  const std::vector<EdgeGrid> before = grids;
  HealStats stats;
  ASSERT_TRUE(
      HealEdgeGrids(*model, Pcurves(*model), AllFaces(*model), false, 1, nullptr, &grids, &stats)
          .ok());
  EXPECT_EQ(stats.rounds, 1);
  EXPECT_EQ(stats.splits, 0);
  ASSERT_EQ(grids.size(), before.size());
  for (size_t e = 0; e < grids.size(); ++e) EXPECT_EQ(grids[e].t, before[e].t) << "edge " << e + 1;
}

TEST(HealTest, SplitsLandOnTheCurveAndClearEveryFaceOnTheEdge) {
  auto model = Ring();
  ASSERT_TRUE(model);
  std::vector<EdgeGrid> grids = Grids(*model, 1.0);
  const std::vector<EdgeGrid> before = grids;
  ASSERT_GE(FacesWithConflicts(*model, grids), 2);  // the top and the bottom
  HealStats stats;
  ASSERT_TRUE(
      HealEdgeGrids(*model, Pcurves(*model), AllFaces(*model), false, 1, nullptr, &grids, &stats)
          .ok());
  EXPECT_GT(stats.splits, 0);
  EXPECT_GE(stats.rounds, 1);
  EXPECT_EQ(FacesWithConflicts(*model, grids), 0);
  int split_edges = 0;
  for (size_t e = 0; e < grids.size(); ++e) {
    const EdgeGrid &g = grids[e], &old = before[e];
    ASSERT_EQ(g.t.size(), g.xyz.size());
    // Only insertions: every earlier parameter is still there, and the ends stay at the vertices.
    EXPECT_TRUE(std::includes(g.t.begin(), g.t.end(), old.t.begin(), old.t.end()))
        << "edge " << e + 1;
    EXPECT_EQ(g.first_vertex, old.first_vertex);
    EXPECT_EQ(g.last_vertex, old.last_vertex);
    EXPECT_EQ(Dist(g.xyz.front(), old.xyz.front()), 0.0);
    EXPECT_EQ(Dist(g.xyz.back(), old.xyz.back()), 0.0);
    split_edges += g.t.size() > old.t.size();
    // A circle of the ring (all its points at one height) keeps every point on it.
    bool level = true;
    for (const Vec3& p : g.xyz) level = level && p.z == g.xyz.front().z;
    if (!level) continue;
    const double r = std::hypot(g.xyz.front().x, g.xyz.front().y);
    for (const Vec3& p : g.xyz) EXPECT_NEAR(std::hypot(p.x, p.y), r, 1e-9 * r) << "edge " << e + 1;
  }
  EXPECT_GT(split_edges, 0);
}

TEST(HealTest, SameGridsAtAnyThreadCount) {
  auto model = Ring();
  ASSERT_TRUE(model);
  std::vector<EdgeGrid> one = Grids(*model, 1.0), two = one;
  HealStats stats_one, stats_two;
  ASSERT_TRUE(
      HealEdgeGrids(*model, Pcurves(*model), AllFaces(*model), false, 1, nullptr, &one, &stats_one)
          .ok());
  ASSERT_TRUE(
      HealEdgeGrids(*model, Pcurves(*model), AllFaces(*model), false, 2, nullptr, &two, &stats_two)
          .ok());
  EXPECT_GT(stats_one.splits, 0);
  EXPECT_EQ(stats_one.splits, stats_two.splits);
  EXPECT_EQ(stats_one.rounds, stats_two.rounds);
  ASSERT_EQ(one.size(), two.size());
  for (size_t e = 0; e < one.size(); ++e) {
    EXPECT_EQ(one[e].t, two[e].t) << "edge " << e + 1;
    ASSERT_EQ(one[e].xyz.size(), two[e].xyz.size());
    for (size_t k = 0; k < one[e].xyz.size(); ++k)
      EXPECT_EQ(Dist(one[e].xyz[k], two[e].xyz[k]), 0.0) << "edge " << e + 1;
  }
}

TEST(HealTest, StopsWhenTheContextIsCancelled) {
  auto model = Ring();
  ASSERT_TRUE(model);
  std::vector<EdgeGrid> grids = Grids(*model, 1.0);
  Context context;
  context.Cancel();
  EXPECT_EQ(
      HealEdgeGrids(*model, Pcurves(*model), AllFaces(*model), false, 1, &context, &grids).code(),
      StatusCode::kCancelled);
}

}  // namespace
}  // namespace rdmesh
