#include "boundary/pcurves.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Geom_Surface.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <algorithm>
#include <functional>
#include <string>

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

// The wire's FORWARD and REVERSED edges as BRepTools_WireExplorer walks them on `face`
// (FORWARD), which takes the face's (u,v) bounds on a cone, B-spline or Bezier surface
// (`bounds`). The status fails when the explorer cannot reach them all.
Status WireEdges(const TopoDS_Face& face, const TopoDS_Wire& wire,
                 const std::function<UvBounds()>& bounds, std::vector<TopoDS_Edge>* edges) {
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
    return Status(StatusCode::kInternal,
                  "a wire's edges do not connect end to end: the wire explorer reaches " +
                      std::to_string(edges->size()) + " of its " + std::to_string(all) + " edges");
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
  std::vector<TopoDS_Edge> edges;
  for (TopExp_Explorer wexp(face, TopAbs_WIRE); wexp.More(); wexp.Next()) {
    FaceWire& wire = loops.wires.emplace_back();
    wire.reached = WireEdges(face, TopoDS::Wire(wexp.Current()), bounds, &edges);
    for (const TopoDS_Edge& e : edges) {
      WireEdge& w = wire.edges.emplace_back();
      w.eid = id(e);
      w.reversed = e.Orientation() == TopAbs_REVERSED;
      if (w.eid != 0) w.pcurve = pcurve(w.eid, e).curve;
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
