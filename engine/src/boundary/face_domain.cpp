#include "boundary/face_domain.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRep_Tool.hxx>
#include <Standard_Failure.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "model/model.h"

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

// A pcurve may miss its edge by far more than the meshing tolerance and still be valid within a
// loose edge tolerance (Rhino's trimmed NURBS: up to a third of a segment). Boundary nodes at
// such (u,v) sit beside the surface point they stand for, and the triangles along the boundary
// then stand on edge and can neither meet the criteria nor be split without folding. Where
// S(pcurve) misses a grid point by more than kPcurveMiss of its shorter segment, the node takes
// the (u,v) where the surface passes through the point instead: Gauss-Newton from the pcurve's
// (u,v), kept only when it lands on the point (within a tenth of the miss).
constexpr double kPcurveMiss = 0.01;

// Gauss-Newton steps from `start` toward the surface's point nearest `target` (finite
// differences), from a distance `gap`, while a step brings it closer and it is above `stop`;
// the distance reached into *reached.
Vec2 DescendToward(Surface& s, Vec2 start, Vec3 target, double gap, double stop, double* reached) {
  const double hu = 1e-7 * std::max(s.umax - s.umin, 1e-12);
  const double hv = 1e-7 * std::max(s.vmax - s.vmin, 1e-12);
  Vec2 q = start;
  for (int iter = 0; iter < 8 && gap > stop; ++iter) {
    Vec3 p = s.Point(q.x, q.y);
    Vec3 su = (1.0 / hu) * (s.Point(q.x + hu, q.y) - p);
    Vec3 sv = (1.0 / hv) * (s.Point(q.x, q.y + hv) - p);
    Vec3 r = target - p;
    // Normal equations of the 2x2 least-squares step.
    double a = Dot(su, su), b = Dot(su, sv), c = Dot(sv, sv);
    double det = a * c - b * b;
    if (!(det > 1e-24 * a * c)) break;
    double ru = Dot(su, r), rv = Dot(sv, r);
    Vec2 next{q.x + (c * ru - b * rv) / det, q.y + (a * rv - b * ru) / det};
    double next_gap = Dist(s.Point(next.x, next.y), target);
    if (!(next_gap < gap)) break;
    q = next, gap = next_gap;
  }
  *reached = gap;
  return q;
}

Vec2 ProjectNear(Surface& s, Vec2 start, Vec3 target, double miss) {
  double gap;
  const Vec2 q = DescendToward(s, start, target, miss, 1e-3 * miss, &gap);
  return gap <= 0.1 * miss ? q : start;
}

// One edge of a wire as the wire explorer walks it: its grid points' (u,v) in walking order.
struct EdgeWalk {
  int eid = 0;
  bool reversed = false;
  std::vector<Vec2> uv;
};

// A pcurve that misses its edge by more than this fraction of the edge's length is no guide to
// where the edge lies on the surface (RepairLoosePcurve).
constexpr double kLoosePcurve = 0.5;
// RepairLoosePcurve looks for a point's nearest surface point from the best of this many
// (u,v) samples along each parameter.
constexpr int kRepairSamples = 24;

// The (u,v) where the surface passes through `target`, searched over the surface's whole range:
// the nearest of a grid of samples, then Gauss-Newton (ProjectNear). `found` false when that does
// not land on the point (within 1e-3 of `scale`).
Vec2 ProjectFromAfar(Surface& s, Vec3 target, double scale, bool* found) {
  Vec2 best{s.umin, s.vmin};
  double nearest = HUGE_VAL;
  for (int i = 0; i <= kRepairSamples; ++i)
    for (int j = 0; j <= kRepairSamples; ++j) {
      const Vec2 q{s.umin + (s.umax - s.umin) * i / kRepairSamples,
                   s.vmin + (s.vmax - s.vmin) * j / kRepairSamples};
      const double d = Dist(s.Point(q.x, q.y), target);
      if (d < nearest) nearest = d, best = q;
    }
  const Vec2 q = nearest > 0 ? ProjectNear(s, best, target, nearest) : best;
  *found = Dist(s.Point(q.x, q.y), target) <= 1e-3 * scale;
  return q;
}

// Where a walk's pcurve misses the edge's grid points by more than `loose` of the edge's length
// (kLoosePcurve: NXP_MPL115A1's file has no pcurves, and the reader projects its fillet arcs, 0.24
// long, onto wrong turns, up to 0.4 off, issue 35; the edges' 3D curves lie on the surface), the
// walk takes the (u,v) of its points on the surface instead, each moved by whole periods next to
// the one before. Left as it is when a point does not lie on the surface.
void RepairLoosePcurve(const Model& model, const std::vector<EdgeGrid>& grids, double period_u,
                       double period_v, double loose, Surface& surface, EdgeWalk* w) {
  const EdgeGrid& g = grids[w->eid - 1];
  if (g.degenerate) return;
  const int n = static_cast<int>(w->uv.size());
  std::vector<Vec3> xyz(n);
  double length = 0, miss = 0;
  for (int k = 0; k < n; ++k) {
    const int idx = w->reversed ? n - 1 - k : k;
    xyz[k] = idx == 0       ? VertexPoint(model, g.first_vertex)
             : idx == n - 1 ? VertexPoint(model, g.last_vertex)
                            : g.xyz[idx];
    if (k > 0) length += Dist(xyz[k], xyz[k - 1]);
    miss = std::max(miss, Dist(surface.Point(w->uv[k].x, w->uv[k].y), xyz[k]));
  }
  if (!(miss > loose * length)) return;
  std::vector<Vec2> uv(n);
  bool found = true;
  for (int k = 0; k < n && found; ++k) {
    uv[k] = ProjectFromAfar(surface, xyz[k], std::max(length, miss), &found);
    if (k == 0) continue;
    for (auto [period, axis] : {std::pair(period_u, &Vec2::x), std::pair(period_v, &Vec2::y)})
      if (period > 0) uv[k].*axis += period * std::round((uv[k - 1].*axis - uv[k].*axis) / period);
  }
  if (found) w->uv = std::move(uv);
}

