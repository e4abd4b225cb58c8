#include "boundary/pcurves.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <Geom_Surface.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <algorithm>
#include <cmath>
#include <functional>
#include <gp_Pnt2d.hxx>
#include <gp_Vec2d.hxx>
#include <string>
#include <tuple>

#include "core/parallel.h"
#include "model/model.h"

namespace rdmesh {

namespace {

// Which of a seam's two pcurves BRep_Tool::CurveOnSurface(edge, face) returns: the second when
// the edge, taken relative to the face (reversed with a REVERSED face), is REVERSED.
bool SecondSide(const TopoDS_Face& face, const TopoDS_Edge& edge) {
  const TopAbs_Orientation o = edge.Orientation();
  return face.Orientation() == TopAbs_REVERSED ? o == TopAbs_FORWARD : o == TopAbs_REVERSED;
}

Pcurve FromOcct(const TopoDS_Face& face, const TopoDS_Edge& edge) {
  Pcurve p;
  p.curve = BRep_Tool::CurveOnSurface(edge, face, p.first, p.last);
  return p;
}

UvBounds BoundsFromOcct(const TopoDS_Face& face) {
  UvBounds b;
  BRepTools::UVBounds(face, b.umin, b.umax, b.vmin, b.vmax);
  return b;
}

// The wire's edges in the order BRepTools_WireExplorer walks them, when the wire already lists
// them so: each FORWARD or REVERSED with both its vertices, each beginning where the one before
// ends (the first where the last ends), and no vertex beginning two of them. The explorer then
// takes them in this order from the first; it builds maps of the wire's vertices to get there.
bool EdgesInOrder(const TopoDS_Wire& wire, std::vector<TopoDS_Edge>* edges) {
  edges->clear();
  std::vector<const void*> starts;
  TopoDS_Vertex first, end;
  for (TopoDS_Iterator it(wire); it.More(); it.Next()) {
    const TopoDS_Edge& e = TopoDS::Edge(it.Value());
    if (e.Orientation() != TopAbs_FORWARD && e.Orientation() != TopAbs_REVERSED) return false;
    TopoDS_Vertex v0, v1;
    TopExp::Vertices(e, v0, v1, Standard_True);
    if (v0.IsNull() || v1.IsNull()) return false;
    if (edges->empty())
      first = v0;
    else if (!v0.IsSame(end))
      return false;
    end = v1;
    starts.push_back(v0.TShape().get());
    edges->push_back(e);
  }
  if (edges->empty() || !end.IsSame(first)) return false;
  std::sort(starts.begin(), starts.end());
  return std::adjacent_find(starts.begin(), starts.end()) == starts.end();
}

// One FORWARD or REVERSED edge of a wire with its ends: its vertices in walking order, and where
// its pcurve on the face begins and ends.
struct WireLink {
  TopoDS_Edge edge;
  TopoDS_Vertex from, to;
  gp_Pnt2d start, end;
};

// How well `next` continues a walk that has reached `end` (the (u,v) of `last`'s end, moved by
// whole periods as the walk went). Lower is better, compared in order: a vertex of its own
// (met within the two vertices' tolerances), the same edge back (a seam's other side), (u,v)
// ends apart by more than `slack` after the best shift by whole periods, the periods shifted,
// and the distance.
struct LinkRank {
  int own_vertex = 0, back = 0, apart = 0, periods = 0;
  double distance = 0;
  bool operator<(const LinkRank& o) const {
    return std::tie(own_vertex, back, apart, periods, distance) <
           std::tie(o.own_vertex, o.back, o.apart, o.periods, o.distance);
  }
};

// The wire's edges chained by their ends, for a wire BRepTools_WireExplorer cannot walk. The
// explorer follows a vertex to an edge that begins there only where the two pcurves meet within
// twice the (u,v) resolution of the vertex tolerance, and without whole periods: it stops where a
// surface of revolution's pcurves meet a period apart, or where a torus's seam meets its circle
// just outside that resolution. Here each edge is followed by the edge that begins at its end
// vertex (or one within both tolerances) whose pcurve begins nearest, after a shift by whole
// periods (`shift` per edge: the shift JoinWalks will make), not the same edge back unless
// nothing else begins there. A chain that comes back to its first edge's start closes a loop;
// the wire's other edges make loops of their own. Fails for a missing pcurve, or an edge that
// ends where no other begins (its loop is left open, for JoinWalks to name the edges).
Status ChainByEnds(const TopoDS_Face& face, const TopoDS_Wire& wire, double period_u,
                   double period_v, std::vector<std::vector<TopoDS_Edge>>* loops) {
  loops->clear();
  std::vector<WireLink> links;
  double umin = HUGE_VAL, umax = -HUGE_VAL, vmin = HUGE_VAL, vmax = -HUGE_VAL;
  for (TopoDS_Iterator it(wire); it.More(); it.Next()) {
    const TopoDS_Edge& e = TopoDS::Edge(it.Value());
    if (e.Orientation() != TopAbs_FORWARD && e.Orientation() != TopAbs_REVERSED) continue;
    WireLink& link = links.emplace_back();
    link.edge = e;
    TopExp::Vertices(e, link.from, link.to, Standard_True);
    double first = 0, last = 0;
    const Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(e, face, first, last);
    if (pcurve.IsNull() || link.from.IsNull() || link.to.IsNull())
      return Status(StatusCode::kInternal,
                    "a wire's edges do not connect end to end: an edge has no pcurve or vertex");
    const bool reversed = e.Orientation() == TopAbs_REVERSED;
    link.start = pcurve->Value(reversed ? last : first);
    link.end = pcurve->Value(reversed ? first : last);
    for (const gp_Pnt2d& p : {link.start, link.end}) {
      umin = std::min(umin, p.X()), umax = std::max(umax, p.X());
      vmin = std::min(vmin, p.Y()), vmax = std::max(vmax, p.Y());
    }
  }
  if (links.empty()) return Status::Ok();
  const double slack = 1e-3 * std::max(umax - umin, vmax - vmin) + 1e-9;
  auto near = [](const TopoDS_Vertex& a, const TopoDS_Vertex& b) {
    return a.IsSame(b) || BRep_Tool::Pnt(a).Distance(BRep_Tool::Pnt(b)) <=
                              BRep_Tool::Tolerance(a) + BRep_Tool::Tolerance(b);
  };
  // The whole periods that bring `p` nearest `to` along one axis.
  auto periods = [](double to, double p, double period) {
    return period > 0 ? std::round((to - p) / period) : 0.0;
  };
  std::vector<bool> used(links.size(), false);
  Status status;
  for (size_t first = 0; first < links.size(); ++first) {
    if (used[first]) continue;
    std::vector<TopoDS_Edge>& loop = loops->emplace_back();
    used[first] = true;
    loop.push_back(links[first].edge);
    size_t last = first;
    gp_Vec2d shift(0, 0);  // of `last`'s pcurve, from the walk's shifts
    while (true) {
      const gp_Pnt2d end = links[last].end.Translated(shift);
      if (links[last].to.IsSame(links[first].from) && end.Distance(links[first].start) <= slack)
        break;  // closed, without a shift (as JoinWalks closes a loop)
      int best = -1;
      LinkRank best_rank;
      gp_Vec2d best_shift;
      for (size_t j = 0; j < links.size(); ++j) {
        if (used[j]) continue;
        const bool same = links[j].from.IsSame(links[last].to);
        if (!same && !near(links[j].from, links[last].to)) continue;
        const double ku = periods(end.X(), links[j].start.X(), period_u);
        const double kv = periods(end.Y(), links[j].start.Y(), period_v);
        const gp_Vec2d move(ku * period_u, kv * period_v);
        LinkRank rank;
        rank.own_vertex = !same;
        rank.back = links[j].edge.IsSame(links[last].edge);
        rank.distance = end.Distance(links[j].start.Translated(move));
        rank.apart = rank.distance > slack;
        rank.periods = static_cast<int>(std::fabs(ku) + std::fabs(kv));
        if (best < 0 || rank < best_rank)
          best = static_cast<int>(j), best_rank = rank, best_shift = move;
      }
      if (best < 0) {
        if (used == std::vector<bool>(links.size(), true)) break;
        status = Status(StatusCode::kInternal,
                        "a wire's edges do not connect end to end: an edge ends where no other "
                        "edge of the wire begins");
        break;
      }
      used[best] = true;
      loop.push_back(links[best].edge);
      last = static_cast<size_t>(best);
      shift = best_shift;
    }
  }
  return status;
}

// The wire's FORWARD and REVERSED edges as BRepTools_WireExplorer walks them on `face`
// (FORWARD), which takes the face's (u,v) bounds on a cone, B-spline or Bezier surface
// (`bounds`): one loop. Where the explorer cannot reach them all, the edges chained by their
// ends instead (ChainByEnds: one loop or more), and the status fails when that cannot chain them
// either.
Status WireEdges(const TopoDS_Face& face, const TopoDS_Wire& wire,
                 const std::function<UvBounds()>& bounds, double period_u, double period_v,
                 std::vector<std::vector<TopoDS_Edge>>* loops) {
  loops->assign(1, {});
  std::vector<TopoDS_Edge>* edges = &loops->front();
  if (EdgesInOrder(wire, edges)) return Status::Ok();
  edges->clear();
  UvBounds b;
  const GeomAbs_SurfaceType type = BRepAdaptor_Surface(face, Standard_False).GetType();
  if (type == GeomAbs_Cone || type == GeomAbs_BSplineSurface || type == GeomAbs_BezierSurface)
    b = bounds();
  BRepTools_WireExplorer ex;
  ex.Init(wire, face, b.umin, b.umax, b.vmin, b.vmax);
  for (; ex.More(); ex.Next()) {
    const TopoDS_Edge& e = ex.Current();
    if (e.Orientation() == TopAbs_FORWARD || e.Orientation() == TopAbs_REVERSED)
      edges->push_back(e);
  }
  // The explorer follows the edges from vertex to vertex and silently drops those it cannot
  // reach; a loop without them would leave a hole in the mesh.
  int all = 0;
  for (TopExp_Explorer it(wire, TopAbs_EDGE); it.More(); it.Next())
    all += it.Current().Orientation() == TopAbs_FORWARD ||
           it.Current().Orientation() == TopAbs_REVERSED;
  if (static_cast<int>(edges->size()) < all)
    return ChainByEnds(face, wire, period_u, period_v, loops);
  return Status::Ok();
}

// The loops of `face` (FORWARD), its edges' ids from `id` and pcurves from `pcurve`.
FaceLoops LoopsOf(const TopoDS_Face& face, const std::function<UvBounds()>& bounds,
                  const std::function<int(const TopoDS_Edge&)>& id,
                  const std::function<Pcurve(int, const TopoDS_Edge&)>& pcurve) {
  FaceLoops loops;
  TopLoc_Location location;  // periods do not depend on where the surface is placed
  const Handle(Geom_Surface)& geom = BRep_Tool::Surface(face, location);
  loops.period_u = !geom.IsNull() && geom->IsUPeriodic() ? geom->UPeriod() : 0.0;
  loops.period_v = !geom.IsNull() && geom->IsVPeriodic() ? geom->VPeriod() : 0.0;
  std::vector<std::vector<TopoDS_Edge>> walked;
  for (TopExp_Explorer wexp(face, TopAbs_WIRE); wexp.More(); wexp.Next()) {
    const Status reached = WireEdges(face, TopoDS::Wire(wexp.Current()), bounds, loops.period_u,
                                     loops.period_v, &walked);
    for (const std::vector<TopoDS_Edge>& edges : walked) {
      FaceWire& wire = loops.wires.emplace_back();
      wire.reached = reached;
      for (const TopoDS_Edge& e : edges) {
        WireEdge& w = wire.edges.emplace_back();
        w.eid = id(e);
        w.reversed = e.Orientation() == TopAbs_REVERSED;
        if (w.eid != 0) w.pcurve = pcurve(w.eid, e).curve;
      }
    }
  }
  return loops;
}

// A face's own frame: the face without its placement when that is a rigid motion, so that
// OCCT's lookups, which work in the surface's frame anyway, need not walk the placement's chain
// of locations (shared by every face of an instance, and by both threads). The same answers:
// an edge's pcurve is found, or its curve projected, relative to the surface's placement.
TopoDS_Face InOwnFrame(const TopoDS_Face& face) {
  if (face.Location().IsIdentity() || !RigidlyPlaced(face)) return face;
  return TopoDS::Face(face.Located(TopLoc_Location()));
}

}  // namespace

void FacePcurves::BuildFace(const Model& model, int f, Face* out) {
  try {
    const TopoDS_Face face = InOwnFrame(TopoDS::Face(model.face(f).Oriented(TopAbs_FORWARD)));
    out->bounds = BoundsFromOcct(face);
    // The face's distinct edges come in the order of Model::face_edges.
    const std::vector<int>& ids = model.face_edges[f - 1];
    std::vector<TopoDS_Edge> distinct;
    auto id = [&](const TopoDS_Edge& edge) {
      for (size_t k = 0; k < distinct.size(); ++k)
        if (distinct[k].IsSame(edge)) return ids[k];
      return 0;
    };
    for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
      const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
      int eid = id(edge);
      if (eid == 0) {
        if (distinct.size() >= ids.size()) throw Standard_Failure("edges differ");
        distinct.push_back(edge);
        eid = ids[distinct.size() - 1];
      }
      // Only a seam's pcurve depends on the edge's orientation.
      const bool second = SecondSide(face, edge);
      const bool either = !BRep_Tool::IsClosed(edge, face);
      if (either) out->rim.push_back(eid);
      if (!out->Lookup(eid, second))
        out->entries.push_back({eid, second, either, FromOcct(face, edge)});
    }
    if (distinct.size() != ids.size()) throw Standard_Failure("edges differ");
    out->loops = LoopsOf(
        face, [&] { return out->bounds; }, id,
        [&](int eid, const TopoDS_Edge& edge) {
          const Pcurve* known = out->Lookup(eid, SecondSide(face, edge));
          return known ? *known : FromOcct(face, edge);
        });
    out->built = true;
  } catch (const Standard_Failure&) {
    *out = Face();  // looked up from OCCT at every call, which fails the same way
  }
}

