// The derivative-free optimisers: the bounded cross pattern search takes the same steps as the
// plain one, whatever the objective returns for probes that cannot win.
#include "geometry/pattern_search.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rdmesh {
namespace {

double Bumpy(Vec2 x) {
  return -std::hypot(x.x - 0.3, 2 * (x.y + 0.2)) + 0.05 * std::sin(17 * x.x) * std::cos(11 * x.y);
}

TEST(PatternSearchTest, FindsTheMaximumOfABowl) {
  auto f = [](Vec2 x) { return -(x.x - 0.25) * (x.x - 0.25) - (x.y + 0.5) * (x.y + 0.5); };
  PatternSearchResult r = CrossPatternSearch(
      f, [](Vec2) { return true; }, {0, 0}, f({0, 0}), {0.2, 0.2}, 1e-4, 500);
  EXPECT_NEAR(r.x.x, 0.25, 1e-3);
  EXPECT_NEAR(r.x.y, -0.5, 1e-3);
}

TEST(PatternSearchTest, BoundedSearchTakesTheSameSteps) {
  auto feasible = [](Vec2 x) { return x.x > -1 && x.x < 1 && x.y > -1 && x.y < 1; };
  int plain_calls = 0, bounded_calls = 0, evals = 0;
  auto plain = [&](Vec2 x) {
    ++plain_calls;
    return Bumpy(x);
  };
  // Answers "no better than the bound" with a useless value whenever it may.
  auto bounded = [&](Vec2 x, double bound) {
    ++bounded_calls;
    double v = Bumpy(x);
    return v > bound ? v : bound - 1e3;
  };
  for (Vec2 x0 : {Vec2{0, 0}, Vec2{0.7, 0.1}, Vec2{-0.5, -0.5}}) {
    for (int max_evals : {5, 24, 200}) {
      PatternSearchResult a =
          CrossPatternSearch(plain, feasible, x0, Bumpy(x0), {0.1, 0.05}, 1e-3, max_evals);
      PatternSearchResult b =
          CrossPatternSearch(bounded, feasible, x0, Bumpy(x0), {0.1, 0.05}, 1e-3, max_evals);
      EXPECT_EQ(a.x.x, b.x.x);
      EXPECT_EQ(a.x.y, b.x.y);
      EXPECT_EQ(a.value, b.value);
      EXPECT_EQ(a.evals, b.evals);
      evals += a.evals;
    }
  }
  // Both call the objective equally often; repeated probes are answered from memory.
  EXPECT_EQ(plain_calls, bounded_calls);
  EXPECT_GT(plain_calls, 0);
  EXPECT_LT(plain_calls, evals);
}

}  // namespace
}  // namespace rdmesh