// A pcurve may cross its surface's seam inside an edge by running back over the whole period (a
// KiCad toroid's 0.0014 mm edge, whose B-spline pcurve drops from u = 2pi to u = 0 between two
// of its grid points, issue 35): two points a chord apart in 3D then lie a period apart in
// (u,v), and the loop sweeps the whole surface. Where the (u,v) middle of two consecutive grid
// points, the second moved by whole periods next to the first, lies on the edge's curve at the
// middle parameter and the unmoved middle lies off it by more than twice as far, the walk's
// points from the second on move by those periods. A step under half a period is never moved.
void UnwrapSeamJumps(const Model& model, const std::vector<EdgeGrid>& grids, double period_u,
                     double period_v, Surface& surface, std::vector<EdgeWalk>* walks) {
  for (EdgeWalk& w : *walks) {
    const EdgeGrid& g = grids[w.eid - 1];
    const int n = static_cast<int>(w.uv.size());
    if (g.degenerate || n != static_cast<int>(g.t.size())) continue;
    std::unique_ptr<Curve> curve;
    for (int k = 1; k < n; ++k) {
      Vec2 shift{0, 0};
      for (auto [period, axis] : {std::pair(period_u, &Vec2::x), std::pair(period_v, &Vec2::y)})
        if (period > 0)
          shift.*axis = period * std::round((w.uv[k - 1].*axis - w.uv[k].*axis) / period);
      if (shift.x == 0 && shift.y == 0) continue;
      if (!curve) curve = MakeEdgeCurve(TopoDS::Edge(model.edge(w.eid).Oriented(TopAbs_FORWARD)));
      if (!curve) break;
      const int a = w.reversed ? n - k : k - 1, b = w.reversed ? n - 1 - k : k;
      const Vec3 middle = curve->Point(0.5 * (g.t[a] + g.t[b]));
      const Vec2 as_is = 0.5 * (w.uv[k - 1] + w.uv[k]), moved = as_is + 0.5 * shift;
      const double off = Dist(surface.Point(as_is.x, as_is.y), middle);
      const double on = Dist(surface.Point(moved.x, moved.y), middle);
      if (!(2 * on < off)) continue;
      for (int j = k; j < n; ++j) w.uv[j] = w.uv[j] + shift;
    }
  }
}

double VertexTolerance(const Model& model, int vertex_id) {
  return vertex_id > 0 ? BRep_Tool::Tolerance(TopoDS::Vertex(model.vertices(vertex_id))) : 0.0;
}

std::string EdgeName(int eid) { return "edge " + std::to_string(eid); }

// Walks one wire of the face: its edges' grid points in (u,v). Fails for an edge without id,
// grid or pcurve, and for a wire whose edges do not connect.
Status WalkWire(const FaceWire& wire, const std::vector<EdgeGrid>& grids,
                std::vector<EdgeWalk>* walks) {
  walks->clear();
  for (const WireEdge& e : wire.edges) {
    EdgeWalk w;
    w.eid = e.eid;
    if (w.eid == 0)
      return Status(StatusCode::kInternal, "a face edge is missing from the edge map");
    const EdgeGrid& g = grids[w.eid - 1];
    if (g.t.size() < 2) return Status(StatusCode::kInternal, EdgeName(w.eid) + " has no grid");
    if (e.pcurve.IsNull())
      return Status(StatusCode::kInternal, EdgeName(w.eid) + " has no pcurve on the face");
    w.reversed = e.reversed;
    const int n = static_cast<int>(g.t.size());
    for (int k = 0; k < n; ++k) {
      gp_Pnt2d p = e.pcurve->Value(g.t[w.reversed ? n - 1 - k : k]);
      w.uv.push_back({p.X(), p.Y()});
    }
    walks->push_back(std::move(w));
  }
  return wire.reached;
}

// Where one pcurve ends and the next begins: moves the next walk by whole periods when that
// makes the ends meet, and checks that what is left of the gap is within the tolerance of the
// vertex they share (the B-rep promises no more). `wrap` is the junction that closes the loop.
Status JoinWalks(const Model& model, const EdgeGrid& from_grid, const EdgeWalk& from, EdgeWalk* to,
                 bool wrap, double period_u, double period_v, double uv_slack, Surface& surface) {
  Vec2 end = from.uv.back(), start = to->uv.front();
  if (!wrap) {
    auto shift = [&](double period, double Vec2::*axis) {
      if (period <= 0) return;
      double k = std::round((end.*axis - start.*axis) / period);
      if (k == 0 || std::fabs(end.*axis - (start.*axis + k * period)) > 1e-3 * period) return;
      for (Vec2& p : to->uv) p.*axis += k * period;
    };
    shift(period_u, &Vec2::x);
    shift(period_v, &Vec2::y);
    start = to->uv.front();
  }
  Vec2 gap = start - end;
  if (std::hypot(gap.x, gap.y) <= uv_slack) return Status::Ok();
  const int vertex = from.reversed ? from_grid.first_vertex : from_grid.last_vertex;
  double tol = VertexTolerance(model, vertex);
  for (int eid : {from.eid, to->eid})
    tol = std::max(tol, BRep_Tool::Tolerance(TopoDS::Edge(model.edge(eid))));
  const double gap3 = Dist(surface.Point(end.x, end.y), surface.Point(start.x, start.y));
  if (gap3 <= 2 * tol * (1 + 1e-6) + 1e-12) return Status::Ok();
  char buf[200];
  std::snprintf(buf, sizeof(buf),
                " do not meet in (u,v): their pcurve ends at vertex %d are %.3g apart on the "
                "surface, more than twice its tolerance %.3g",
                vertex, gap3, tol);
  return Status(StatusCode::kInternal,
                std::string(wrap ? "a boundary loop does not close in (u,v): " : "") +
                    EdgeName(from.eid) + " and " + EdgeName(to->eid) + buf);
}

