// Triangle measures: the cheap centroid bound never exceeds the full measure's violation.
#include "measure.h"

#include <gtest/gtest.h>

#include <random>

namespace rdmesh {
namespace {

TEST(MeasureTest, CentroidViolationIsALowerBound) {
  std::unique_ptr<Surface> sphere = MakeSphereSurface(1.0);
  FaceCriteria c;
  c.max_deviation = 1e-3;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 6), v(-1.4, 1.4), size(1e-3, 0.5);
  int bounded = 0;
  for (int i = 0; i < 2000; ++i) {
    Vec2 q0{u(rng), v(rng)};
    double h = size(rng);
    std::uniform_real_distribution<double> d(-h, h);
    Vec2 uv[3] = {q0, {q0.x + d(rng), q0.y + d(rng)}, {q0.x + d(rng), q0.y + d(rng)}};
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = sphere->Point(uv[k].x, uv[k].y);
    double full = MeasureTriangle(*sphere, uv, p, c).violation;
    double bound = CentroidViolation(*sphere, uv, p, c);
    ASSERT_LE(bound, full);
    bounded += bound > 0.5 * full;
  }
  EXPECT_GT(bounded, 1000);  // and it is a useful bound
}

}  // namespace
}  // namespace rdmesh
