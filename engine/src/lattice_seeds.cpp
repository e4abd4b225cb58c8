#include "lattice_seeds.h"

#include <algorithm>
#include <cmath>

namespace rdmesh {

namespace {

// The sphere's radius, from one chord along a meridian (exact for a sphere: a chord spanning
// 2h of latitude is 2 R sin h), so that a scaled placement is taken into account.
double MeridianRadius(Surface& s, double u) {
  const double h = 0.25;
  const double chord = Dist(s.Point(u, -h), s.Point(u, h));
  return chord / (2 * std::sin(h));
}

}  // namespace

std::vector<Vec2> SphereLatticeSeeds(const FaceDomain& d, Surface& s, double max_deviation,
                                     double fill, size_t max_seeds) {
  std::vector<Vec2> seeds;
  if (!(max_deviation > 0) || d.segments.empty()) return seeds;
  const double radius = MeridianRadius(s, 0.5 * (d.umin + d.umax));
  const double deviation = fill * max_deviation;
  if (!(radius > 0) || !(deviation < 0.5 * radius)) return seeds;
  // An equilateral triangle of circumradius r stands `deviation` off the sphere when
  // r^2 = 2 R deviation - deviation^2; its edge is r sqrt(3), an angle of `step` radians.
  const double circum = std::sqrt(2 * radius * deviation - deviation * deviation);
  const double edge = std::sqrt(3.0) * circum;
  const double step = 2 * std::asin(std::min(1.0, 0.5 * edge / radius));
  if (!(step > 0) || step > M_PI / 8) return seeds;
  // Rings of latitude every row height of the lattice, from pole to pole.
  const int rows = std::max(2, static_cast<int>(std::lround(M_PI / (step * std::sqrt(3.0) / 2))));
  const double row = M_PI / rows;
  // Expected count against the cap before any point is made (the sphere's part in the box).
  const double band = std::max(0.0, std::min(d.vmax, M_PI / 2) - std::max(d.vmin, -M_PI / 2));
  const double span = std::min(d.umax - d.umin, 2 * M_PI);
  const double expected = (span / step) * (band / row) + 1;
  if (expected > static_cast<double>(max_seeds)) return seeds;
  // Clear of the boundary by 0.4 of an edge: the boundary's own nodes are spaced by the edge
  // grids' sagitta rule, about 1.25 lattice edges, so the first row of seeds sits nearer to it
  // than a lattice row would. 0.3-0.4 give the same seeds on the unit sphere and gmsh_cube_filet;
  // at 0.5 the octants of gmsh_cube_filet start with too few seeds near their boundary, and
  // refinement splits 60% more triangles than the lattice holds.
  const double clearance = 0.4 * edge;
  for (int k = 1; k < rows; ++k) {
    const double v = -M_PI / 2 + k * row;
    if (v <= d.vmin || v >= d.vmax) continue;
    const int n = std::max(3, static_cast<int>(std::lround(2 * M_PI * std::cos(v) / step)));
    const double du = 2 * M_PI / n;
    const double offset = (k % 2) * 0.5 * du;
    const long first = static_cast<long>(std::ceil((d.umin - offset) / du));
    const long last = static_cast<long>(std::floor((d.umax - offset) / du));
    for (long j = first; j <= last; ++j) {
      const Vec2 p{offset + j * du, v};
      if (p.x <= d.umin || p.x >= d.umax || !InsideDomain(d, p)) continue;
      const Vec3 x = s.Point(p.x, p.y);
      bool clear = true;
      for (const auto& seg : d.segments) {
        if (PointSegmentDistance(x, d.xyz[seg[0]], d.xyz[seg[1]]) < clearance) {
          clear = false;
          break;
        }
      }
      if (clear) seeds.push_back(p);
      if (seeds.size() > max_seeds) return {};
    }
  }
  return seeds;
}

}  // namespace rdmesh