// Joins each walk of a loop to the next (JoinWalks), the last to the first.
Status JoinLoop(const Model& model, const std::vector<EdgeGrid>& grids, double period_u,
                double period_v, double slack, Surface& surface, std::vector<EdgeWalk>* walks) {
  const int m = static_cast<int>(walks->size());
  for (int i = 0; i < m; ++i) {
    const int j = (i + 1) % m;
    Status st = JoinWalks(model, grids[(*walks)[i].eid - 1], (*walks)[i], &(*walks)[j], j == 0,
                          period_u, period_v, slack, surface);
    if (!st.ok()) return st;
  }
  return Status::Ok();
}

// Whether a joined loop runs over more than one period of a periodic parameter.
bool CoversMoreThanAPeriod(const std::vector<EdgeWalk>& walks, double period_u, double period_v) {
  for (auto [period, axis] : {std::pair(period_u, &Vec2::x), std::pair(period_v, &Vec2::y)}) {
    if (period <= 0) continue;
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    for (const EdgeWalk& w : walks)
      for (const Vec2& p : w.uv) lo = std::min(lo, p.*axis), hi = std::max(hi, p.*axis);
    if (hi - lo > period * (1 + 1e-6)) return true;
  }
  return false;
}

// The area a joined loop encloses in (u,v), signed (counter-clockwise positive).
double LoopArea(const std::vector<EdgeWalk>& walks) {
  double area = 0;
  const Vec2* prev = nullptr;
  for (const EdgeWalk& w : walks)
    for (const Vec2& p : w.uv) {
      if (prev) area += Cross(*prev, p);
      prev = &p;
    }
  if (prev) area += Cross(*prev, walks.front().uv.front());
  return 0.5 * area;
}

// A loop that covers its surface more than once, the rest of its turns made of degenerate edges:
// the pin rings of a KiCad transformer (issue 35) are faces of revolution whose loop runs over two
// or three turns in u, each real circle over one turn, and edges flagged degenerate (a point in
// 3D, within vertex tolerances from 2e-7 to 0.9) over the other turns, where the surface is a
// whole circle. Meshed as they are, the degenerate edges pinch a turn of the ring into a point and
// every triangle there folds. The loop is the same face once, without those edges, when it still
// closes (JoinWalks, `unjoined` the walks before any join) over at most one turn and encloses an
// area (a sphere's two seams without its poles enclose none): then that loop into *walks.
bool WithoutOverlap(const Model& model, const std::vector<EdgeGrid>& grids,
                    const std::vector<EdgeWalk>& unjoined, double period_u, double period_v,
                    double slack, double span, Surface& surface, std::vector<EdgeWalk>* walks) {
  std::vector<EdgeWalk> kept;
  for (const EdgeWalk& w : unjoined)
    if (!grids[w.eid - 1].degenerate || !BRep_Tool::Degenerated(TopoDS::Edge(model.edge(w.eid))))
      kept.push_back(w);
  if (kept.empty() || kept.size() == unjoined.size()) return false;
  if (!JoinLoop(model, grids, period_u, period_v, slack, surface, &kept).ok()) return false;
  if (CoversMoreThanAPeriod(kept, period_u, period_v)) return false;
  if (!(std::fabs(LoopArea(kept)) > slack * span)) return false;
  *walks = std::move(kept);
  return true;
}

// Per walk of a joined loop, whether it meets a neighbour only within the B-rep's tolerance: its
// end and the next walk's start (the last's end and the first's start, after whole periods: a loop
// around a cylinder closes a turn on) more than `slack` apart in (u,v).
std::vector<bool> AtLooseJunctions(const std::vector<EdgeWalk>& walks, double period_u,
                                   double period_v, double slack) {
  const int m = static_cast<int>(walks.size());
  std::vector<bool> loose(m, false);
  for (int i = 0; i < m; ++i) {
    const int j = (i + 1) % m;
    Vec2 gap = walks[j].uv.front() - walks[i].uv.back();
    if (j == 0)
      for (auto [period, axis] : {std::pair(period_u, &Vec2::x), std::pair(period_v, &Vec2::y)})
        if (period > 0) gap.*axis -= period * std::round(gap.*axis / period);
    if (std::hypot(gap.x, gap.y) > slack) loose[i] = loose[j] = true;
  }
  return loose;
}

// On a periodic surface, where two walks of a loop meet only within the B-rep's tolerance, the
// walks at that junction whose pcurves miss their edges by more than kPcurveMiss of the length take
// their points on the surface (RepairLoosePcurve), and the loop is joined again from `unjoined`
// (the walks before any join); kept, into *walks and *unjoined, when all its walks then meet.
// JoinWalks moves a walk by whole periods only onto the end before it, so a pcurve that ends on a
// wrong turn puts the walks after it on that turn (issue 35: NXP_MPL115A1's fillet corners, whose
// reader-made pcurves end up to half a turn off, within the 0.4 tolerance but under kLoosePcurve
// of the edge's length).
void MeetOnTheSurface(const Model& model, const std::vector<EdgeGrid>& grids, double period_u,
                      double period_v, double slack, Surface& surface,
                      std::vector<EdgeWalk>* unjoined, std::vector<EdgeWalk>* walks) {
  if (period_u <= 0 && period_v <= 0) return;
  const std::vector<bool> loose = AtLooseJunctions(*walks, period_u, period_v, slack);
  if (std::find(loose.begin(), loose.end(), true) == loose.end()) return;
  std::vector<EdgeWalk> placed = *unjoined;
  for (size_t i = 0; i < placed.size(); ++i)
    if (loose[i])
      RepairLoosePcurve(model, grids, period_u, period_v, kPcurveMiss, surface, &placed[i]);
  const std::vector<EdgeWalk> before = placed;
  if (!JoinLoop(model, grids, period_u, period_v, slack, surface, &placed).ok()) return;
  const std::vector<bool> still = AtLooseJunctions(placed, period_u, period_v, slack);
  if (std::find(still.begin(), still.end(), true) != still.end()) return;
  *unjoined = before;
  *walks = std::move(placed);
}

