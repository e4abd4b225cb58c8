#include "pcurves.h"

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

#include "model.h"
#include "parallel.h"

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

// The loops of `face` (FORWARD, face id `face_id`), its edges' pcurves from `pcurve`.
FaceLoops LoopsOf(const Model& model, const TopoDS_Face& face,
                  const std::function<UvBounds()>& bounds,
                  const std::function<Pcurve(const TopoDS_Edge&)>& pcurve) {
  FaceLoops loops;
  const Handle(Geom_Surface)& geom = BRep_Tool::Surface(face);
  loops.period_u = !geom.IsNull() && geom->IsUPeriodic() ? geom->UPeriod() : 0.0;
  loops.period_v = !geom.IsNull() && geom->IsVPeriodic() ? geom->VPeriod() : 0.0;
  std::vector<TopoDS_Edge> edges;
  for (TopExp_Explorer wexp(face, TopAbs_WIRE); wexp.More(); wexp.Next()) {
    FaceWire& wire = loops.wires.emplace_back();
    wire.reached = WireEdges(face, TopoDS::Wire(wexp.Current()), bounds, &edges);
    for (const TopoDS_Edge& e : edges) {
      WireEdge& w = wire.edges.emplace_back();
      w.eid = model.edges.FindIndex(e);
      w.reversed = e.Orientation() == TopAbs_REVERSED;
      if (w.eid != 0) w.pcurve = pcurve(e).curve;
    }
  }
  return loops;
}

}  // namespace

FacePcurves FacePcurves::Build(const Model& model, const std::vector<int>& faces, int threads,
                               Context* context) {
  FacePcurves table;
  table.faces_.resize(model.face_count());
  const ParallelRunner runner(threads);
  runner.For(
      0, static_cast<int>(faces.size()),
      [&](int i) {
        if (context && context->ShouldStop()) return;
        Face& out = table.faces_[faces[i] - 1];
        try {
          const TopoDS_Face face = TopoDS::Face(model.face(faces[i]).Oriented(TopAbs_FORWARD));
          out.bounds = BoundsFromOcct(face);
          for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
            const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
            bool known = false;
            for (const Entry& e : out.entries)
              known = known ||
                      (e.edge.IsSame(edge) && SecondSide(face, e.edge) == SecondSide(face, edge));
            if (!known) out.entries.push_back({edge, FromOcct(face, edge)});
          }
          out.loops = LoopsOf(
              model, face, [&] { return out.bounds; },
              [&](const TopoDS_Edge& edge) {
                const bool second = SecondSide(face, edge);
                for (const Entry& e : out.entries)
                  if (e.edge.IsSame(edge) && SecondSide(face, e.edge) == second) return e.pcurve;
                return FromOcct(face, edge);
              });
          out.built = true;
        } catch (const Standard_Failure&) {
          out = Face();  // looked up from OCCT at every call, which fails the same way
        }
      },
      Partition::kOnePerTask);
  return table;
}

const FacePcurves::Face* FacePcurves::Built(int face_id) const {
  if (face_id < 1 || face_id > static_cast<int>(faces_.size())) return nullptr;
  const Face& f = faces_[face_id - 1];
  return f.built ? &f : nullptr;
}

Pcurve FacePcurves::Find(const Model& model, int face_id, const TopoDS_Face& face,
                         const TopoDS_Edge& edge) const {
  const Face* f = Built(face_id);
  if (f && face.IsSame(model.face(face_id))) {
    const bool second = SecondSide(face, edge);
    for (const Entry& e : f->entries)
      if (e.edge.IsSame(edge) && (e.edge.Orientation() == TopAbs_REVERSED) == second)
        return e.pcurve;
  }
  return FromOcct(face, edge);
}

UvBounds FacePcurves::Bounds(const Model& model, int face_id) const {
  if (const Face* f = Built(face_id)) return f->bounds;
  return BoundsFromOcct(model.face(face_id));
}

const FaceLoops& FacePcurves::Loops(const Model& model, int face_id, FaceLoops* scratch) const {
  if (const Face* f = Built(face_id)) return f->loops;
  const TopoDS_Face face = TopoDS::Face(model.face(face_id).Oriented(TopAbs_FORWARD));
  *scratch = LoopsOf(
      model, face, [&] { return BoundsFromOcct(face); },
      [&](const TopoDS_Edge& edge) { return FromOcct(face, edge); });
  return *scratch;
}

}  // namespace rdmesh
