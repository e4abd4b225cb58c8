#include "face_domain.h"

#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <cmath>

#include "model.h"

namespace rdmesh {

namespace {

Vec3 VertexPoint(const Model& model, int vertex_id) {
  gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(model.vertices(vertex_id)));
  return {p.X(), p.Y(), p.Z()};
}

double SegmentDistance2(Vec2 p, Vec2 a, Vec2 b) {
  Vec2 ab = b - a, ap = p - a;
  double l2 = ab.x * ab.x + ab.y * ab.y;
  double t = l2 > 0 ? std::clamp((ap.x * ab.x + ap.y * ab.y) / l2, 0.0, 1.0) : 0.0;
  Vec2 d = p - (a + t * ab);
  return d.x * d.x + d.y * d.y;
}

void ComputeScale(Surface& s, FaceDomain* d) {
  double du = (d->umax - d->umin), dv = (d->vmax - d->vmin);
  double hu = 1e-4 * std::max(du, 1e-12), hv = 1e-4 * std::max(dv, 1e-12);
  double su = 0, sv = 0;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      double u = d->umin + du * (i + 0.5) / 5, v = d->vmin + dv * (j + 0.5) / 5;
      Vec3 p = s.Point(u, v);
      su += Dist(s.Point(u + hu, v), p) / hu;
      sv += Dist(s.Point(u, v + hv), p) / hv;
    }
  }
  d->scale_u = su > 0 ? su / 25 : 1;
  d->scale_v = sv > 0 ? sv / 25 : 1;
  if (!std::isfinite(d->scale_u) || d->scale_u <= 0) d->scale_u = 1;
  if (!std::isfinite(d->scale_v) || d->scale_v <= 0) d->scale_v = 1;
}

}  // namespace

Status BuildFaceDomain(const Model& model, int face_id, const std::vector<EdgeGrid>& grids,
                       Surface& surface, FaceDomain* d) {
  *d = FaceDomain();
  TopoDS_Face face = TopoDS::Face(model.face(face_id).Oriented(TopAbs_FORWARD));
  for (TopExp_Explorer wexp(face, TopAbs_WIRE); wexp.More(); wexp.Next()) {
    TopoDS_Wire wire = TopoDS::Wire(wexp.Current());
    const int loop_start = static_cast<int>(d->uv.size());
    Vec2 loop_end_uv;
    for (BRepTools_WireExplorer ex(wire, face); ex.More(); ex.Next()) {
      TopoDS_Edge e = ex.Current();
      if (e.Orientation() == TopAbs_INTERNAL || e.Orientation() == TopAbs_EXTERNAL) continue;
      int eid = model.edges.FindIndex(e);
      if (eid == 0)
        return Status(StatusCode::kInternal, "a face edge is missing from the edge map");
      const EdgeGrid& g = grids[eid - 1];
      if (g.t.size() < 2)
        return Status(StatusCode::kInternal, "edge " + std::to_string(eid) + " has no grid");
      double f, l;
      Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(e, face, f, l);
      if (pcurve.IsNull())
        return Status(StatusCode::kInternal,
                      "edge " + std::to_string(eid) + " has no pcurve on the face");
      const bool reversed = e.Orientation() == TopAbs_REVERSED;
      const int n = static_cast<int>(g.t.size());
      for (int k = 0; k < n; ++k) {
        int idx = reversed ? n - 1 - k : k;
        gp_Pnt2d p = pcurve->Value(g.t[idx]);
        Vec2 uv{p.X(), p.Y()};
        if (k == n - 1) {  // the next edge starts here
          loop_end_uv = uv;
          break;
        }
        NodeRef ref;
        Vec3 xyz;
        if (idx == 0 || idx == n - 1) {
          ref.dim = 0;
          ref.entity = idx == 0 ? g.first_vertex : g.last_vertex;
          xyz = VertexPoint(model, ref.entity);
        } else {
          ref.dim = 1;
          ref.entity = eid;
          ref.t = g.t[idx];
          xyz = g.xyz[idx];
        }
        int node = static_cast<int>(d->uv.size());
        d->uv.push_back(uv);
        d->xyz.push_back(xyz);
        d->ref.push_back(ref);
        d->segments.push_back({node, node + 1});
        d->segment_splittable.push_back(g.degenerate);
      }
    }
    const int loop_end = static_cast<int>(d->uv.size());
    if (loop_end - loop_start < 2) {
      d->uv.resize(loop_start), d->xyz.resize(loop_start), d->ref.resize(loop_start);
      d->segments.resize(loop_start), d->segment_splittable.resize(loop_start);
      continue;
    }
    d->segments.back()[1] = loop_start;  // close the loop
    // The last pcurve must end where the first began.
    Vec2 gap = loop_end_uv - d->uv[loop_start];
    double span = 0;
    for (int i = loop_start; i < loop_end; ++i) {
      span = std::max(span, std::fabs(d->uv[i].x - d->uv[loop_start].x));
      span = std::max(span, std::fabs(d->uv[i].y - d->uv[loop_start].y));
    }
    if (std::hypot(gap.x, gap.y) > 1e-3 * std::max(span, 1e-12) + 1e-9)
      return Status(StatusCode::kInternal, "a boundary loop does not close in (u,v)");
  }
  if (d->uv.size() < 3) return Status(StatusCode::kInternal, "the face has no boundary loop");
  d->umin = d->umax = d->uv[0].x;
  d->vmin = d->vmax = d->uv[0].y;
  for (const Vec2& p : d->uv) {
    d->umin = std::min(d->umin, p.x), d->umax = std::max(d->umax, p.x);
    d->vmin = std::min(d->vmin, p.y), d->vmax = std::max(d->vmax, p.y);
  }
  ComputeScale(surface, d);
  return Status::Ok();
}