// The node a vertex takes where loops touch at it (or one loop passes it twice): among the
// vertex's nodes so far (`nodes`), the one at the same (u,v), or else the nearest within `slack`
// (pcurves that meet at the vertex only up to rounding: 3e-16 apart where a LED's hole touches
// its outline) that is not a neighbour in its own loop (`before`, `after`: a short or degenerate
// edge between two nodes of one vertex stays a segment); -1 for a node of its own.
int VertexNode(const FaceDomain& d, const std::vector<int>& nodes, Vec2 uv, double slack,
               int before, int after) {
  for (int other : nodes)
    if (d.uv[other].x == uv.x && d.uv[other].y == uv.y) return other;
  int nearest = -1;
  double best = slack;
  for (int other : nodes) {
    if (other == before || other == after) continue;
    const double gap = std::hypot(d.uv[other].x - uv.x, d.uv[other].y - uv.y);
    if (gap <= best) nearest = other, best = gap;
  }
  return nearest;
}

// Whether edge grid `g` has no length: every point of it within its vertex's tolerance of the
// vertex. Such an edge runs from a point to itself (the LED_D3.0mm
// models of KiCad's library carry one in a planar face's outline); its ends' (u,v) may differ by
// rounding, and two nodes there make the loop's segments either side touch.
bool NoLength(const Model& model, const EdgeGrid& g, int vertex) {
  const Vec3 p = VertexPoint(model, vertex);
  const double tolerance = BRep_Tool::Tolerance(TopoDS::Vertex(model.vertices(vertex)));
  for (const Vec3& q : g.xyz)
    if (Dist(p, q) > tolerance) return false;
  return !g.xyz.empty();
}

// Whether grid segment `k` of edge `a` and grid segment `l` of edge `b` lie on each other in 3D:
// their middles within the two edges' tolerances.
bool OnEachOther(const Model& model, const std::vector<EdgeGrid>& grids, int a, int k, int b,
                 int l) {
  const std::unique_ptr<Curve> ca = MakeEdgeCurve(
                                   TopoDS::Edge(model.edge(a).Oriented(TopAbs_FORWARD))),
                               cb = MakeEdgeCurve(
                                   TopoDS::Edge(model.edge(b).Oriented(TopAbs_FORWARD)));
  if (!ca || !cb) return false;
  const std::vector<double>&ta = grids[a - 1].t, &tb = grids[b - 1].t;
  const Vec3 ma = ca->Point(0.5 * (ta[k] + ta[k + 1])), mb = cb->Point(0.5 * (tb[l] + tb[l + 1]));
  return Dist(ma, mb) <= BRep_Tool::Tolerance(TopoDS::Edge(model.edge(a))) +
                             BRep_Tool::Tolerance(TopoDS::Edge(model.edge(b)));
}

// Removes pinches: two segments of different edges that join the same two nodes in opposite
// directions and lie on each other in 3D. Where two loops touch along such a chord (a square
// hole whose side lies on the outline's), the face has no width there, and the two segments
// would stand for one constraint that the triangulation's nesting rule counts once, so the hole
// beside it would be meshed. Without both, the loops join into closed loops still (each node
// keeps as many segments in as out). Segments that only share their ends (an arc and its chord,
// each one segment) are left to healing.
void DropPinches(const Model& model, const std::vector<EdgeGrid>& grids, FaceDomain* d) {
  const int ns = static_cast<int>(d->segments.size());
  std::map<std::pair<int, int>, std::vector<int>> by_nodes;
  for (int s = 0; s < ns; ++s) by_nodes[{d->segments[s][0], d->segments[s][1]}].push_back(s);
  std::vector<bool> drop(ns, false);
  for (int s = 0; s < ns; ++s) {
    const auto [a, b] = std::pair(d->segments[s][0], d->segments[s][1]);
    if (drop[s] || a == b || d->segment_edge[s] == 0) continue;
    const auto twins = by_nodes.find({b, a});
    if (twins == by_nodes.end()) continue;
    for (int t : twins->second)
      if (!drop[t] && d->segment_edge[t] != 0 && d->segment_edge[t] != d->segment_edge[s] &&
          OnEachOther(model, grids, d->segment_edge[s], d->segment_grid_index[s],
                      d->segment_edge[t], d->segment_grid_index[t])) {
        drop[s] = drop[t] = true;
        break;
      }
  }
  if (std::find(drop.begin(), drop.end(), true) == drop.end()) return;
  FaceDomain kept = *d;
  kept.segments.clear(), kept.segment_splittable.clear(), kept.segment_edge.clear();
  kept.segment_grid_index.clear(), kept.loop_begin.clear();
  for (size_t k = 0; k < d->loop_begin.size(); ++k) {
    const int end = k + 1 < d->loop_begin.size() ? d->loop_begin[k + 1] : ns;
    const int begin = static_cast<int>(kept.segments.size());
    for (int s = d->loop_begin[k]; s < end; ++s) {
      if (drop[s]) continue;
      kept.segments.push_back(d->segments[s]);
      kept.segment_splittable.push_back(d->segment_splittable[s]);
      kept.segment_edge.push_back(d->segment_edge[s]);
      kept.segment_grid_index.push_back(d->segment_grid_index[s]);
    }
    if (static_cast<int>(kept.segments.size()) > begin) kept.loop_begin.push_back(begin);
  }
  *d = std::move(kept);
}

void SetBounds(Surface& surface, FaceDomain* d) {
  d->umin = d->umax = d->uv[0].x;
  d->vmin = d->vmax = d->uv[0].y;
  for (const Vec2& p : d->uv) {
    d->umin = std::min(d->umin, p.x), d->umax = std::max(d->umax, p.x);
    d->vmin = std::min(d->vmin, p.y), d->vmax = std::max(d->vmax, p.y);
  }
  ComputeScale(surface, d);
}

// The (u,v) of the surface's point nearest `target` (DescendToward, as ProjectNear, but kept
// wherever it ends: the target may lie off the surface).
Vec2 NearestOnSurface(Surface& s, Vec2 start, Vec3 target) {
  double gap;
  return DescendToward(s, start, target, Dist(s.Point(start.x, start.y), target), 0, &gap);
}

}  // namespace

