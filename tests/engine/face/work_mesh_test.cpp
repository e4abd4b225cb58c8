// Adjacency helpers of the working mesh (work_mesh.h) on a plain 4 x 4 node grid.
#include "face/work_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace rdmesh {
namespace {

// Nodes (i, j), i, j in 0..3, id 4 j + i, at (i, j) in (u,v) and (i, j, 0) in 3D; the border
// nodes are fixed. Two counter-clockwise triangles per cell.
WorkMesh Grid() {
  WorkMesh m;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      bool border = i == 0 || j == 0 || i == 3 || j == 3;
      m.AddNode({double(i), double(j)}, {double(i), double(j), 0}, {0, 0, 1}, border,
                border ? NodeRef{0, 0, 0} : NodeRef{});
    }
  std::vector<std::array<int, 3>> tris;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      int a = 4 * j + i, b = a + 1, c = a + 5, d = a + 4;
      tris.push_back({a, b, c});
      tris.push_back({a, c, d});
    }
  std::vector<std::array<bool, 3>> constrained(tris.size(), {false, false, false});
  InitWorkMesh(tris, constrained, {}, &m);
  return m;
}

TEST(OperationsTest, FanIsRingAndNeighbours) {
  WorkMesh m = Grid();
  std::vector<int> ring = {99}, nodes = {99};  // stale content is replaced
  for (int v = 0; v < m.node_count(); ++v) {
    m.Fan(v, &ring, &nodes);
    EXPECT_EQ(ring, m.Ring(v)) << v;
    EXPECT_EQ(nodes, m.Neighbours(v)) << v;
  }
  m.Fan(5, &ring, &nodes);
  EXPECT_EQ(ring.size(), 6u);  // interior node: a closed fan of six
  EXPECT_EQ(nodes.size(), 6u);
}

TEST(OperationsTest, CollapseTrisDropsTheTwoTrianglesOnTheEdge) {
  WorkMesh m = Grid();
  const int v = 5, w = 6;
  std::vector<Tri> tris;
  CollapseTris(m, v, w, m.Ring(v), &tris);
  ASSERT_EQ(tris.size(), 4u);
  for (const Tri& t : tris) {
    EXPECT_EQ(std::count(t.begin(), t.end(), v), 0);
    EXPECT_EQ(std::count(t.begin(), t.end(), w), 1);
  }
}

TEST(OperationsTest, RingsOfListsEachTriangleOnce) {
  WorkMesh m = Grid();
  std::vector<int> region = RingsOf(m, {5, 6});
  EXPECT_EQ(region.size(), 10u);  // 6 + 6 around each, 2 on the edge 5-6 shared
  std::vector<int> sorted = region;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_TRUE(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());
}

TEST(OperationsTest, LastMovesSkipsFixedMovers) {
  WorkMesh m = Grid();
  // Moves 5, then 0 (fixed: stays put), then 6.
  const std::vector<int> movers = {5, 0, 6};
  std::vector<int> region = RingsOf(m, {5, 6});
  std::vector<int> last = LastMoves(m, movers, region);
  ASSERT_EQ(last.size(), region.size());
  for (size_t j = 0; j < region.size(); ++j) {
    const Tri& t = m.tri[region[j]];
    bool has5 = m.CornerOf(region[j], 5) >= 0, has6 = m.CornerOf(region[j], 6) >= 0;
    EXPECT_EQ(last[j], has6 ? 2 : has5 ? 0 : -1) << t[0] << " " << t[1] << " " << t[2];
  }
  // A triangle none of the movers touches is final from the start.
  EXPECT_EQ(LastMoves(m, {0}, {0})[0], -1);
}

}  // namespace
}  // namespace rdmesh
