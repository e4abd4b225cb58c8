// One edge's grid (edge_grid.h) on analytic curves: equal sagittas on a circle, one segment on a
// straight line unless max_length asks for more, and the RD tolerance as an angle rule.
#include "edge_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analytic_fixture.h"
#include "surface.h"

namespace rdmesh {
namespace {

TEST(EdgeGridTest, CircleGetsEqualSagittas) {
  auto circle = MakeCircleCurve(1.0, 0.0);
  EdgeGridCriteria c;
  c.max_sagitta = 1e-3;
  c.min_segments = 3;
  std::vector<double> t = DiscretizeCurve(*circle, 0, 2 * M_PI, c);
  int n = static_cast<int>(std::ceil(M_PI / std::acos(1 - 1e-3)));
  EXPECT_EQ(static_cast<int>(t.size()) - 1, n);
  for (size_t k = 0; k + 1 < t.size(); ++k) {
    SegmentMeasure m = MeasureSegment(*circle, t[k], t[k + 1]);
    EXPECT_LE(m.sagitta, 1e-3 * (1 + 1e-6));
    EXPECT_GE(m.sagitta, 0.9e-3);
  }
}

TEST(EdgeGridTest, StraightLineIsOneSegment) {
  auto plane = MakePlaneSurface();
  testing::ParamLine line(*plane, {0, 0}, {3, 1});
  EdgeGridCriteria c;
  c.max_sagitta = 1e-6;
  EXPECT_EQ(DiscretizeCurve(line, 0, 1, c).size(), 2u);
  c.max_length = 1.0;
  EXPECT_EQ(DiscretizeCurve(line, 0, 1, c).size(), 5u);  // length sqrt(10) -> 4 segments
}

TEST(EdgeGridTest, RdToleranceIsAnAngleRule) {
  // RD of a segment turning by theta is ~theta^2 / 24: tau = 1e-3 is ~9 degrees a segment.
  auto circle = MakeCircleCurve(5.0, 0.0);
  EdgeGridCriteria c;
  c.rd_tolerance = 1e-3;
  c.min_segments = 3;
  std::vector<double> t = DiscretizeCurve(*circle, 0, 2 * M_PI, c);
  double theta = std::sqrt(24 * 1e-3);
  EXPECT_EQ(static_cast<int>(t.size()) - 1, static_cast<int>(std::ceil(2 * M_PI / theta)));
}

}  // namespace
}  // namespace rdmesh