Status BuildFaceDomain(const Model& model, const FacePcurves& pcurves, int face_id,
                       const std::vector<EdgeGrid>& grids, Surface& surface, FaceDomain* d) {
  *d = FaceDomain();
  FaceLoops scratch;
  const FaceLoops& loops = pcurves.Loops(model, face_id, &scratch);
  const double period_u = loops.period_u, period_v = loops.period_v;
  std::map<int, std::vector<int>> vertex_nodes;  // vertex id -> its nodes so far
  std::vector<EdgeWalk> walks;
  for (const FaceWire& wire : loops.wires) {
    Status st = WalkWire(wire, grids, &walks);
    if (!st.ok()) return st;
    if (walks.empty()) continue;
    for (EdgeWalk& w : walks)
      RepairLoosePcurve(model, grids, period_u, period_v, kLoosePcurve, surface, &w);
    UnwrapSeamJumps(model, grids, period_u, period_v, surface, &walks);
    // The slack for pcurve ends that meet: 1e-3 of the loop's extent in (u,v), as before any
    // tolerance is looked at.
    double span = 0;
    for (const EdgeWalk& w : walks)
      for (const Vec2& p : w.uv)
        span =
            std::max({span, std::fabs(p.x - walks[0].uv[0].x), std::fabs(p.y - walks[0].uv[0].y)});
    const double slack = 1e-3 * std::max(span, 1e-12) + 1e-9;
    std::vector<EdgeWalk> unjoined = walks;
    st = JoinLoop(model, grids, period_u, period_v, slack, surface, &walks);
    if (!st.ok()) return st;
    MeetOnTheSurface(model, grids, period_u, period_v, slack, surface, &unjoined, &walks);
    if (CoversMoreThanAPeriod(walks, period_u, period_v))
      WithoutOverlap(model, grids, unjoined, period_u, period_v, slack, span, surface, &walks);
    const int m = static_cast<int>(walks.size());
    // Nodes: every grid point but each walk's last, which is the next walk's first.
    std::vector<int> loop;
    std::vector<int> seg_edge, seg_index;
    std::vector<bool> seg_degenerate;
    for (int i = 0; i < m; ++i) {
      const EdgeWalk& w = walks[i];
      const EdgeGrid& g = grids[w.eid - 1];
      const int n = static_cast<int>(g.t.size());
      for (int k = 0; k + 1 < n; ++k) {
        const int idx = w.reversed ? n - 1 - k : k;
        NodeRef ref;
        Vec3 xyz;
        if (idx == 0 || idx == n - 1) {
          ref.dim = 0;
          ref.entity = idx == 0 ? g.first_vertex : g.last_vertex;
          xyz = VertexPoint(model, ref.entity);
        } else {
          ref.dim = 1;
          ref.entity = w.eid;
          ref.t = g.t[idx];
          xyz = g.xyz[idx];
        }
        Vec2 uv = w.uv[k];
        if (ref.dim == 1 && !g.degenerate) {
          double miss = Dist(surface.Point(uv.x, uv.y), xyz);
          double segment = std::min(Dist(xyz, g.xyz[idx - 1]), Dist(xyz, g.xyz[idx + 1]));
          if (miss > kPcurveMiss * segment) uv = ProjectNear(surface, uv, xyz, miss);
        }
        const int node_seg_index = w.reversed ? n - 2 - k : k;
        // The loop's last node comes before its first.
        const int before = loop.empty() ? -1 : loop.back();
        const int after = i == m - 1 && k == n - 2 && !loop.empty() ? loop.front() : -1;
        int node =
            ref.dim == 0 ? VertexNode(*d, vertex_nodes[ref.entity], uv, slack, before, after) : -1;
        // The same vertex again after an edge of no length whose ends' (u,v) differ by rounding
        // only (a pole's degenerated edge spans a real (u,v) segment and stays): one node.
        if (node < 0 && ref.dim == 0 && !loop.empty() && d->ref[loop.back()].dim == 0 &&
            d->ref[loop.back()].entity == ref.entity &&
            std::hypot(d->uv[loop.back()].x - uv.x, d->uv[loop.back()].y - uv.y) <= 1e-6 * slack &&
            NoLength(model, grids[seg_edge.back() - 1], ref.entity))
          node = loop.back();
        if (node >= 0 && !loop.empty() && node == loop.back()) {
          // Both ends of an edge at one (u,v): its segment of no length goes, and the node goes
          // on with this walk's segment.
          seg_edge.back() = w.eid;
          seg_index.back() = node_seg_index;
          seg_degenerate.back() = g.degenerate;
          continue;
        }
        if (node < 0) {
          node = static_cast<int>(d->uv.size());
          d->uv.push_back(uv);
          d->xyz.push_back(xyz);
          d->ref.push_back(ref);
          if (ref.dim == 0) vertex_nodes[ref.entity].push_back(node);
        }
        loop.push_back(node);
        seg_edge.push_back(w.eid);
        seg_index.push_back(node_seg_index);
        seg_degenerate.push_back(g.degenerate);
      }
    }
    if (loop.size() > 1 && loop.back() == loop.front()) {  // the loop closes on such an edge
      loop.pop_back(), seg_edge.pop_back(), seg_index.pop_back(), seg_degenerate.pop_back();
    }
    if (loop.size() < 2) continue;  // a lone pole: no boundary
    d->loop_begin.push_back(static_cast<int>(d->segments.size()));
    for (size_t k = 0; k < loop.size(); ++k) {
      d->segments.push_back({loop[k], loop[(k + 1) % loop.size()]});
      d->segment_splittable.push_back(seg_degenerate[k]);
      d->segment_edge.push_back(seg_edge[k]);
      d->segment_grid_index.push_back(seg_index[k]);
    }
  }
  DropPinches(model, grids, d);
  if (d->uv.size() < 2) return Status(StatusCode::kInternal, "the face has no boundary loop");
  SetBounds(surface, d);
  return Status::Ok();
}

