#include "face/lattice_seeds.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <utility>

namespace rdmesh {

namespace {

// The ring lattice of a partial sphere stands at this fraction of the deviation (the fastest
// of the fills that came within 1.2x the interpolating minimum; docs/TUNING.md).
constexpr double kRingFill = 0.85;

// A closed sphere's geodesic lattice stands at this fraction of the deviation (the fill nearest
// the interpolating minimum from 3e-3 to 3e-5; docs/TUNING.md).
constexpr double kGeodesicFill = 0.95;

// Rounds of the spring relaxation of the geodesic lattice, its step (stable below 1/3 with six
// neighbours) and its momentum: 100 rounds at 0.9 do what 400 rounds without did (unit sphere
// at 1e-3 / 3e-4 / 1e-4 / 3e-5: 1514 / 5064 / 15008 / 49606 triangles against 1518 / 5070 /
// 15018 / 50058).
constexpr int kRelaxRounds = 100;
constexpr double kRelaxStep = 0.2;
constexpr double kRelaxMomentum = 0.9;

// The radius of a circle through S(a) and S(b), 2h of its turn apart (a chord spanning 2h of a
// circle of radius R is 2 R sin h), so that a scaled placement is taken into account.
constexpr double kChordHalfTurn = 0.25;

double ChordRadius(Vec3 a, Vec3 b) { return Dist(a, b) / (2 * std::sin(kChordHalfTurn)); }

// The sphere's radius, from one chord along a meridian.
double MeridianRadius(Surface& s, double u) {
  return ChordRadius(s.Point(u, -kChordHalfTurn), s.Point(u, kChordHalfTurn));
}

// The unit icosahedron with vertex 0 at the north pole and 11 at the south pole; its faces are
// counter-clockwise seen from outside.
struct Icosahedron {
  std::array<Vec3, 12> v;
  std::array<std::array<int, 3>, 20> f;
};

Icosahedron MakeIcosahedron() {
  Icosahedron ico;
  const double z = 1 / std::sqrt(5.0), r = 2 / std::sqrt(5.0);
  ico.v[0] = {0, 0, 1};
  for (int i = 0; i < 5; ++i) {
    const double a = 2 * M_PI * i / 5, b = 2 * M_PI * (i + 0.5) / 5;
    ico.v[1 + i] = {r * std::cos(a), r * std::sin(a), z};
    ico.v[6 + i] = {r * std::cos(b), r * std::sin(b), -z};
  }
  ico.v[11] = {0, 0, -1};
  for (int i = 0; i < 5; ++i) {
    const int a = 1 + i, b = 1 + (i + 1) % 5, c = 6 + i, d = 6 + (i + 1) % 5;
    ico.f[4 * i] = {0, a, b};
    ico.f[4 * i + 1] = {a, c, b};
    ico.f[4 * i + 2] = {b, c, d};
    ico.f[4 * i + 3] = {c, 11, d};
  }
  return ico;
}

// A point of the geodesic lattice named by its integer barycentric weights (summing to T) on
// icosahedron vertices, sorted by vertex, so that a point on an edge or a corner has one name
// whichever face reaches it. Unused slots hold vertex 12.
using LatticeKey = std::array<int, 6>;

LatticeKey KeyOf(std::array<std::pair<int, int>, 3> w) {
  for (auto& x : w)
    if (x.second == 0) x.first = 12;
  std::sort(w.begin(), w.end());
  return {w[0].first, w[0].second, w[1].first, w[1].second, w[2].first, w[2].second};
}

// The geodesic lattice of class (m, n) on the unit sphere: the triangular lattice in which a
// corner of each icosahedron face is m steps along, then n steps at 60 degrees, from the next;
// T = m^2 + mn + n^2, 10 T + 2 points (Goldberg-Coxeter). Its points are projected from the
// faces to the sphere and then relaxed as a network of equal springs along the lattice edges
// (the projection alone leaves the triangles near the face centres about 1.5 times the area of
// those near the corners; on the unit sphere at 1e-4 that cost 1.20x the minimum against 1.08x).
std::vector<Vec3> GeodesicLattice(int m, int n) {
  const Icosahedron ico = MakeIcosahedron();
  const int t = m * m + m * n + n * n;
  // The third vertex of the face across each directed edge.
  std::map<std::pair<int, int>, int> across;
  for (const auto& f : ico.f)
    for (int i = 0; i < 3; ++i) across[{f[(i + 1) % 3], f[i]}] = f[(i + 2) % 3];
  std::map<LatticeKey, int> index;
  std::vector<Vec3> points;
  struct Local {
    int face, a, b;
  };
  std::vector<Local> where;  // one face's lattice coordinates of each point
  auto weights = [&](int a, int b) {
    const int wb = a * (m + n) + b * n, wc = b * m - a * n;
    return std::array<int, 3>{t - wb - wc, wb, wc};
  };
  for (int fi = 0; fi < 20; ++fi) {
    const auto& f = ico.f[fi];
    for (int a = -n; a <= m; ++a) {
      for (int b = 0; b <= m + n; ++b) {
        const std::array<int, 3> w = weights(a, b);
        if (w[0] < 0 || w[1] < 0 || w[2] < 0) continue;
        const LatticeKey key = KeyOf({{{f[0], w[0]}, {f[1], w[1]}, {f[2], w[2]}}});
        if (index.count(key)) continue;
        index[key] = static_cast<int>(points.size());
        const Vec3 q = w[0] * ico.v[f[0]] + (w[1] * ico.v[f[1]] + w[2] * ico.v[f[2]]);
        points.push_back((1.0 / Norm(q)) * q);
        where.push_back({fi, a, b});
      }
    }
  }
  // Lattice edges: the six steps from each point, unfolded onto the face across an edge when
  // they leave the point's face (a step near a corner that leaves two edges is dropped; the
  // point across finds it from its side).
  std::vector<std::pair<int, int>> edges;
  const int steps[6][2] = {{1, 0}, {0, 1}, {-1, 1}, {-1, 0}, {0, -1}, {1, -1}};
  for (size_t p = 0; p < points.size(); ++p) {
    const auto& f = ico.f[where[p].face];
    for (const auto& s : steps) {
      std::array<int, 3> w = weights(where[p].a + s[0], where[p].b + s[1]);
      std::array<int, 3> vtx = f;
      int negative = -1, count = 0;
      for (int i = 0; i < 3; ++i)
        if (w[i] < 0) negative = i, ++count;
      if (count > 1) continue;
      if (count == 1) {
        const int x = negative, y = (x + 1) % 3, z = (x + 2) % 3;
        w[y] += w[x], w[z] += w[x], w[x] = -w[x];
        vtx[x] = across[{f[y], f[z]}];
        if (w[y] < 0 || w[z] < 0) continue;
      }
      auto it = index.find(KeyOf({{{vtx[0], w[0]}, {vtx[1], w[1]}, {vtx[2], w[2]}}}));
      const int q = it == index.end() ? -1 : it->second, self = static_cast<int>(p);
      if (q >= 0 && q != self) edges.push_back({std::min(self, q), std::max(self, q)});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  double rest = 0;
  for (const auto& e : edges) rest += Dist(points[e.first], points[e.second]);
  rest /= std::max<size_t>(1, edges.size());
  std::vector<Vec3> force(points.size()), velocity(points.size(), Vec3{0, 0, 0});
  for (int round = 0; round < kRelaxRounds; ++round) {
    std::fill(force.begin(), force.end(), Vec3{0, 0, 0});
    for (const auto& e : edges) {
      const Vec3 d = points[e.second] - points[e.first];
      const double len = Norm(d);
      const Vec3 pull = ((len - rest) / len) * d;
      force[e.first] = force[e.first] + pull;
      force[e.second] = force[e.second] - pull;
    }
    for (size_t i = 0; i < points.size(); ++i) {
      velocity[i] = kRelaxMomentum * velocity[i] + kRelaxStep * force[i];
      const Vec3 q = points[i] + velocity[i];
      points[i] = (1.0 / Norm(q)) * q;
    }
  }
  return points;
}

// GeodesicLattice, computed once per class in the process (closed spheres of one radius meshed at
// one deviation, in one model or over a daemon's requests, share it): a few recent classes are
// kept.
std::shared_ptr<const std::vector<Vec3>> CachedLattice(int m, int n) {
  static std::mutex mutex;
  static std::vector<std::pair<std::pair<int, int>, std::shared_ptr<const std::vector<Vec3>>>>
      cache;
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& entry : cache)
      if (entry.first == std::make_pair(m, n)) return entry.second;
  }
  auto made = std::make_shared<const std::vector<Vec3>>(GeodesicLattice(m, n));
  std::lock_guard<std::mutex> lock(mutex);
  if (cache.size() >= 8) cache.erase(cache.begin());
  cache.push_back({{m, n}, made});
  return made;
}

// The sphere's part of the work common to both lattices: its radius, and the equilateral
// triangle of circumradius r that stands `fill` x the deviation off it (r^2 = 2 R d - d^2): its
// edge r sqrt(3), and the angle that edge turns on the sphere. edge 0 when no lattice serves.
struct LatticeScale {
  double radius = 0, edge = 0, step = 0;
};

LatticeScale ScaleOf(const FaceDomain& d, Surface& s, double max_deviation, double fill) {
  LatticeScale l;
  l.radius = MeridianRadius(s, 0.5 * (d.umin + d.umax));
  const double deviation = fill * max_deviation;
  if (!(max_deviation > 0) || d.segments.empty() || !(l.radius > 0) ||
      !(deviation < 0.5 * l.radius))
    return {};
  const double edge = std::sqrt(3.0) * std::sqrt(2 * l.radius * deviation - deviation * deviation);
  // A lattice edge that turns more than pi/8 is a coarse request: the grid of SeedPoints serves.
  l.step = 2 * std::asin(std::min(1.0, 0.5 * edge / l.radius));
  if (!(l.step > 0 && l.step <= M_PI / 8)) return {};
  l.edge = edge;
  return l;
}

// Keeps `p` as a seed when it lies inside the domain and clear of its boundary by `clearance`
// in 3D. False once there are more than max_seeds.
bool KeepClear(const FaceDomain& d, Surface& s, Vec2 p, double clearance, size_t max_seeds,
               std::vector<Vec2>* seeds) {
  if (p.x <= d.umin || p.x >= d.umax || p.y <= d.vmin || p.y >= d.vmax || !InsideDomain(d, p))
    return true;
  const Vec3 x = s.Point(p.x, p.y);
  for (const auto& seg : d.segments) {
    if (PointSegmentDistance(x, d.xyz[seg[0]], d.xyz[seg[1]]) < clearance) return true;
  }
  seeds->push_back(p);
  return seeds->size() <= max_seeds;
}

// The boundary's own nodes are spaced by the edge grids' sagitta rule, about 1.25 lattice edges,
// so seeds keep clear of it by 0.4 of an edge: the first row then sits nearer to it than a
// lattice row would. 0.3-0.4 give the same ring seeds on the unit sphere and gmsh_cube_filet; at
// 0.5 the octants of gmsh_cube_filet start with too few seeds near their boundary, and refinement
// splits 60% more triangles than the lattice holds.
constexpr double kClearance = 0.4;

// Rings of latitude one lattice row apart, each with as many seeds as its circumference holds,
// alternate rings offset by half a step.
std::vector<Vec2> RingSeeds(const FaceDomain& d, Surface& s, double max_deviation,
                            size_t max_seeds) {
  std::vector<Vec2> seeds;
  const LatticeScale l = ScaleOf(d, s, max_deviation, kRingFill);
  if (!(l.edge > 0)) return seeds;
  const double edge = l.edge, step = l.step;
  const int rows = std::max(2, static_cast<int>(std::lround(M_PI / (step * std::sqrt(3.0) / 2))));
  const double row = M_PI / rows;
  // Expected count against the cap before any point is made (the sphere's part in the box).
  const double band = std::max(0.0, std::min(d.vmax, M_PI / 2) - std::max(d.vmin, -M_PI / 2));
  const double span = std::min(d.umax - d.umin, 2 * M_PI);
  const double expected = (span / step) * (band / row) + 1;
  if (expected > static_cast<double>(max_seeds)) return seeds;
  for (int k = 1; k < rows; ++k) {
    const double v = -M_PI / 2 + k * row;
    if (v <= d.vmin || v >= d.vmax) continue;
    const int n = std::max(3, static_cast<int>(std::lround(2 * M_PI * std::cos(v) / step)));
    const double du = 2 * M_PI / n;
    const double offset = (k % 2) * 0.5 * du;
    const long first = static_cast<long>(std::ceil((d.umin - offset) / du));
    const long last = static_cast<long>(std::floor((d.umax - offset) / du));
    for (long j = first; j <= last; ++j) {
      if (!KeepClear(d, s, {offset + j * du, v}, kClearance * edge, max_seeds, &seeds)) return {};
    }
  }
  return seeds;
}

// The geodesic lattice of the coarsest class whose equal triangles stand within kGeodesicFill
// of the deviation, mapped to (longitude, latitude).
std::vector<Vec2> GeodesicSeeds(const FaceDomain& d, Surface& s, double max_deviation,
                                size_t max_seeds) {
  std::vector<Vec2> seeds;
  const LatticeScale l = ScaleOf(d, s, max_deviation, kGeodesicFill);
  if (!(l.edge > 0)) return seeds;
  const double edge = l.edge, radius = l.radius;
  // Each point holds two triangles of area sqrt(3)/4 edge^2 of the sphere's 4 pi R^2.
  const double area = std::sqrt(3.0) / 4 * edge * edge;
  const double wanted_t = (4 * M_PI * radius * radius / (2 * area) - 2) / 10;
  int best_m = 0, best_n = 0, best_t = 0;
  for (int m = 1; m * m <= 4 * wanted_t + 4; ++m) {
    for (int n = 0; n <= m; ++n) {
      const int t = m * m + m * n + n * n;
      if (t >= wanted_t && (best_t == 0 || t < best_t)) best_m = m, best_n = n, best_t = t;
    }
  }
  if (best_t == 0 || 10.0 * best_t + 2 > static_cast<double>(max_seeds)) return seeds;
  const std::shared_ptr<const std::vector<Vec3>> lattice = CachedLattice(best_m, best_n);
  for (const Vec3& q : *lattice) {
    if (std::fabs(q.z) > 1 - 1e-12) continue;  // a pole: on the boundary
    const double v = std::asin(q.z), u = std::atan2(q.y, q.x);
    for (double turn : {-2 * M_PI, 0.0, 2 * M_PI}) {
      if (!KeepClear(d, s, {u + turn, v}, kClearance * edge, max_seeds, &seeds)) return {};
    }
  }
  // In a fixed order, by latitude, then longitude.
  std::sort(seeds.begin(), seeds.end(),
            [](Vec2 a, Vec2 b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
  return seeds;
}

// A torus's lattice stands at this fraction of the deviation (0.85 and 0.95 gave 0.2% and 0.3%
// more triangles than 0.9 on the tori of 24 models at 1e-3; docs/TUNING.md).
constexpr double kTorusFill = 0.9;

// The torus's radii from chords (OCCT's parameters: u turns about the axis, v about the tube):
// the tube's radius r from a chord along v (as a sphere's meridian), the major radius R from a
// chord along u on the outer equator (radius R + r).
struct TorusRadii {
  double major = 0, minor = 0;
};

TorusRadii RadiiOf(Surface& s, double u) {
  TorusRadii t;
  t.minor = MeridianRadius(s, u);
  t.major = ChordRadius(s.Point(u - kChordHalfTurn, 0), s.Point(u + kChordHalfTurn, 0)) - t.minor;
  return t;
}

}  // namespace

std::vector<Vec2> TorusLatticeSeeds(const FaceDomain& d, Surface& s, double max_deviation,
                                    size_t max_seeds) {
  std::vector<Vec2> seeds;
  const TorusRadii t = RadiiOf(s, 0.5 * (d.umin + d.umax));
  const double dev = kTorusFill * max_deviation;
  // A deviation of a quarter of the tube's radius or more is a coarse request (fewer than six
  // rows about the tube): the grid of SeedPoints serves. (The sphere's limit, a lattice edge of
  // pi/8, left most KiCad leads' thin tubes without a lattice at 1e-3.)
  if (!(max_deviation > 0) || d.segments.empty() || !(t.minor > 0) || !(t.major > t.minor) ||
      !(dev < 0.25 * t.minor))
    return seeds;
  // Rows of constant v (circles about the axis), one lattice row apart along the tube and
  // dividing its turn evenly from v = 0 (a closed torus meets itself): a triangle equilateral in
  // the metric of the curvatures (|k_u|, 1/r) whose interpolation error is dev has circumradius
  // sqrt(2 dev) there, edge sqrt(6 dev) and row height sqrt(4.5 dev).
  const double row_3d = std::sqrt(4.5 * dev * t.minor);
  const double dv = 2 * M_PI / std::lround(2 * M_PI * t.minor / row_3d);
  // Along a row the curvature is cos v / (R + r cos v): an edge of metric length sqrt(6 dev)
  // (sqrt(8 dev) where the torus is a saddle, whose error is the sagitta of its edges along a
  // principal direction) turns du = a / sqrt(|cos v| (R + r cos v)); at most pi/8, where the
  // row is almost straight.
  double expected = 0;
  std::vector<std::pair<double, int>> plan;  // (v, points per turn)
  for (long k = static_cast<long>(std::ceil(d.vmin / dv));
       k <= static_cast<long>(std::floor(d.vmax / dv)); ++k) {
    const double v = k * dv;
    if (v <= d.vmin || v >= d.vmax) continue;
    const double c = std::cos(v), ring = t.major + t.minor * c;
    const double a = std::sqrt((c >= 0 ? 6 : 8) * dev);
    const double du = std::min(M_PI / 8, a / std::sqrt(std::max(std::fabs(c) * ring, 1e-300)));
    const int n = std::max(16, static_cast<int>(std::ceil(2 * M_PI / du)));
    plan.push_back({v, n});
    expected += std::min(d.umax - d.umin, 2 * M_PI) * n / (2 * M_PI) + 1;
  }
  if (plan.empty() || expected > static_cast<double>(max_seeds)) return seeds;
  for (const auto& [v, n] : plan) {
    const double du = 2 * M_PI / n;
    const double offset = (std::lround(v / dv) & 1) * 0.5 * du;  // alternate rows by half a step
    const long first = static_cast<long>(std::ceil((d.umin - offset) / du));
    const long last = static_cast<long>(std::floor((d.umax - offset) / du));
    for (long j = first; j <= last; ++j)
      if (!KeepClear(d, s, {offset + j * du, v}, kClearance * row_3d, max_seeds, &seeds)) return {};
  }
  return seeds;
}

std::vector<Vec2> SphereLatticeSeeds(const FaceDomain& d, Surface& s, double max_deviation,
                                     size_t max_seeds) {
  const bool closed =
      d.umax - d.umin >= 2 * M_PI - 1e-9 && d.vmin <= -M_PI / 2 + 1e-9 && d.vmax >= M_PI / 2 - 1e-9;
  return closed ? GeodesicSeeds(d, s, max_deviation, max_seeds)
                : RingSeeds(d, s, max_deviation, max_seeds);
}

}  // namespace rdmesh
