#include "face/first_triangulation.h"

#include <algorithm>
#include <cmath>

#include "face/cdt.h"
#include "face/measure.h"

namespace rdmesh {

namespace {

bool Stopping(const Context* context) { return context && context->ShouldStop(); }

}  // namespace

Status TriangulateDomain(const FaceDomain& domain, const std::vector<Vec2>& seeds, Surface& surface,
                         Context* context, WorkMesh* mesh) {
  *mesh = WorkMesh();
  std::vector<Vec2> points;
  points.reserve(domain.uv.size() + seeds.size());
  for (const Vec2& p : domain.uv) points.push_back({p.x * domain.scale_u, p.y * domain.scale_v});
  for (const Vec2& p : seeds) points.push_back({p.x * domain.scale_u, p.y * domain.scale_v});
  CdtResult cdt;
  Status st = ConstrainedTriangulation(points, domain.segments, context, &cdt);
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
  for (size_t i = 0; i < seeds.size(); ++i) {
    const Vec2& q = seeds[i];
    mesh->AddNode(q, surface.Point(q.x, q.y), surface.Normal(q.x, q.y), false, NodeRef{});
    if (stop_every(i)) return context->StopStatus();
  }
  std::vector<std::array<int, 2>> splittable;
  for (size_t s = 0; s < domain.segments.size(); ++s)
    if (domain.segment_splittable[s]) splittable.push_back(domain.segments[s]);
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