int MoveVertexNodesToSurface(Surface& surface, FaceDomain* d) {
  const int nn = static_cast<int>(d->uv.size());
  std::vector<double> shorter(nn, HUGE_VAL);
  for (const auto& [a, b] : d->segments) {
    const double length = Dist(d->xyz[a], d->xyz[b]);
    shorter[a] = std::min(shorter[a], length), shorter[b] = std::min(shorter[b], length);
  }
  FaceDomain moved = *d;
  std::vector<bool> is_moved(nn, false);
  int count = 0;
  for (int i = 0; i < nn; ++i) {
    if (d->ref[i].dim != 0 || !(shorter[i] < HUGE_VAL)) continue;
    const Vec2 start = d->uv[i];
    const Vec2 q = NearestOnSurface(surface, start, d->xyz[i]);
    const Vec3 from = surface.Point(start.x, start.y), to = surface.Point(q.x, q.y);
    if (!(Dist(to, d->xyz[i]) < Dist(from, d->xyz[i])) ||
        !(Dist(from, to) > kPcurveMiss * shorter[i]))
      continue;
    moved.uv[i] = q, is_moved[i] = true, ++count;
  }
  if (count == 0) return 0;
  SetBounds(surface, &moved);
  for (const DomainConflict& c : FindConflicts(moved))
    for (int s : {c.a, c.b})
      if (s >= 0 && (is_moved[moved.segments[s][0]] || is_moved[moved.segments[s][1]])) return 0;
  *d = std::move(moved);
  return count;
}

double BoundaryGap(const FaceDomain& domain, Surface& surface, const std::vector<double>& moved) {
  double gap = 0;
  for (size_t i = 0; i < domain.uv.size(); ++i) {
    const Vec2 q = domain.uv[i];
    // Along the normal: a pcurve that is not parametrised as its 3D curve puts S(uv) beside the
    // point, along the surface.
    const Vec3 off = domain.xyz[i] - surface.Point(q.x, q.y);
    const double away = std::fabs(Dot(off, surface.Normal(q.x, q.y)));
    gap = std::max(gap, moved.empty() ? away : away - moved[i]);
  }
  return gap;
}

double BoundaryGapPastSurface(const TopoDS_Face& face, const FaceDomain& domain,
                              const std::vector<double>& moved) {
  const BRepAdaptor_Surface surface(face, false);
  double gap = 0;
  for (size_t i = 0; i < domain.uv.size(); ++i) {
    const Vec2 q = domain.uv[i], in = IntoSurfaceRange(surface, q);
    if (in.x == q.x && in.y == q.y) continue;
    const gp_Pnt s = surface.Value(in.x, in.y);
    const double away = Dist(domain.xyz[i], Vec3{s.X(), s.Y(), s.Z()});
    gap = std::max(gap, moved.empty() ? away : away - moved[i]);
  }
  return gap;
}

double EdgeTrimGap(const TopoDS_Face& face, double above) {
  constexpr int kSamples = 32;       // points of the pcurve's image per edge
  constexpr int kCurvePoints = 128;  // the 3D curve's polyline they are measured to
  double gap = 0;
  for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
    const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
    if (BRep_Tool::Degenerated(edge) || !(BRep_Tool::Tolerance(edge) > above)) continue;
    try {
      const BRepAdaptor_Curve curve(edge), on_face(edge, face);
      const double a = curve.FirstParameter(), b = curve.LastParameter();
      std::vector<Vec3> line(kCurvePoints + 1);
      for (int k = 0; k <= kCurvePoints; ++k) {
        const gp_Pnt p = curve.Value(a + (b - a) * k / kCurvePoints);
        line[k] = {p.X(), p.Y(), p.Z()};
      }
      for (int k = 0; k <= kSamples; ++k) {
        const gp_Pnt p = on_face.Value(a + (b - a) * k / kSamples);
        const Vec3 x{p.X(), p.Y(), p.Z()};
        double d = HUGE_VAL;
        for (int j = 0; j < kCurvePoints; ++j)
          d = std::min(d, PointSegmentDistance(x, line[j], line[j + 1]));
        gap = std::max(gap, d);
      }
    } catch (const Standard_Failure&) {
      continue;  // an edge without a 3D curve or a pcurve: the domain reports it
    }
  }
  return gap;
}

double BoundaryChordHeight(const FaceDomain& domain, Surface& surface) {
  double height = 0;
  for (size_t k = 0; k < domain.segments.size(); ++k) {
    if (domain.segment_edge[k] == 0 || domain.segment_splittable[k]) continue;
    const int a = domain.segments[k][0], b = domain.segments[k][1];
    const Vec2 q = 0.5 * (domain.uv[a] + domain.uv[b]);
    const Vec3 off = surface.Point(q.x, q.y) - 0.5 * (domain.xyz[a] + domain.xyz[b]);
    height = std::max(height, std::fabs(Dot(off, surface.Normal(q.x, q.y))));
  }
  return height;
}

