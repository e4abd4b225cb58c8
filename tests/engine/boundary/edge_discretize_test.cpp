// One edge's grid (edge_discretize.h) on analytic curves: equal sagittas on a circle, one segment
// on a straight line unless max_length asks for more, the RD tolerance as an angle rule, and the
// closed forms for arcs and lines against the searched measures.
#include "boundary/edge_discretize.h"

#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "analytic_fixture.h"
#include "geometry/surface.h"

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

// The same curve without its shape: MeasureSegment searches it.
class Unshaped final : public Curve {
 public:
  explicit Unshaped(Curve& c) : c_(c) {}
  Vec3 Point(double t) override { return c_.Point(t); }

 private:
  Curve& c_;
};

TEST(EdgeGridTest, ArcAndLineClosedFormsMatchTheSearch) {
  auto circle = MakeCircleCurve(2.0, 0.5);
  ASSERT_EQ(circle->shape, Curve::Shape::kCircle);
  Unshaped searched(*circle);
  for (auto [a, b] : {std::pair{0.1, 0.4}, {1.0, 2.5}, {-0.3, 3.5}, {0.0, 6.0}}) {
    SegmentMeasure exact = MeasureSegment(*circle, a, b), found = MeasureSegment(searched, a, b);
    EXPECT_NEAR(exact.split, 0.5 * (a + b), 1e-15);
    EXPECT_NEAR(found.split, exact.split, 1e-3 * (b - a)) << a << " " << b;
    // The closed form is the maximum; the search lands a little below it.
    EXPECT_GE(exact.sagitta, found.sagitta * (1 - 1e-12));
    EXPECT_NEAR(exact.sagitta, 2.0 * (1 - std::cos(0.5 * (b - a))), 1e-12);
    EXPECT_NEAR(found.sagitta, exact.sagitta, 1e-6 * exact.sagitta);
    EXPECT_NEAR(found.rd, exact.rd, 1e-6 * exact.rd);
  }
  // A straight parameter line marked as a line: no sagitta, no deficit, split in the middle.
  auto plane = MakePlaneSurface();
  testing::ParamLine line(*plane, {0, 0}, {3, 1});
  line.shape = Curve::Shape::kLine;
  SegmentMeasure m = MeasureSegment(line, 0.2, 0.6);
  EXPECT_EQ(m.sagitta, 0);
  EXPECT_EQ(m.rd, 0);
  EXPECT_DOUBLE_EQ(m.split, 0.4);
  EXPECT_NEAR(m.chord, 0.4 * std::sqrt(10.0), 1e-12);
}

}  // namespace
}  // namespace rdmesh
