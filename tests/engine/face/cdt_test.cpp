// The starting triangulation (cdt.h): constrained Delaunay of boundary loops and seed points in
// (u,v), holes by nesting, and the reasons it gives for boundaries it cannot take.
#include "face/cdt.h"

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

namespace rdmesh {
namespace {

double TriangleArea(const std::vector<Vec2>& points, const std::array<int, 3>& t) {
  return 0.5 * Orient(points[t[0]], points[t[1]], points[t[2]]);
}

// A 4 x 4 square (points 0..3, counter-clockwise) around a 2 x 2 hole (points 4..7, clockwise).
void SquareWithHole(std::vector<Vec2>* points, std::vector<std::array<int, 2>>* segments) {
  *points = {{0, 0}, {4, 0}, {4, 4}, {0, 4}, {1, 1}, {1, 3}, {3, 3}, {3, 1}};
  *segments = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}};
}

TEST(CdtTest, HoleIsLeftOutAndEverySegmentIsAConstrainedEdge) {
  std::vector<Vec2> points;
  std::vector<std::array<int, 2>> segments;
  SquareWithHole(&points, &segments);
  CdtResult result;
  ASSERT_TRUE(ConstrainedTriangulation(points, segments, nullptr, &result).ok());
  // 8 boundary points, one hole, no interior point: 8 + 2 * 1 - 2 triangles.
  ASSERT_EQ(result.triangles.size(), 8u);
  ASSERT_EQ(result.constrained.size(), 8u);
  double area = 0;
  int constrained = 0;
  for (size_t k = 0; k < result.triangles.size(); ++k) {
    const std::array<int, 3>& t = result.triangles[k];
    EXPECT_GT(TriangleArea(points, t), 0) << "triangle " << k << " is not counter-clockwise";
    area += TriangleArea(points, t);
    // No triangle lies in the hole: its centroid is outside [1, 3]^2.
    Vec2 c = (1.0 / 3) * (points[t[0]] + points[t[1]] + points[t[2]]);
    EXPECT_FALSE(c.x > 1 && c.x < 3 && c.y > 1 && c.y < 3) << "triangle " << k;
    for (int i = 0; i < 3; ++i) {
      if (!result.constrained[k][i]) continue;
      ++constrained;
      // The edge opposite corner i is one of the segments.
      int a = t[(i + 1) % 3], b = t[(i + 2) % 3];
      bool found = false;
      for (const auto& s : segments)
        found = found || (s[0] == a && s[1] == b) || (s[0] == b && s[1] == a);
      EXPECT_TRUE(found) << "edge " << a << "-" << b << " is marked constrained";
    }
  }
  EXPECT_DOUBLE_EQ(area, 16 - 4);
  EXPECT_EQ(constrained, 8);  // each segment bounds one inside triangle
}

TEST(CdtTest, SeedPointIsACornerOfEveryTriangleAroundIt) {
  std::vector<Vec2> points = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5, 0.5}};
  std::vector<std::array<int, 2>> segments = {{0, 1}, {1, 2}, {2, 3}, {3, 0}};
  CdtResult result;
  ASSERT_TRUE(ConstrainedTriangulation(points, segments, nullptr, &result).ok());
  ASSERT_EQ(result.triangles.size(), 4u);
  for (const auto& t : result.triangles) EXPECT_TRUE(t[0] == 4 || t[1] == 4 || t[2] == 4);
}

TEST(CdtTest, BoundariesItCannotTakeFailWithTheReason) {
  CdtResult result;
  // Two loops whose segments cross.
  std::vector<Vec2> crossing = {{0, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 1}, {3, 1}, {3, 3}};
  Status st = ConstrainedTriangulation(
      crossing, {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 4}}, nullptr, &result);
  EXPECT_EQ(st.code(), StatusCode::kInternal);
  EXPECT_NE(st.message().find("intersect"), std::string::npos) << st.message();
  // Two boundary nodes at one (u,v).
  std::vector<Vec2> twice = {{0, 0}, {1, 0}, {1, 0}, {0, 1}};
  st = ConstrainedTriangulation(twice, {{0, 1}, {2, 3}, {3, 0}}, nullptr, &result);
  EXPECT_EQ(st.code(), StatusCode::kInternal);
  EXPECT_NE(st.message().find("coincide"), std::string::npos) << st.message();
  // Not here: a boundary whose points all lie on one line (a triangulation of dimension 1)
  // crashes in MarkDomains today; MeshFace never gets there, as FindConflicts reports such a
  // loop first.
}

TEST(CdtTest, StopsWhenTheContextIsCancelled) {
  std::vector<Vec2> points;
  std::vector<std::array<int, 2>> segments;
  SquareWithHole(&points, &segments);
  Context context;
  context.Cancel();
  CdtResult result;
  EXPECT_EQ(ConstrainedTriangulation(points, segments, &context, &result).code(),
            StatusCode::kCancelled);
  EXPECT_TRUE(result.triangles.empty());
}

}  // namespace
}  // namespace rdmesh