std::vector<DomainConflict> FindConflicts(const FaceDomain& d, const Context* context) {
  std::vector<DomainConflict> out;
  const int ns = static_cast<int>(d.segments.size());
  std::vector<Vec2> p(d.uv.size());
  for (size_t i = 0; i < p.size(); ++i) p[i] = {d.uv[i].x * d.scale_u, d.uv[i].y * d.scale_v};
  const double extent = std::max((d.umax - d.umin) * d.scale_u, (d.vmax - d.vmin) * d.scale_v);
  const double eps = 1e-12 * std::max(extent, 1e-300);
  // Loops that enclose no area.
  for (size_t k = 0; k < d.loop_begin.size(); ++k) {
    const int b = d.loop_begin[k];
    const int e = k + 1 < d.loop_begin.size() ? d.loop_begin[k + 1] : ns;
    double area = 0, perimeter = 0;
    for (int s = b; s < e; ++s) {
      Vec2 a = p[d.segments[s][0]], c = p[d.segments[s][1]];
      area += Cross(a, c);
      perimeter += std::hypot(c.x - a.x, c.y - a.y);
    }
    if (e - b < 3 || std::fabs(area) <= 1e-10 * perimeter * perimeter)
      for (int s = b; s < e; ++s) out.push_back({s, -1});
  }
  // Segment pairs, swept along u by their bounding boxes.
  std::vector<int> order(ns);
  for (int s = 0; s < ns; ++s) order[s] = s;
  auto lo = [&](int s) { return std::min(p[d.segments[s][0]].x, p[d.segments[s][1]].x); };
  auto hi = [&](int s) { return std::max(p[d.segments[s][0]].x, p[d.segments[s][1]].x); };
  std::sort(order.begin(), order.end(), [&](int a, int b) { return lo(a) < lo(b); });
  auto seg_dist = [](Vec2 q, Vec2 a, Vec2 b) { return std::sqrt(SegmentDistance2(q, a, b)); };
  std::vector<int> active;
  for (int k = 0; k < ns; ++k) {
    // Segments that share a u range (one edge along v) are all active at once: poll often.
    if ((k & 63) == 63 && context && context->ShouldStop()) break;
    const int s = order[k];
    const double x0 = lo(s);
    active.erase(
        std::remove_if(active.begin(), active.end(), [&](int t) { return hi(t) < x0 - eps; }),
        active.end());
    const int a0 = d.segments[s][0], a1 = d.segments[s][1];
    const Vec2 a = p[a0], b = p[a1];
    for (int t : active) {
      const int c0 = d.segments[t][0], c1 = d.segments[t][1];
      const Vec2 c = p[c0], e = p[c1];
      if (std::min(a.y, b.y) > std::max(c.y, e.y) + eps ||
          std::min(c.y, e.y) > std::max(a.y, b.y) + eps)
        continue;
      bool conflict;
      const int shared = (a0 == c0) + (a0 == c1) + (a1 == c0) + (a1 == c1);
      if (shared >= 2) {
        conflict = true;  // the same chord twice
      } else if (shared == 1) {
        // Neighbours conflict only when they fold back onto each other.
        const int common = (a0 == c0 || a0 == c1) ? a0 : a1;
        const Vec2 o = p[common];
        const Vec2 u = p[common == a0 ? a1 : a0] - o, v = p[(c0 == common) ? c1 : c0] - o;
        const double lu = std::hypot(u.x, u.y), lv = std::hypot(v.x, v.y);
        conflict = std::fabs(Cross(u, v)) <= 1e-12 * lu * lv && u.x * v.x + u.y * v.y > 0;
      } else {
        const double o1 = Orient(a, b, c), o2 = Orient(a, b, e);
        const double o3 = Orient(c, e, a), o4 = Orient(c, e, b);
        conflict = ((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) &&
                   ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0));
        conflict = conflict || std::min({seg_dist(a, c, e), seg_dist(b, c, e), seg_dist(c, a, b),
                                         seg_dist(e, a, b)}) <= eps;
      }
      if (conflict) out.push_back({std::min(s, t), std::max(s, t)});
    }
    active.push_back(s);
  }
  return out;
}

std::string DescribeConflict(const FaceDomain& d, const DomainConflict& c) {
  auto edge_of = [&](int s) {
    return d.segment_edge[s] > 0 ? EdgeName(d.segment_edge[s]) : std::string("a gap bridge");
  };
  const Vec2 q = d.uv[d.segments[c.a][0]];
  char at[80];
  std::snprintf(at, sizeof(at), " near (u,v) = (%.6g, %.6g)", q.x, q.y);
  if (c.b < 0) return "a boundary loop through " + edge_of(c.a) + " encloses no area in (u,v)" + at;
  return "boundary loops intersect in (u,v): segments of " + edge_of(c.a) + " and " + edge_of(c.b) +
         " cross or touch" + at;
}