FacePcurves FacePcurves::Build(const Model& model, const std::vector<int>& faces, int threads,
                               Context* context) {
  FacePcurves table;
  const int nf = model.face_count();
  table.faces_.resize(nf);
  // An instanced copy, rigidly placed like its representative, is the same face in its own
  // frame: it takes the representative's answers, under its own edge ids.
  std::vector<bool> asked(nf, false);
  for (int f : faces) asked[f - 1] = true;
  std::vector<int> sources, copies;
  for (int f : faces) {
    const int rep = model.face_representative[f - 1];
    const bool copy = rep != f && asked[rep - 1] && RigidlyPlaced(model.face(f)) &&
                      RigidlyPlaced(model.face(rep)) &&
                      model.face_edges[f - 1].size() == model.face_edges[rep - 1].size();
    (copy ? copies : sources).push_back(f);
  }
  const ParallelRunner runner(threads);
  runner.For(
      0, static_cast<int>(sources.size()),
      [&](int i) {
        if (context && context->ShouldStop()) return;
        BuildFace(model, sources[i], &table.faces_[sources[i] - 1]);
      },
      Partition::kOnePerTask);
  runner.For(0, static_cast<int>(copies.size()), [&](int i) {
    if (context && context->ShouldStop()) return;
    const int f = copies[i], rep = model.face_representative[f - 1];
    Face& out = table.faces_[f - 1];
    out = table.faces_[rep - 1];
    if (!out.built) return;  // left to OCCT, as the representative is
    const std::vector<int>&from = model.face_edges[rep - 1], &to = model.face_edges[f - 1];
    auto id = [&](int eid) {
      for (size_t k = 0; k < from.size(); ++k)
        if (from[k] == eid) return to[k];
      return 0;
    };
    for (Entry& e : out.entries) e.eid = id(e.eid);
    for (int& e : out.rim) e = id(e);
    for (FaceWire& wire : out.loops.wires)
      for (WireEdge& e : wire.edges) e.eid = id(e.eid);
  });
  return table;
}

