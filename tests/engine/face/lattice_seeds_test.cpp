// Sphere faces start from a lattice at about their final density (lattice_seeds): the seeds'
// spacing follows the requested deviation and the radius, on a closed sphere (geodesic lattice)
// and on a band of one (rings of latitude), and they keep clear of the boundary.

#include "face/lattice_seeds.h"

#include <gtest/gtest.h>

#include <BRepPrimAPI_MakeSphere.hxx>
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "domain_fixture.h"
#include "geometry/surface_type.h"
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

// A closed sphere, or with `band` the part of it between latitudes -pi/4 and pi/4.
Lattice SphereLattice(double radius, double deviation, size_t max_seeds = 1000000,
                      bool band = false) {
  Lattice l;
  auto model = LoadShape(band ? BRepPrimAPI_MakeSphere(radius, -M_PI / 4, M_PI / 4).Shape()
                              : BRepPrimAPI_MakeSphere(radius).Shape(),
                         "sphere");
  EXPECT_TRUE(model);
  EXPECT_EQ(model->face_count(), band ? 3 : 1);  // a band has two planar caps
  int id = 1;
  while (id < model->face_count() && FaceSurfaceType(model->face(id)) != SurfaceType::kSphere) ++id;
  EXPECT_TRUE(Domain(*model, id, Grids(*model, deviation), &l.domain).ok());
  l.surface = MakeFaceSurface(model->face(id), false);
  l.seeds = SphereLatticeSeeds(l.domain, *l.surface, deviation, max_seeds);
  return l;
}

// The edge of the equilateral triangle that stands `fill` x the deviation off the sphere:
// circumradius r with r^2 = 2 R d - d^2 for d = fill x the deviation.
double LatticeEdge(double radius, double deviation, double fill) {
  const double d = fill * deviation;
  return std::sqrt(3.0) * std::sqrt(2 * radius * d - d * d);
}

// Each seed's distance to its nearest neighbour (brute force).
std::vector<double> NearestDistances(const Lattice& l) {
  std::vector<Vec3> x;
  for (const Vec2& p : l.seeds) x.push_back(l.surface->Point(p.x, p.y));
  std::vector<double> nearest(x.size(), HUGE_VAL);
  for (size_t i = 0; i < x.size(); ++i)
    for (size_t j = 0; j < x.size(); ++j)
      if (j != i) nearest[i] = std::min(nearest[i], Dist(x[i], x[j]));
  return nearest;
}

TEST(LatticeSeedsTest, ClosedSphereSpacingFollowsTheDeviationAndTheRadius) {
  for (double radius : {1.0, 25.0}) {
    const double deviation = 1e-3 * radius;
    Lattice l = SphereLattice(radius, deviation);
    ASSERT_FALSE(l.seeds.empty());
    // The coarsest geodesic class whose equal triangles stand within 0.95 of the deviation:
    // no fewer seeds than such triangles need (less those near the seam and the poles), and not
    // many more, as the classes 10 T + 2 lie close together.
    const double edge = LatticeEdge(radius, deviation, 0.95);
    const double cells = 4 * M_PI * radius * radius / (std::sqrt(3.0) / 2 * edge * edge);
    EXPECT_GT(l.seeds.size(), 0.95 * cells) << radius;
    EXPECT_LT(l.seeds.size(), 1.1 * cells) << radius;
    // Relaxed: every nearest neighbour within 0.8-1.05 of that edge, the largest under 1.3 x
    // the smallest, also near the twelve five-fold points (the projection alone spreads them
    // over 0.77-1.09, 1.42 x; relaxed they are 0.83-1.02, 1.22 x).
    std::vector<double> nearest = NearestDistances(l);
    const auto [lo, hi] = std::minmax_element(nearest.begin(), nearest.end());
    EXPECT_GT(*lo, 0.8 * edge) << radius;
    EXPECT_LT(*hi, 1.05 * edge) << radius;
    EXPECT_LT(*hi, 1.3 * *lo) << radius;
  }
}

TEST(LatticeSeedsTest, BandSpacingFollowsTheDeviationAndTheRadius) {
  for (double radius : {1.0, 25.0}) {
    const double deviation = 1e-3 * radius;
    Lattice l = SphereLattice(radius, deviation, 1000000, /*band=*/true);
    ASSERT_FALSE(l.seeds.empty());
    const double edge = LatticeEdge(radius, deviation, 0.85);
    // The band's area (2 pi R^2 (sin(pi/4) - sin(-pi/4))) over a lattice cell's (two
    // equilateral triangles), less the rows kept clear of its two rims.
    const double cells =
        2 * M_PI * radius * radius * std::sqrt(2.0) / (std::sqrt(3.0) / 2 * edge * edge);
    EXPECT_GT(l.seeds.size(), 0.85 * cells) << radius;
    EXPECT_LT(l.seeds.size(), 1.05 * cells) << radius;
    std::vector<double> nearest = NearestDistances(l);
    const auto [lo, hi] = std::minmax_element(nearest.begin(), nearest.end());
    EXPECT_GT(*lo, 0.75 * edge) << radius;
    EXPECT_LT(*hi, 1.1 * edge) << radius;
  }
}

TEST(LatticeSeedsTest, SeedsKeepClearOfTheBoundary) {
  const double deviation = 1e-3;
  for (bool band : {false, true}) {
    Lattice l = SphereLattice(1.0, deviation, 1000000, band);
    ASSERT_FALSE(l.seeds.empty());
    const double edge = LatticeEdge(1.0, deviation, band ? 0.85 : 0.95);
    for (const Vec2& p : l.seeds) {
      ASSERT_TRUE(InsideDomain(l.domain, p));
      const Vec3 x = l.surface->Point(p.x, p.y);
      for (const auto& s : l.domain.segments)
        ASSERT_GE(PointSegmentDistance(x, l.domain.xyz[s[0]], l.domain.xyz[s[1]]),
                  0.4 * edge * 0.999)
            << band;
    }
  }
}

TEST(LatticeSeedsTest, NoneBeyondTheCapOrForACoarseRequest) {
  EXPECT_TRUE(SphereLattice(1.0, 1e-3, 100).seeds.empty());
  EXPECT_TRUE(SphereLattice(1.0, 1e-3, 100, /*band=*/true).seeds.empty());
  // A request coarse enough that the lattice edge turns more than pi/8: the coarse seed grid
  // serves instead.
  EXPECT_TRUE(SphereLattice(1.0, 0.05).seeds.empty());
}

}  // namespace
}  // namespace rdmesh