int AddSingularLines(const std::vector<SingularLine>& lines, FaceDomain* d) {
  // Pieces per part at first: refinement splits them where the fans around the point need it.
  constexpr int kLinePieces = 4;
  const int loop_nodes = static_cast<int>(d->uv.size());
  int added = 0;
  for (const SingularLine& line : lines) {
    auto across = [&](Vec2 q) { return line.axis == 0 ? q.y : q.x; };
    auto along = [&](Vec2 q) { return line.axis == 0 ? q.x : q.y; };
    const double eps = 1e-9 * (line.axis == 0 ? d->vmax - d->vmin : d->umax - d->umin);
    bool crossed = false;
    for (const auto& s : d->segments) {
      const double a = across(d->uv[s[0]]) - line.at, b = across(d->uv[s[1]]) - line.at;
      crossed = crossed || (a > eps && b < -eps) || (a < -eps && b > eps);
    }
    if (crossed) continue;
    std::vector<int> on;
    for (int i = 0; i < loop_nodes; ++i)
      if (std::fabs(across(d->uv[i]) - line.at) <= eps) on.push_back(i);
    std::sort(on.begin(), on.end(),
              [&](int a, int b) { return along(d->uv[a]) < along(d->uv[b]); });
    const double extent = line.axis == 0 ? d->umax - d->umin : d->vmax - d->vmin;
    for (size_t k = 0; k + 1 < on.size(); ++k) {
      const int p = on[k], q = on[k + 1];
      const double a = along(d->uv[p]), b = along(d->uv[q]);
      if (!(b - a > 1e-9 * extent)) continue;
      Vec2 mid = 0.5 * (d->uv[p] + d->uv[q]);
      (line.axis == 0 ? mid.y : mid.x) = line.at;
      if (!InsideDomain(*d, mid)) continue;
      // Not along a boundary segment that lies on the line.
      bool on_boundary = false;
      for (const auto& s : d->segments)
        on_boundary = on_boundary || (std::fabs(across(d->uv[s[0]]) - line.at) <= eps &&
                                      std::fabs(across(d->uv[s[1]]) - line.at) <= eps &&
                                      std::min(along(d->uv[s[0]]), along(d->uv[s[1]])) < b &&
                                      std::max(along(d->uv[s[0]]), along(d->uv[s[1]])) > a);
      if (on_boundary) continue;
      int prev = p;
      for (int j = 1; j < kLinePieces; ++j) {
        Vec2 x = d->uv[p];
        (line.axis == 0 ? x.x : x.y) = a + (b - a) * j / kLinePieces;
        (line.axis == 0 ? x.y : x.x) = line.at;
        d->uv.push_back(x);
        d->xyz.push_back(d->xyz[p]);
        d->ref.push_back(NodeRef{});
        const int n = static_cast<int>(d->uv.size()) - 1;
        d->line_segments.push_back({prev, n});
        prev = n;
      }
      d->line_segments.push_back({prev, q});
      ++added;
    }
  }
  return added;
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

namespace {

// How far the surface normal turns along u (along_u) or along v: for each of five probe lines
// across the domain, the turn in each of `steps` even steps along it (line-major).
std::vector<double> TurnSteps(const FaceDomain& d, Surface& s, bool along_u, int steps) {
  const double du = d.umax - d.umin, dv = d.vmax - d.vmin;
  std::vector<double> turn;
  turn.reserve(5 * steps);
  for (int j = 0; j < 5; ++j) {
    Vec3 prev;
    for (int i = 0; i <= steps; ++i) {
      double a = static_cast<double>(i) / steps, b = (j + 0.5) / 5;
      double u = d.umin + du * (along_u ? a : b), v = d.vmin + dv * (along_u ? b : a);
      Vec3 n = s.Normal(u, v);
      if (i > 0) turn.push_back(std::acos(std::clamp(Dot(n, prev), -1.0, 1.0)));
      prev = n;
    }
  }
  return turn;
}

// The largest total turn over the probe lines of TurnSteps.
double WorstTurn(const std::vector<double>& turn, int steps) {
  double worst = 0;
  for (int j = 0; j < 5; ++j) {
    double total = 0;
    for (int i = 0; i < steps; ++i) total += turn[j * steps + i];
    worst = std::max(worst, total);
  }
  return worst;
}

// Seed lines along one parameter: where they cross it, and the width of each one's cell (scaled
// as for 2D tests).
struct SeedLines {
  std::vector<double> at, cell;
};

// Where `count` seed lines go along one parameter (range [lo, lo + range], scale as the domain's):
// the middles of even cells, unless the normal turns much faster in part of the range than an
// even cell can take (a blunt nose at the end of a long hull: all of its turn in the first cell,
// and a fan from the pole across it; a tight blend along one side of a B-spline patch). Then the
// lines, as many as the finely probed turn needs, split it into even parts.
SeedLines PlaceSeedLines(const FaceDomain& d, Surface& s, bool along_u, int count,
                         const std::vector<double>& coarse, int coarse_steps, double step) {
  const double lo = along_u ? d.umin : d.vmin, range = along_u ? d.umax - d.umin : d.vmax - d.vmin;
  const double scale = along_u ? d.scale_u : d.scale_v;
  SeedLines lines;
  for (int i = 0; i < count; ++i) {
    lines.at.push_back(lo + range * (i + 0.5) / count);
    lines.cell.push_back(range * scale / count);
  }
  double densest = 0;  // the largest turn per whole range
  for (int i = 0; i < coarse_steps; ++i)
    for (int j = 0; j < 5; ++j) densest = std::max(densest, coarse[j * coarse_steps + i]);
  densest *= coarse_steps;
  if (!(densest / count > 1.5 * step)) return lines;
  constexpr int kFine = 8;
  const int steps = kFine * coarse_steps;
  std::vector<double> turn = TurnSteps(d, s, along_u, steps);
  std::vector<double> cumulative(steps + 1, 0.0);
  for (int i = 0; i < steps; ++i) {
    double most = 0;
    for (int j = 0; j < 5; ++j) most = std::max(most, turn[j * steps + i]);
    cumulative[i + 1] = cumulative[i] + most;
  }
  const double total = cumulative[steps];
  if (!(total > 0)) return lines;
  const int n = std::clamp(static_cast<int>(std::ceil(total / step - 1e-9)), count, 12);
  std::vector<double> at(n);
  int k = 0;
  for (int i = 0; i < n; ++i) {
    double target = total * (i + 0.5) / n;
    while (k + 1 < steps && cumulative[k + 1] < target) ++k;
    double part = cumulative[k + 1] - cumulative[k];
    at[i] = (k + (part > 0 ? (target - cumulative[k]) / part : 0.5)) / steps;
  }
  lines.at.assign(n, 0);
  lines.cell.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    double from = i > 0 ? 0.5 * (at[i - 1] + at[i]) : 0.0;
    double to = i + 1 < n ? 0.5 * (at[i] + at[i + 1]) : 1.0;
    lines.at[i] = lo + range * at[i];
    lines.cell[i] = range * scale * (to - from);
  }
  return lines;
}

}  // namespace

std::vector<Vec2> SeedPoints(const FaceDomain& d, Surface& s) {
  const int kProbe = 9;
  const double kStep = M_PI / 6;
  std::vector<double> turn_u = TurnSteps(d, s, true, kProbe - 1);
  std::vector<double> turn_v = TurnSteps(d, s, false, kProbe - 1);
  int nu =
      std::clamp(static_cast<int>(std::ceil(WorstTurn(turn_u, kProbe - 1) / kStep - 1e-9)), 1, 12);
  int nv =
      std::clamp(static_cast<int>(std::ceil(WorstTurn(turn_v, kProbe - 1) / kStep - 1e-9)), 1, 12);
  std::vector<Vec2> seeds;
  if (nu * nv <= 1) return seeds;
  SeedLines lines_u = PlaceSeedLines(d, s, true, nu, turn_u, kProbe - 1, kStep);
  SeedLines lines_v = PlaceSeedLines(d, s, false, nv, turn_v, kProbe - 1, kStep);
  for (size_t j = 0; j < lines_v.at.size(); ++j) {
    for (size_t i = 0; i < lines_u.at.size(); ++i) {
      Vec2 p{lines_u.at[i], lines_v.at[j]};
      if (!InsideDomain(d, p)) continue;
      // Clear of the boundary by 0.35 of its cell's smaller side.
      double clearance = 0.35 * std::min(lines_u.cell[i], lines_v.cell[j]);
      double clearance2 = clearance * clearance;
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