void FacePcurves::Release(int threads) {
  const ParallelRunner runner(threads);
  runner.For(0, static_cast<int>(faces_.size()), [&](int i) { faces_[i] = Face(); });
  faces_.clear();
}

bool RigidlyPlaced(const TopoDS_Shape& shape) {
  const TopLoc_Location& location = shape.Location();
  return location.IsIdentity() || location.Transformation().ScaleFactor() == 1.0;
}

std::pair<TopoDS_Face, TopoDS_Edge> InOwnFrame(const TopoDS_Face& face, const TopoDS_Edge& edge) {
  if (face.Location().IsIdentity() || !RigidlyPlaced(face) ||
      !edge.Location().IsEqual(face.Location()))
    return {face, edge};
  return {TopoDS::Face(face.Located(TopLoc_Location())),
          TopoDS::Edge(edge.Located(TopLoc_Location()))};
}

const FacePcurves::Face* FacePcurves::Built(int face_id) const {
  if (face_id < 1 || face_id > static_cast<int>(faces_.size())) return nullptr;
  const Face& f = faces_[face_id - 1];
  return f.built ? &f : nullptr;
}

const Pcurve* FacePcurves::Face::Lookup(int eid, bool second) const {
  for (const Entry& e : entries)
    if (e.eid == eid && (e.either || e.second == second)) return &e.pcurve;
  return nullptr;
}