bool InsideDomain(const FaceDomain& d, Vec2 p) {
  bool inside = false;
  for (const auto& s : d.segments) {
    Vec2 a = d.uv[s[0]], b = d.uv[s[1]];
    if ((a.y > p.y) != (b.y > p.y)) {
      double x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
      if (p.x < x) inside = !inside;
    }
  }
  return inside;
}

std::vector<Vec2> SeedPoints(const FaceDomain& d, Surface& s) {
  const int kProbe = 9;
  double du = d.umax - d.umin, dv = d.vmax - d.vmin;
  auto turn = [&](bool along_u) {
    double worst = 0;
    for (int j = 0; j < 5; ++j) {
      double total = 0;
      Vec3 prev;
      for (int i = 0; i < kProbe; ++i) {
        double a = static_cast<double>(i) / (kProbe - 1), b = (j + 0.5) / 5;
        double u = d.umin + du * (along_u ? a : b), v = d.vmin + dv * (along_u ? b : a);
        Vec3 n = s.Normal(u, v);
        if (i > 0) total += std::acos(std::clamp(Dot(n, prev), -1.0, 1.0));
        prev = n;
      }
      worst = std::max(worst, total);
    }
    return worst;
  };
  const double kStep = M_PI / 6;
  int nu = std::clamp(static_cast<int>(std::ceil(turn(true) / kStep - 1e-9)), 1, 12);
  int nv = std::clamp(static_cast<int>(std::ceil(turn(false) / kStep - 1e-9)), 1, 12);
  std::vector<Vec2> seeds;
  if (nu * nv <= 1) return seeds;
  double cell = std::min(du * d.scale_u / nu, dv * d.scale_v / nv);
  double clearance2 = (0.35 * cell) * (0.35 * cell);
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      Vec2 p{d.umin + du * (i + 0.5) / nu, d.vmin + dv * (j + 0.5) / nv};
      if (!InsideDomain(d, p)) continue;
      Vec2 ps{p.x * d.scale_u, p.y * d.scale_v};
      bool clear = true;
      for (const auto& seg : d.segments) {
        Vec2 a{d.uv[seg[0]].x * d.scale_u, d.uv[seg[0]].y * d.scale_v};
        Vec2 b{d.uv[seg[1]].x * d.scale_u, d.uv[seg[1]].y * d.scale_v};
        if (SegmentDistance2(ps, a, b) < clearance2) {
          clear = false;
          break;
        }
      }
      if (clear) seeds.push_back(p);
    }
  }
  return seeds;
}

}  // namespace rdmesh
