#pragma once
// Builds and refines one analytic face through the engine's own stages (edge grid, domain, CDT,
// refinement) without any file: a unit sphere, a cylinder or a plane square.

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "boundary/edge_discretize.h"
#include "face/cdt.h"
#include "face/measure.h"
#include "face/refine.h"
#include "face/work_mesh.h"
#include "geometry/surface.h"

namespace rdmesh::testing {

/// A curve along a surface's parameter line: C(t) = S(u0 + t du, v0 + t dv).
class ParamLine final : public Curve {
 public:
  ParamLine(Surface& s, Vec2 from, Vec2 to) : s_(s), from_(from), to_(to) {}
  Vec3 Point(double t) override {
    Vec2 q = (1 - t) * from_ + t * to_;
    return s_.Point(q.x, q.y);
  }

 private:
  Surface& s_;
  Vec2 from_, to_;
};

struct AnalyticFace {
  std::unique_ptr<Surface> surface;
  WorkMesh mesh;
  RefineStats stats;
  double scale_u = 1, scale_v = 1;

  /// Triangles that are not degenerate in 3D (pole triangles vanish in the output).
  int OutputTriangles() const {
    int n = 0;
    for (size_t t = 0; t < mesh.tri.size(); ++t) {
      if (!mesh.alive[t]) continue;
      const auto& x = mesh.tri[t];
      if (Area(mesh.xyz[x[0]], mesh.xyz[x[1]], mesh.xyz[x[2]]) > 1e-14) ++n;
    }
    return n;
  }
  /// Largest distance from points of the triangles (a lattice) to the surface, found through
  /// `distance` (point -> surface distance, exact for the analytic shapes).
  template <typename Fn>
  double MeasuredDeviation(Fn distance, int samples = 6) const {
    double worst = 0;
    for (size_t t = 0; t < mesh.tri.size(); ++t) {
      if (!mesh.alive[t]) continue;
      const auto& x = mesh.tri[t];
      for (int i = 0; i <= samples; ++i)
        for (int j = 0; i + j <= samples; ++j) {
          double a = double(i) / samples, b = double(j) / samples;
          Vec3 p = (1 - a - b) * mesh.xyz[x[0]] + (a * mesh.xyz[x[1]] + b * mesh.xyz[x[2]]);
          worst = std::max(worst, distance(p));
        }
    }
    return worst;
  }
};

/// Meshes the rectangle [u0,u1]x[v0,v1] of `surface`. Sides flagged `pole` are degenerate
/// (splittable) edges; sides flagged `seam_pair` share their points (u0 and u1 sides of a
/// closed surface). Edge grids come from DiscretizeCurve with `edge` criteria.
inline void MeshRectangle(AnalyticFace* f, double u0, double u1, double v0, double v1, bool poles,
                          const EdgeGridCriteria& edge, const FaceCriteria& face,
                          bool improve = true, int64_t max_triangles = 200000) {
  Surface& s = *f->surface;
  s.umin = u0, s.umax = u1, s.vmin = v0, s.vmax = v1;
  // Sides in counter-clockwise order: bottom (v0), right (u1), top (v1), left (u0).
  Vec2 corners[4] = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
  std::vector<Vec2> uv;
  std::vector<std::array<int, 2>> segments, splittable;
  for (int side = 0; side < 4; ++side) {
    Vec2 a = corners[side], b = corners[(side + 1) % 4];
    bool pole_side = poles && (side == 0 || side == 2);
    std::vector<double> ts = {0.0, 1.0};
    if (!pole_side) {
      ParamLine line(s, a, b);
      ts = DiscretizeCurve(line, 0.0, 1.0, edge);
    }
    for (size_t k = 0; k + 1 < ts.size(); ++k) {
      int n = static_cast<int>(uv.size());
      uv.push_back((1 - ts[k]) * a + ts[k] * b);
      segments.push_back({n, n + 1});
      if (pole_side) splittable.push_back({n, n + 1});
    }
  }
  segments.back()[1] = 0;
  if (poles)
    splittable.back()[1] =
        splittable.back()[1] >= static_cast<int>(uv.size()) ? 0 : splittable.back()[1];
  // Scale for isotropy: mean |Su|, |Sv| at the centre.
  Vec2 c = 0.5 * (corners[0] + corners[2]);
  double h = 1e-6;
  f->scale_u = Dist(s.Point(c.x + h, c.y), s.Point(c.x, c.y)) / h;
  f->scale_v = Dist(s.Point(c.x, c.y + h), s.Point(c.x, c.y)) / h;
  std::vector<Vec2> scaled;
  for (Vec2 p : uv) scaled.push_back({p.x * f->scale_u, p.y * f->scale_v});
  // Interior seeds on a coarse grid, as the face mesher does for curved faces.
  std::vector<Vec2> seeds;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 4; ++j)
      seeds.push_back({u0 + (u1 - u0) * (i + 0.5) / 8, v0 + (v1 - v0) * (j + 0.5) / 4});
  for (Vec2 p : seeds) scaled.push_back({p.x * f->scale_u, p.y * f->scale_v});
  CdtResult cdt;
  Status st = ConstrainedTriangulation(scaled, segments, nullptr, &cdt);
  if (!st.ok()) {
    std::fprintf(stderr, "CDT failed: %s\n", st.message().c_str());
    return;
  }
  for (Vec2 p : uv) {
    Vec3 x = s.Point(p.x, p.y);
    f->mesh.AddNode(p, x, s.Normal(p.x, p.y), true, NodeRef{0, 0, 0});
  }
  for (Vec2 p : seeds) f->mesh.AddNode(p, s.Point(p.x, p.y), s.Normal(p.x, p.y), false, NodeRef{});
  InitWorkMesh(cdt.triangles, cdt.constrained, splittable, &f->mesh);
  RefineFace(&f->mesh, s, face, f->scale_u, f->scale_v, max_triangles, improve, nullptr, &f->stats);
}

}  // namespace rdmesh::testing