Pcurve FacePcurves::Find(int face_id, const TopoDS_Face& face, int edge_id,
                         const TopoDS_Edge& edge) const {
  if (const Face* f = Built(face_id))
    if (const Pcurve* known = f->Lookup(edge_id, SecondSide(face, edge))) return *known;
  return FromOcct(face, edge);
}

bool FacePcurves::IsSeam(int face_id, const TopoDS_Face& face, int edge_id,
                         const TopoDS_Edge& edge) const {
  if (const Face* f = Built(face_id))
    for (const Entry& e : f->entries)
      if (e.eid == edge_id) return !e.either;
  return BRep_Tool::IsClosed(edge, face);
}

const std::vector<int>* FacePcurves::Rim(int face_id) const {
  const Face* f = Built(face_id);
  return f ? &f->rim : nullptr;
}

UvBounds FacePcurves::Bounds(const Model& model, int face_id) const {
  if (const Face* f = Built(face_id)) return f->bounds;
  return BoundsFromOcct(model.face(face_id));
}

const FaceLoops& FacePcurves::Loops(const Model& model, int face_id, FaceLoops* scratch) const {
  if (const Face* f = Built(face_id)) return f->loops;
  const TopoDS_Face face = TopoDS::Face(model.face(face_id).Oriented(TopAbs_FORWARD));
  *scratch = LoopsOf(
      face, [&] { return BoundsFromOcct(face); },
      [&](const TopoDS_Edge& edge) { return model.edges.FindIndex(edge); },
      [&](int, const TopoDS_Edge& edge) { return FromOcct(face, edge); });
  return *scratch;
}

}  // namespace rdmesh
