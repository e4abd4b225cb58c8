#include "face/first_triangulation.h"

#include <algorithm>
#include <cmath>

#include "face/cdt.h"
#include "face/measure.h"

namespace rdmesh {

namespace {

bool Stopping(const Context* context) { return context && context->ShouldStop(); }

// Seeds closer than this (of the scaled domain's size) to a singular line are left out.
constexpr double kLineClearance = 0.01;

double SegmentDistance(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 d = b - a, w = p - a;
  const double len2 = d.x * d.x + d.y * d.y;
  const double s = len2 > 0 ? std::clamp((w.x * d.x + w.y * d.y) / len2, 0.0, 1.0) : 0.0;
  const Vec2 foot = a + s * d;
  return std::hypot(p.x - foot.x, p.y - foot.y);
}

}  // namespace

Status TriangulateDomain(const FaceDomain& domain, const std::vector<Vec2>& seeds, Surface& surface,
                         Context* context, WorkMesh* mesh) {
  *mesh = WorkMesh();
  std::vector<Vec2> points;
  points.reserve(domain.uv.size() + seeds.size());
  for (const Vec2& p : domain.uv) points.push_back({p.x * domain.scale_u, p.y * domain.scale_v});
  // A seed on or beside a singular line would split its constraint, or make slivers across it.
  std::vector<Vec2> kept;
  const std::vector<Vec2>* seeds_used = &seeds;
  if (!domain.line_segments.empty()) {
    const double clear = kLineClearance * std::max((domain.umax - domain.umin) * domain.scale_u,
                                                   (domain.vmax - domain.vmin) * domain.scale_v);
    for (const Vec2& p : seeds) {
      bool near = false;
      for (const auto& s : domain.line_segments) {
        const Vec2 a = domain.uv[s[0]], b = domain.uv[s[1]];
        const Vec2 sa = {a.x * domain.scale_u, a.y * domain.scale_v};
        const Vec2 sb = {b.x * domain.scale_u, b.y * domain.scale_v};
        near =
            near || SegmentDistance({p.x * domain.scale_u, p.y * domain.scale_v}, sa, sb) < clear;
      }
      if (!near) kept.push_back(p);
    }
    seeds_used = &kept;
  }
  for (const Vec2& p : *seeds_used) points.push_back({p.x * domain.scale_u, p.y * domain.scale_v});
  CdtResult cdt;
  Status st =
      ConstrainedTriangulation(points, domain.segments, domain.line_segments, context, &cdt);
  if (Stopping(context)) return context->StopStatus();
  if (!st.ok()) return st;
  // A face of 10^5 boundary nodes (absurd options) spends seconds here under a sanitizer:
  // poll every few thousand nodes.
  auto stop_every = [context](size_t i) { return (i & 4095) == 4095 && Stopping(context); };
  for (size_t i = 0; i < domain.uv.size(); ++i) {
    const Vec2& q = domain.uv[i];
    mesh->AddNode(q, domain.xyz[i], surface.Normal(q.x, q.y), true, domain.ref[i]);
    if (stop_every(i)) return context->StopStatus();
  }
  for (size_t i = 0; i < seeds_used->size(); ++i) {
    const Vec2& q = (*seeds_used)[i];
    mesh->AddNode(q, surface.Point(q.x, q.y), surface.Normal(q.x, q.y), false, NodeRef{});
    if (stop_every(i)) return context->StopStatus();
  }
  std::vector<std::array<int, 2>> splittable;
  for (size_t s = 0; s < domain.segments.size(); ++s)
    if (domain.segment_splittable[s]) splittable.push_back(domain.segments[s]);
  splittable.insert(splittable.end(), domain.line_segments.begin(), domain.line_segments.end());
  InitWorkMesh(cdt.triangles, cdt.constrained, splittable, mesh);
  if (Stopping(context)) return context->StopStatus();
  return Status::Ok();
}

Status TurnLimitedTriangulation(const FaceDomain& domain, std::vector<Vec2> seeds, Surface& surface,
                                double min_normal_cos, double max_turn, int rounds,
                                size_t max_seeds, Context* context, WorkMesh* mesh) {
  const double min_cos = std::cos(max_turn);
  for (int round = 0;; ++round) {
    Status st = TriangulateDomain(domain, seeds, surface, context, mesh);
    if (!st.ok() || round == rounds) return st;
    std::vector<Vec2> more;
    for (size_t t = 0; t < mesh->tri.size(); ++t) {
      if (!mesh->alive[t]) continue;
      Vec2 uv[3];
      Vec3 xyz[3], normals[3];
      mesh->FoldCorners(mesh->tri[t], uv, xyz, normals);
      double turn = 1;  // the smallest cosine between two corners' normals
      for (int i = 0; i < 3; ++i) turn = std::min(turn, Dot(normals[i], normals[(i + 1) % 3]));
      if (turn >= min_cos && TriangleAgreement(uv, xyz, normals) >= min_normal_cos) continue;
      const Tri& c = mesh->tri[t];
      more.push_back((1.0 / 3) * (mesh->uv[c[0]] + mesh->uv[c[1]] + mesh->uv[c[2]]));
    }
    if (more.empty() || seeds.size() + more.size() > max_seeds) return Status::Ok();
    seeds.insert(seeds.end(), more.begin(), more.end());
  }
}

}  // namespace rdmesh
