// Triangle measures: the early stop of MeasureTriangleBelow is a true lower bound, and when it
// measures in full it gives exactly MeasureTriangle's result.
#include "measure.h"

#include <gtest/gtest.h>

#include <random>

namespace rdmesh {
namespace {

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
    TriangleMeasure full = MeasureTriangle(*sphere, uv, p, c), m;
    double l = limit(rng);
    if (MeasureTriangleBelow(*sphere, uv, p, c, l, &m)) {
      EXPECT_EQ(m.violation, full.violation);
      EXPECT_EQ(m.deviation, full.deviation);
      EXPECT_EQ(m.rd, full.rd);
      EXPECT_EQ(m.worst_uv.x, full.worst_uv.x);
      EXPECT_EQ(m.worst_uv.y, full.worst_uv.y);
    } else {
      ++stopped;
      EXPECT_GE(m.violation, l);
      EXPECT_LE(m.violation, full.violation);
    }
  }
  EXPECT_GT(stopped, 200);
}

}  // namespace
}  // namespace rdmesh
