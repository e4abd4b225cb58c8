// OCC_CATCH_SIGNALS below must turn faults inside OCCT's modelling classes into exceptions, in
// TBB's worker threads too, when the caller has OCCT's fault handlers installed (model_readers'
// ScopedOcctFaultHandlers); it has to be defined before any OCCT header.
#define OCC_CONVERT_SIGNALS 1

#include "model/step/heal_items.h"

#include <BRepLib.hxx>
#include <BRep_Builder.hxx>
#include <BRep_CurveRepresentation.hxx>
#include <BRep_GCurve.hxx>
#include <BRep_ListIteratorOfListOfCurveRepresentation.hxx>
#include <BRep_TEdge.hxx>
#include <BRep_TVertex.hxx>
#include <BRep_Tool.hxx>
#include <ShapeBuild_ReShape.hxx>
#include <ShapeExtend.hxx>
#include <ShapeFix.hxx>
#include <ShapeFix_Edge.hxx>
#include <ShapeFix_Face.hxx>
#include <ShapeFix_Shape.hxx>
#include <ShapeFix_Shell.hxx>
#include <ShapeFix_Solid.hxx>
#include <ShapeFix_Wire.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_DataMapOfShapeReal.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_MapOfShape.hxx>
#include <TopTools_ShapeMapHasher.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Iterator.hxx>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <unordered_set>
#include <utility>
#include <vector>

#include "core/parallel.h"
#include "geometry/surface_type.h"
#include "model/step/finish.h"

namespace rdmesh::step {

namespace {

// ShapeBuild_ReShape whose Apply returns a shape none of whose sub-shapes (down to `until`) is
// recorded as it is, with the status OK, as the base class does: the base copies every sub-shape
// on its way down (edges with all their curve representations) only to find nothing changed,
// which was most of ShapeFix_Face's time (ShapeFix_Wire applies the context to its wire and
// edges dozens of times per face). Recorded shapes go the base class's way. In the mode that
// considers locations (ShapeFix_Shape's) IsRecorded and the base's Value both look a shape up
// without its location, and Value gives an unrecorded shape back with it: the same shortcut.
class QuickReShape : public ShapeBuild_ReShape {
 public:
  TopoDS_Shape Apply(const TopoDS_Shape& shape,
                     const TopAbs_ShapeEnum until = TopAbs_SHAPE) override {
    if (shape.IsNull() || RecordedWithin(shape, until))
      return ShapeBuild_ReShape::Apply(shape, until);
    myStatus = ShapeExtend::EncodeStatus(ShapeExtend_OK);
    return shape;
  }

 private:
  // Whether `shape` or a sub-shape the base class's Apply would visit is recorded.
  bool RecordedWithin(const TopoDS_Shape& shape, TopAbs_ShapeEnum until) const {
    if (IsRecorded(shape)) return true;
    const TopAbs_ShapeEnum type = shape.ShapeType();
    if (type >= until || type == TopAbs_VERTEX || type == TopAbs_SHAPE) return false;
    for (TopoDS_Iterator it(shape, Standard_False); it.More(); it.Next())
      if (RecordedWithin(it.Value(), until)) return true;
    return false;
  }
};

// ShapeFix_Shape with the context its Init would make (one that considers locations), but a
// QuickReShape: applied to a whole item, OCCT's copies all of it to give the same shape back (a
// sixth of the shell stage on a 1,684-face part), and its wire fixing applies it to every edge.
Handle(ShapeFix_Shape) NewShapeFix() {
  Handle(ShapeFix_Shape) fix = new ShapeFix_Shape;
  Handle(ShapeBuild_ReShape) context = new QuickReShape;
  context->ModeConsiderLocation() = Standard_True;
  fix->SetContext(context);
  return fix;
}

// RecModif of ShapeProcess_ShapeContext: what each sub-shape (down to edges) became.
void RecordModifications(const TopoDS_Shape& shape, const Handle(ShapeBuild_ReShape) & reshape,
                         TopTools_DataMapOfShapeShape* map) {
  if (shape.IsNull()) return;
  TopoDS_Shape located = shape.Located(TopLoc_Location());
  TopoDS_Shape r = located;
  if (map->IsBound(r)) r = map->Find(r);
  if (!r.IsNull()) {
    TopoDS_Shape result;
    if (reshape->Status(r, result, Standard_True) && result != r) map->Bind(located, result);
  }
  if (shape.ShapeType() >= TopAbs_EDGE) return;
  for (TopoDS_Iterator it(shape, Standard_False); it.More(); it.Next())
    RecordModifications(it.Value(), reshape, map);
}

}  // namespace

void HealItem(BrepItem* item) {
  item->healed = item->raw;
  item->modified.Clear();
  try {
    OCC_CATCH_SIGNALS
    Handle(ShapeFix_Shape) fix = NewShapeFix();
    fix->Init(item->raw);
    fix->SetPrecision(item->units.precision);
    fix->SetMaxTolerance(item->units.max_tolerance);
    fix->FixFaceTool()->FixWireTool()->FixSameParameterMode() = Standard_False;
    fix->FixSolidTool()->CreateOpenSolidMode() = Standard_False;
    fix->Perform();
    TopoDS_Shape result = fix->Shape();
    if (!result.IsNull() && result != item->raw) {
      item->healed = result;
      RecordModifications(item->raw, fix->Context(), &item->modified);
    }
  } catch (const Standard_Failure&) {
    item->healed = item->raw;  // ProcessShape keeps the shape it was given
    item->modified.Clear();
  }
}

TopoDS_Shape HealedShape(const BrepItem& item, const TopoDS_Shape& raw) {
  const TopoDS_Shape* found = item.modified.Seek(raw);
  return found != nullptr ? *found : raw;
}

namespace {

// A pcurve StorePlanePcurves stored, held (so that no other curve takes its address) with its
// points at the ends of its range, to tell whether the fixing changed it in place.
struct StoredPcurve {
  Handle(Geom2d_Curve) curve;
  double first = 0, last = 0;
  gp_Pnt2d at_first, at_last;
  Handle(Geom_Curve) curve3d;  // the edge's 3D curve it was projected from, and its range
  TopLoc_Location location3d;
  double first3d = 0, last3d = 0;
};
// The pcurves StorePlanePcurves stored, by address.
using StoredPcurves = std::map<const Geom2d_Curve*, StoredPcurve>;

// A parameter range of an edge.
struct EdgeRange {
  double first = 0, last = 0;
  bool operator==(const EdgeRange& other) const {
    return first == other.first && last == other.last;
  }
};
// Shared raw edges (by TShape) -> the range a face's fixing cut them to.
using EdgeRanges = std::map<const TopoDS_TShape*, EdgeRange>;

// Sets the range of `rep` when it is a curve (3D or on a surface), as BRep_Builder::Range does.
void SetRange(const Handle(BRep_CurveRepresentation) & rep, const EdgeRange& range) {
  Handle(BRep_GCurve) curve = Handle(BRep_GCurve)::DownCast(rep);
  if (!curve.IsNull()) curve->SetRange(range.first, range.last);
}

// What the fixing of a face finds of its shared edges and vertices, as the faces fixed before
// it in OCCT's order left them: cut ranges, raised tolerances.
struct FoundState {
  EdgeRanges ranges;
  std::map<const TopoDS_TShape*, double> tolerances;  // raw edge or vertex -> raised tolerance
  bool operator==(const FoundState& other) const {
    return ranges == other.ranges && tolerances == other.tolerances;
  }
  bool operator!=(const FoundState& other) const { return !(*this == other); }
};

// One face of one item, fixed on its own.
struct FaceJob {
  BrepItem* item = nullptr;
  size_t item_index = 0;
  size_t order = 0;  // its place among the item's faces, the order OCCT's shell tool fixes them in
  // Its shared edges and vertices as the faces before it left them for its fixing: cut ranges
  // (OCCT's ShapeFix_SplitTool::CutEdge sets every representation's range of an edge in place)
  // and raised tolerances. Empty outside items whose faces go in order.
  FoundState found;
  EdgeRanges cut;     // the shared edges whose range this face's fixing cut, and to what
  TopoDS_Face raw;    // the face as it occurs in its shell
  TopoDS_Face local;  // the private copy ShapeFix_Face works on
  Handle(ShapeBuild_ReShape) context;
  TopTools_DataMapOfShapeShape copies;  // raw edge or vertex (FORWARD) -> its private copy
  TopoDS_Shape healed;
  const char* failure = nullptr;        // why the result cannot be merged; null when it can
  TopTools_DataMapOfShapeShape raw_of;  // healed edge or vertex -> the raw one
  TopTools_DataMapOfShapeShape healed_of_shared;  // raw shared edge -> its healed copy
  TopTools_DataMapOfShapeReal vertex_tolerances;  // raw vertex -> tolerance asked for
  StoredPcurves stored;                           // plane pcurves kept on `healed` (FixFace)
};

bool IsIdentity(const TopoDS_Shape& shape) { return shape.Location().IsIdentity(); }

// A private copy of a vertex: same point, tolerance and point representations.
TopoDS_Shape CopyVertex(const TopoDS_Shape& vertex, const FoundState& state,
                        TopTools_DataMapOfShapeShape* copies) {
  if (const TopoDS_Shape* found = copies->Seek(vertex)) return *found;
  TopoDS_Shape copy = vertex.EmptyCopied();
  if (const auto raised = state.tolerances.find(vertex.TShape().get());
      raised != state.tolerances.end())
    Handle(BRep_TVertex)::DownCast(copy.TShape())->UpdateTolerance(raised->second);
  copy.Orientation(TopAbs_FORWARD);
  copies->Bind(vertex, copy);
  return copy;
}

// A private copy of an edge for the face on `surface` at `location`: its 3D curve and its
// representations on that surface only, its tolerance and flags, copies of its vertices.
TopoDS_Shape CopyEdge(const TopoDS_Shape& edge, const Handle(Geom_Surface) & surface,
                      const TopLoc_Location& location, const FoundState& state,
                      TopTools_DataMapOfShapeShape* copies) {
  if (const TopoDS_Shape* found = copies->Seek(edge)) return *found;
  Handle(BRep_TEdge) raw = Handle(BRep_TEdge)::DownCast(edge.TShape());
  BRep_Builder builder;
  TopoDS_Edge copy;
  builder.MakeEdge(copy);
  Handle(BRep_TEdge) te = Handle(BRep_TEdge)::DownCast(copy.TShape());
  for (BRep_ListIteratorOfListOfCurveRepresentation it(raw->Curves()); it.More(); it.Next()) {
    const Handle(BRep_CurveRepresentation)& rep = it.Value();
    if (rep->IsCurve3D()) {
      te->ChangeCurves().Append(rep->Copy());
    } else if (rep->IsCurveOnSurface(surface, location)) {
      // ShapeFix reverses and shifts pcurves in place: the copy gets its own, so the raw face
      // stays as built (for HealItem, should the merge be refused).
      Handle(BRep_CurveRepresentation) copy = rep->Copy();
      copy->PCurve(Handle(Geom2d_Curve)::DownCast(rep->PCurve()->Copy()));
      if (rep->IsCurveOnClosedSurface())
        copy->PCurve2(Handle(Geom2d_Curve)::DownCast(rep->PCurve2()->Copy()));
      te->ChangeCurves().Append(copy);
    }
  }
  // As BRep_Builder::Range(edge, first, last) left it for the faces fixed after the cut.
  if (const auto found = state.ranges.find(raw.get()); found != state.ranges.end()) {
    for (BRep_ListIteratorOfListOfCurveRepresentation it(te->Curves()); it.More(); it.Next())
      SetRange(it.Value(), found->second);
  }
  te->Tolerance(raw->Tolerance());
  if (const auto raised = state.tolerances.find(raw.get()); raised != state.tolerances.end())
    te->UpdateTolerance(raised->second);
  te->SameParameter(raw->SameParameter());
  te->SameRange(raw->SameRange());
  te->Degenerated(raw->Degenerated());
  for (TopoDS_Iterator it(edge, Standard_False, Standard_False); it.More(); it.Next()) {
    TopoDS_Shape vertex = CopyVertex(it.Value().Oriented(TopAbs_FORWARD), state, copies);
    builder.Add(copy, vertex.Oriented(it.Value().Orientation()));
  }
  copies->Bind(edge, copy);
  return copy;
}

// The private copy of a face: its wires, edges and vertices anew, orientations and order kept.
// False when the face holds located sub-shapes (BuildItem never makes them).
bool CopyFace(FaceJob* job) {
  TopLoc_Location location;
  const Handle(Geom_Surface)& surface = BRep_Tool::Surface(job->raw, location);
  if (!IsIdentity(job->raw)) return false;
  BRep_Builder builder;
  TopoDS_Shape face = job->raw.EmptyCopied();
  face.Orientation(TopAbs_FORWARD);  // so the wires keep their own orientations
  for (TopoDS_Iterator w(job->raw, Standard_False, Standard_False); w.More(); w.Next()) {
    const TopoDS_Shape& wire = w.Value();
    if (wire.ShapeType() != TopAbs_WIRE || !IsIdentity(wire)) return false;
    TopoDS_Wire copy;
    builder.MakeWire(copy);
    for (TopoDS_Iterator e(wire, Standard_False, Standard_False); e.More(); e.Next()) {
      const TopoDS_Shape& edge = e.Value();
      if (edge.ShapeType() != TopAbs_EDGE || !IsIdentity(edge)) return false;
      for (TopoDS_Iterator v(edge); v.More(); v.Next())
        if (!IsIdentity(v.Value())) return false;
      TopoDS_Shape local =
          CopyEdge(edge.Oriented(TopAbs_FORWARD), surface, location, job->found, &job->copies);
      builder.Add(copy, local.Oriented(edge.Orientation()));
    }
    copy.Closed(wire.Closed());
    builder.Add(face, copy.Oriented(wire.Orientation()));
  }
  job->local = TopoDS::Face(face.Oriented(job->raw.Orientation()));
  return true;
}

// ShapeFix_Face on the copy, set up as ShapeFix_Shell's face tool is under XSAlgo's defaults.
// Whether `face` lies on a plane, where OCCT keeps no pcurve and projects the 3D curve again on
// every BRep_Tool::CurveOnSurface call.
bool OnPlane(const TopoDS_Face& face) { return FaceSurfaceType(face) == SurfaceType::kPlane; }

// Stores on each edge of the planar `face` the pcurve BRep_Tool::CurveOnSurface projects, so
// that the fixing, which asks for each one dozens of times, projects it once.
StoredPcurves StorePlanePcurves(const TopoDS_Face& face) {
  StoredPcurves stored;
  BRep_Builder builder;
  for (TopExp_Explorer it(face, TopAbs_EDGE); it.More(); it.Next()) {
    const TopoDS_Edge& edge = TopoDS::Edge(it.Current());
    double first, last;
    Standard_Boolean was_stored = Standard_False;
    Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, face, first, last, &was_stored);
    if (pcurve.IsNull() || was_stored) continue;
    double first3d, last3d;
    TopLoc_Location location3d;
    Handle(Geom_Curve) curve3d = BRep_Tool::Curve(edge, location3d, first3d, last3d);
    if (curve3d.IsNull() || first3d != first || last3d != last)
      continue;  // only where the stored curve reads back over the same range
    builder.UpdateEdge(edge, pcurve, face, BRep_Tool::Tolerance(edge));
    stored.emplace(pcurve.get(),
                   StoredPcurve{pcurve, first, last, pcurve->Value(first), pcurve->Value(last),
                                curve3d, location3d, first3d, last3d});
  }
  return stored;
}

// The curves of `stored`.
std::vector<Handle(Geom2d_Curve)> Curves(const StoredPcurves& stored) {
  std::vector<Handle(Geom2d_Curve)> curves;
  for (const auto& [address, pcurve] : stored) curves.push_back(pcurve.curve);
  return curves;
}

// Whether every stored pcurve still reads as when it was stored (ShapeFix reverses or shifts
// some pcurves in place), and every edge of the fixed `face` that holds one still has the 3D
// curve and range it was projected from (else OCCT would project another).
bool Unchanged(const StoredPcurves& stored, const TopoDS_Shape& face) {
  for (const auto& [address, pcurve] : stored) {
    if (!pcurve.curve->Value(pcurve.first).IsEqual(pcurve.at_first, 0) ||
        !pcurve.curve->Value(pcurve.last).IsEqual(pcurve.at_last, 0))
      return false;
  }
  if (face.IsNull()) return false;
  for (TopExp_Explorer it(face, TopAbs_EDGE); it.More(); it.Next()) {
    const TopoDS_Edge& edge = TopoDS::Edge(it.Current());
    Handle(BRep_TEdge) te = Handle(BRep_TEdge)::DownCast(edge.TShape());
    if (te.IsNull()) continue;
    for (BRep_ListIteratorOfListOfCurveRepresentation c(te->Curves()); c.More(); c.Next()) {
      const Handle(BRep_CurveRepresentation)& rep = c.Value();
      if (!rep->IsCurveOnSurface()) continue;
      const auto found = stored.find(rep->PCurve().get());
      if (found == stored.end()) continue;
      double first3d, last3d;
      TopLoc_Location location3d;
      Handle(Geom_Curve) curve3d = BRep_Tool::Curve(edge, location3d, first3d, last3d);
      if (curve3d != found->second.curve3d || !location3d.IsEqual(found->second.location3d) ||
          first3d != found->second.first3d || last3d != found->second.last3d)
        return false;
      // The representation's own range, as CurveOnSurface returns it.
      double f, l;
      Handle(BRep_GCurve)::DownCast(rep)->Range(f, l);
      if (f != found->second.first || l != found->second.last) return false;
    }
  }
  return true;
}

// The pcurves the fixing of `jobs` stored and kept.
template <typename Jobs>
std::vector<Handle(Geom2d_Curve)> KeptPcurves(const Jobs& jobs) {
  std::vector<Handle(Geom2d_Curve)> kept;
  for (const auto& job : jobs) {
    const std::vector<Handle(Geom2d_Curve)> curves = Curves(job->stored);
    kept.insert(kept.end(), curves.begin(), curves.end());
  }
  return kept;
}

// Clears what fixing `job` made, for it to be fixed again.
void ResetOutputs(FaceJob* job) {
  job->local.Nullify();
  job->context.Nullify();
  job->copies.Clear();
  job->healed.Nullify();
  job->failure = nullptr;
  job->raw_of.Clear();
  job->healed_of_shared.Clear();
  job->vertex_tolerances.Clear();
  job->stored.clear();
  job->cut.clear();
}

void FixFace(FaceJob* job) {
  const UnitFactors& units = job->item->units;
  const TopoDS_Face local = TopoDS::Face(job->local);
  const StoredPcurves stored = OnPlane(local) ? StorePlanePcurves(local) : StoredPcurves();
  Handle(ShapeFix_Face) fix = new ShapeFix_Face;
  fix->SetPrecision(units.precision);
  fix->SetMaxTolerance(units.max_tolerance);
  fix->FixWireTool()->FixSameParameterMode() = Standard_False;
  job->context = new QuickReShape;
  fix->SetContext(job->context);
  fix->Init(job->local);
  fix->Perform();
  job->healed = job->context->Apply(job->local);
  // Kept on the fixed copy, whose edges the merged item takes over: the shell stages and
  // BRepLib::EncodeRegularity ask for them again, and the stored curve is the one they would
  // project. Removed as before where the fixing changed one in place.
  if (Unchanged(stored, job->healed)) {
    job->stored = stored;
    return;
  }
  // OCCT's reader leaves none on a plane: off the fixed copy, also where it copied an edge.
  RemovePcurves(job->healed, Curves(stored));
  RemovePcurves(local, Curves(stored));
}

// The vertex of `edge` with orientation `orientation` (FORWARD or REVERSED), or null.
TopoDS_Shape VertexOf(const TopoDS_Shape& edge, TopAbs_Orientation orientation) {
  for (TopoDS_Iterator it(edge, Standard_False, Standard_False); it.More(); it.Next())
    if (it.Value().Orientation() == orientation) return it.Value();
  return TopoDS_Shape();
}

// The uses of the item's shared edges by a face: (edge, orientation in the face), sorted.
std::vector<std::pair<const void*, int>> SharedUses(const TopoDS_Shape& face,
                                                    const TopTools_MapOfShape& shared,
                                                    const TopTools_DataMapOfShapeShape* raw_of) {
  std::vector<std::pair<const void*, int>> uses;
  for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
    TopoDS_Shape edge = ex.Current();
    if (raw_of != nullptr) {
      const TopoDS_Shape* raw = raw_of->Seek(edge);
      if (raw == nullptr) continue;
      edge = raw->Oriented(edge.Orientation());
    }
    if (!shared.Contains(edge)) continue;
    uses.emplace_back(edge.TShape().get(), static_cast<int>(edge.Orientation()));
  }
  std::sort(uses.begin(), uses.end());
  return uses;
}

// Whether the fixing of a same-parameter, same-range edge `raw` changed its copy `healed` only as
// ShapeFix_SplitTool::CutEdge does where a wire's edges cross near a vertex: every range (of the
// 3D curve and of the pcurves) set to one new range, as BRep_Builder::Range sets them.
bool IsRangeCut(const TopoDS_Edge& raw, const TopoDS_Edge& healed) {
  if (!BRep_Tool::SameParameter(raw) || !BRep_Tool::SameRange(raw) ||
      !BRep_Tool::SameParameter(healed) || !BRep_Tool::SameRange(healed))
    return false;
  double first, last;
  BRep_Tool::Range(healed, first, last);
  for (BRep_ListIteratorOfListOfCurveRepresentation it(
           Handle(BRep_TEdge)::DownCast(healed.TShape())->Curves());
       it.More(); it.Next()) {
    Handle(BRep_GCurve) curve = Handle(BRep_GCurve)::DownCast(it.Value());
    if (curve.IsNull()) return false;  // a polygon: nothing the reader's fixing makes
    if (curve->First() != first || curve->Last() != last) return false;
  }
  return true;
}

// Whether the fixing kept the face's ties to the other faces, so its copy can be merged back:
// every edge it shares with another face used as before, on its own 3D curve and range, its
// vertices where they were. Anything private to the face (a seam, an edge added at a pole, a
// new surface) may change. Fills the records the merge reads.
const char* CheckMergeable(FaceJob* job, const TopTools_MapOfShape& shared) {
  if (job->healed.IsNull() || job->healed.ShapeType() != TopAbs_FACE) return "face split";
  if (job->healed.Orientation() != job->local.Orientation()) return "face reversed";
  if (!IsIdentity(job->healed)) return "located face";
  for (TopTools_DataMapOfShapeShape::Iterator it(job->copies); it.More(); it.Next()) {
    const TopoDS_Shape& raw = it.Key();
    TopoDS_Shape healed = job->context->Apply(it.Value());
    if (healed.IsNull() || healed.ShapeType() != raw.ShapeType()) {
      if (raw.ShapeType() == TopAbs_VERTEX || shared.Contains(raw)) return "shared edge removed";
      continue;
    }
    healed.Orientation(TopAbs_FORWARD);
    if (job->raw_of.IsBound(healed)) return "two edges or vertices merged";
    job->raw_of.Bind(healed, raw);
    if (raw.ShapeType() == TopAbs_EDGE && shared.Contains(raw))
      job->healed_of_shared.Bind(raw, healed);
  }
  if (SharedUses(job->raw, shared, nullptr) != SharedUses(job->healed, shared, &job->raw_of))
    return "shared edges used differently";
  for (TopTools_DataMapOfShapeShape::Iterator it(job->healed_of_shared); it.More(); it.Next()) {
    const TopoDS_Edge& raw = TopoDS::Edge(it.Key());
    const TopoDS_Edge& healed = TopoDS::Edge(it.Value());
    TopLoc_Location lr, lh;
    double fr, lr2, fh, lh2;
    Handle(Geom_Curve) cr = BRep_Tool::Curve(raw, lr, fr, lr2);
    Handle(Geom_Curve) ch = BRep_Tool::Curve(healed, lh, fh, lh2);
    if (cr != ch || !lr.IsEqual(lh)) return "shared edge's curve";
    if (const auto found = job->found.ranges.find(raw.TShape().get());
        found != job->found.ranges.end()) {
      fr = found->second.first;
      lr2 = found->second.last;
    }
    if (fr != fh || lr2 != lh2) {
      if (!IsRangeCut(raw, healed)) return "shared edge's curve";
      job->cut[raw.TShape().get()] = EdgeRange{fh, lh2};
    }
    if (BRep_Tool::Degenerated(raw) != BRep_Tool::Degenerated(healed))
      return "shared edge degenerated";
    for (TopoDS_Iterator v(raw, Standard_False, Standard_False); v.More(); v.Next()) {
      const TopoDS_Shape hv = VertexOf(healed, v.Value().Orientation());
      if (hv.IsNull() || !IsIdentity(hv)) return "shared edge's vertex";
      const TopoDS_Shape* back = job->raw_of.Seek(hv.Oriented(TopAbs_FORWARD));
      if (back == nullptr || !back->IsSame(v.Value())) return "shared edge's vertex replaced";
    }
  }
  // Vertices that come from raw ones stay where they were.
  for (TopExp_Explorer ex(job->healed, TopAbs_VERTEX); ex.More(); ex.Next()) {
    const TopoDS_Shape vertex = ex.Current().Oriented(TopAbs_FORWARD);
    if (!IsIdentity(vertex)) return "located vertex";
    const TopoDS_Shape* raw = job->raw_of.Seek(vertex);
    if (raw == nullptr) continue;
    if (!BRep_Tool::Pnt(TopoDS::Vertex(vertex)).IsEqual(BRep_Tool::Pnt(TopoDS::Vertex(*raw)), 0.))
      return "vertex moved";
    const double tolerance = BRep_Tool::Tolerance(TopoDS::Vertex(vertex));
    if (double* known = job->vertex_tolerances.ChangeSeek(*raw))
      *known = std::max(*known, tolerance);
    else
      job->vertex_tolerances.Bind(*raw, tolerance);
  }
  for (TopExp_Explorer ex(job->healed, TopAbs_EDGE); ex.More(); ex.Next())
    if (!IsIdentity(ex.Current())) return "located edge";
  return nullptr;
}

void Faces(const TopoDS_Shape& shape, std::vector<TopoDS_Face>* faces) {
  if (shape.ShapeType() == TopAbs_FACE) {
    faces->push_back(TopoDS::Face(shape));
    return;
  }
  for (TopoDS_Iterator it(shape, Standard_False, Standard_False); it.More(); it.Next())
    Faces(it.Value(), faces);
}

// The edges of `shape` that more than one of its faces use.
TopTools_MapOfShape SharedEdges(const TopoDS_Shape& shape) {
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  TopTools_MapOfShape shared;
  for (int i = 1; i <= edge_faces.Extent(); ++i) {
    TopTools_MapOfShape faces;
    for (const TopoDS_Shape& face : edge_faces(i)) faces.Add(face);
    if (faces.Extent() > 1) shared.Add(edge_faces.FindKey(i).Oriented(TopAbs_FORWARD));
  }
  return shared;
}

// The merged item: the raw structure with every face replaced by its fixed copy, the edges
// faces share made one again (the 3D curve, each face's pcurves, the largest tolerance), the
// vertices too.
class Merger {
 public:
  Merger(const std::vector<FaceJob*>& jobs, const TopTools_MapOfShape& shared)
      : jobs_(jobs), shared_(shared) {
    for (FaceJob* job : jobs_) {
      for (const auto& [edge, range] : job->cut) last_cut_[edge] = {range, job->order};
      job_of_.Bind(job->raw, job);
      for (TopTools_DataMapOfShapeShape::Iterator it(job->healed_of_shared); it.More(); it.Next()) {
        if (auto* copies = copies_of_shared_.ChangeSeek(it.Key()))
          copies->emplace_back(job, it.Value());
        else
          copies_of_shared_.Bind(it.Key(), {{job, it.Value()}});
      }
      for (TopTools_DataMapOfShapeReal::Iterator it(job->vertex_tolerances); it.More(); it.Next()) {
        if (double* known = vertex_tolerances_.ChangeSeek(it.Key()))
          *known = std::max(*known, it.Value());
        else
          vertex_tolerances_.Bind(it.Key(), it.Value());
      }
    }
  }

  TopoDS_Shape Rebuild(const TopoDS_Shape& raw) {
    if (raw.ShapeType() == TopAbs_FACE) {
      TopoDS_Shape merged = Face(*job_of_.Find(raw));
      faces_.Bind(raw, merged);
      return merged.Oriented(raw.Orientation());
    }
    BRep_Builder builder;
    TopoDS_Shape result = raw.EmptyCopied();
    result.Orientation(TopAbs_FORWARD);
    for (TopoDS_Iterator it(raw, Standard_False, Standard_False); it.More(); it.Next())
      builder.Add(result, Rebuild(it.Value()));
    result.Closed(raw.Closed());
    return result.Oriented(raw.Orientation());
  }

  const TopTools_DataMapOfShapeShape& faces() const { return faces_; }

  /// Raw edge -> merged edge, and raw vertex -> merged vertex for the vertices the faces'
  /// fixing left as they were (OCCT's reader keeps such a vertex, and its colour).
  TopTools_DataMapOfShapeShape RawToMerged() const {
    TopTools_DataMapOfShapeShape map = edges_;
    for (TopTools_DataMapOfShapeShape::Iterator it(private_edges_); it.More(); it.Next())
      map.Bind(it.Key(), it.Value());
    for (TopTools_DataMapOfShapeShape::Iterator it(vertices_); it.More(); it.Next()) {
      const double* asked = vertex_tolerances_.Seek(it.Key());
      if (asked == nullptr || *asked <= BRep_Tool::Tolerance(TopoDS::Vertex(it.Key())))
        map.Bind(it.Key(), it.Value());
    }
    return map;
  }

 private:
  TopoDS_Shape MergedVertex(const TopoDS_Shape& raw) {
    if (const TopoDS_Shape* found = vertices_.Seek(raw)) return *found;
    TopoDS_Shape merged = raw.EmptyCopied();
    merged.Orientation(TopAbs_FORWARD);
    if (const double* tolerance = vertex_tolerances_.Seek(raw))
      Handle(BRep_TVertex)::DownCast(merged.TShape())->UpdateTolerance(*tolerance);
    vertices_.Bind(raw, merged);
    return merged;
  }

  // A vertex of a face's fixed copy, in the merged item.
  TopoDS_Shape Vertex(const FaceJob& job, const TopoDS_Shape& healed) {
    const TopoDS_Shape forward = healed.Oriented(TopAbs_FORWARD);
    if (const TopoDS_Shape* raw = job.raw_of.Seek(forward)) return MergedVertex(*raw);
    return forward;  // new, and the face's own
  }

  TopoDS_Shape SharedEdge(const TopoDS_Shape& raw) {
    if (const TopoDS_Shape* found = edges_.Seek(raw)) return *found;
    Handle(BRep_TEdge) source = Handle(BRep_TEdge)::DownCast(raw.TShape());
    BRep_Builder builder;
    TopoDS_Edge merged;
    builder.MakeEdge(merged);
    Handle(BRep_TEdge) te = Handle(BRep_TEdge)::DownCast(merged.TShape());
    // The last cut of the edge's range, in the faces' order: it set every representation's range
    // then, those of the faces fixed before it too.
    const auto cut = last_cut_.find(source.get());
    for (BRep_ListIteratorOfListOfCurveRepresentation it(source->Curves()); it.More(); it.Next()) {
      if (!it.Value()->IsCurve3D()) continue;
      te->ChangeCurves().Append(it.Value()->Copy());
      if (cut != last_cut_.end()) SetRange(te->ChangeCurves().Last(), cut->second.first);
    }
    double tolerance = 0.;
    bool same_parameter = true, same_range = true;
    static const std::vector<std::pair<FaceJob*, TopoDS_Shape>> kNone;
    const auto* found_copies = copies_of_shared_.Seek(raw);
    const auto& copies = found_copies != nullptr ? *found_copies : kNone;
    for (const auto& [job, copy] : copies) {
      const TopoDS_Shape* healed = &copy;
      Handle(BRep_TEdge) he = Handle(BRep_TEdge)::DownCast(healed->TShape());
      for (BRep_ListIteratorOfListOfCurveRepresentation it(he->Curves()); it.More(); it.Next()) {
        if (it.Value()->IsCurve3D()) continue;
        te->ChangeCurves().Append(it.Value()->Copy());
        if (cut != last_cut_.end() && job->order < cut->second.second)
          SetRange(te->ChangeCurves().Last(), cut->second.first);
      }
      tolerance = std::max(tolerance, he->Tolerance());
      same_parameter = same_parameter && he->SameParameter();
      same_range = same_range && he->SameRange();
    }
    te->Tolerance(tolerance);
    te->SameParameter(same_parameter);
    te->SameRange(same_range);
    te->Degenerated(source->Degenerated());
    // The vertices in the order the last face whose fixing rebuilt the edge left them (a later
    // rebuild keeps the order it finds), else as built.
    const FaceJob* reordered = nullptr;
    for (const auto& [job, copy] : copies)
      if (!SameVertexOrder(copy, raw, *job)) reordered = job;
    if (reordered == nullptr) {
      for (TopoDS_Iterator it(raw, Standard_False, Standard_False); it.More(); it.Next())
        builder.Add(
            merged,
            MergedVertex(it.Value().Oriented(TopAbs_FORWARD)).Oriented(it.Value().Orientation()));
    } else {
      const TopoDS_Shape& healed = reordered->healed_of_shared.Find(raw);
      for (TopoDS_Iterator it(healed, Standard_False, Standard_False); it.More(); it.Next())
        builder.Add(merged, Vertex(*reordered, it.Value()).Oriented(it.Value().Orientation()));
    }
    edges_.Bind(raw, merged);
    return merged;
  }

  // Whether `healed`, a face's copy of `raw`, lists its vertices in raw's order.
  static bool SameVertexOrder(const TopoDS_Shape& healed, const TopoDS_Shape& raw,
                              const FaceJob& job) {
    TopoDS_Iterator h(healed, Standard_False, Standard_False);
    TopoDS_Iterator r(raw, Standard_False, Standard_False);
    for (; h.More() && r.More(); h.Next(), r.Next()) {
      if (h.Value().Orientation() != r.Value().Orientation()) return false;
      const TopoDS_Shape* back = job.raw_of.Seek(h.Value().Oriented(TopAbs_FORWARD));
      if (back == nullptr || !back->IsSame(r.Value())) return false;
    }
    return !h.More() && !r.More();
  }

  // An edge of the face's own (new, or used by this face alone), its vertices merged.
  TopoDS_Shape PrivateEdge(const FaceJob& job, const TopoDS_Shape& healed,
                           TopTools_DataMapOfShapeShape* made) {
    if (const TopoDS_Shape* found = made->Seek(healed)) return *found;
    BRep_Builder builder;
    TopoDS_Shape edge = healed.EmptyCopied();
    edge.Orientation(TopAbs_FORWARD);
    for (TopoDS_Iterator it(healed, Standard_False, Standard_False); it.More(); it.Next())
      builder.Add(edge, Vertex(job, it.Value()).Oriented(it.Value().Orientation()));
    made->Bind(healed, edge);
    if (const TopoDS_Shape* raw = job.raw_of.Seek(healed)) private_edges_.Bind(*raw, edge);
    return edge;
  }

  TopoDS_Shape Face(const FaceJob& job) {
    BRep_Builder builder;
    TopoDS_Shape face = job.healed.EmptyCopied();
    face.Orientation(TopAbs_FORWARD);
    TopTools_DataMapOfShapeShape made;
    for (TopoDS_Iterator hw(job.healed, Standard_False, Standard_False); hw.More(); hw.Next()) {
      const TopoDS_Shape& healed_wire = hw.Value();
      TopoDS_Wire wire;
      builder.MakeWire(wire);
      for (TopoDS_Iterator he(healed_wire, Standard_False, Standard_False); he.More(); he.Next()) {
        const TopoDS_Shape forward = he.Value().Oriented(TopAbs_FORWARD);
        const TopoDS_Shape* raw = job.raw_of.Seek(forward);
        TopoDS_Shape edge = (raw != nullptr && shared_.Contains(*raw))
                                ? SharedEdge(*raw)
                                : PrivateEdge(job, forward, &made);
        builder.Add(wire, edge.Oriented(he.Value().Orientation()));
      }
      wire.Closed(healed_wire.Closed());
      builder.Add(face, wire.Oriented(healed_wire.Orientation()));
    }
    return face;
  }

  const std::vector<FaceJob*>& jobs_;
  // Shared raw edge -> the last range a face's fixing cut it to, and that face's order.
  std::map<const TopoDS_TShape*, std::pair<EdgeRange, size_t>> last_cut_;
  const TopTools_MapOfShape& shared_;
  NCollection_DataMap<TopoDS_Shape, FaceJob*, TopTools_ShapeMapHasher> job_of_;
  // Each shared raw edge's fixed copies, with their faces' jobs, in the jobs' order: looked up
  // once per edge, not in every face's map (quadratic in an item's faces).
  NCollection_DataMap<TopoDS_Shape, std::vector<std::pair<FaceJob*, TopoDS_Shape>>,
                      TopTools_ShapeMapHasher>
      copies_of_shared_;
  TopTools_DataMapOfShapeReal vertex_tolerances_;
  TopTools_DataMapOfShapeShape vertices_, edges_, faces_, private_edges_;
};

// The shell, solid, same-parameter and vertex-tolerance stages of ShapeFix_Shape, on an item
// whose faces are fixed already.
void FinishItem(BrepItem* item, const TopoDS_Shape& merged,
                const TopTools_DataMapOfShapeShape& merged_faces,
                const TopTools_DataMapOfShapeShape& merged_edges_vertices,
                const std::vector<FaceJob*>& jobs, const ParallelRunner& runner) {
  item->healed = merged;
  item->modified.Clear();
  Handle(ShapeFix_Shape) fix = NewShapeFix();
  fix->Init(merged);
  fix->SetPrecision(item->units.precision);
  fix->SetMaxTolerance(item->units.max_tolerance);
  fix->FixFaceTool()->FixWireTool()->FixSameParameterMode() = Standard_False;
  fix->FixSolidTool()->CreateOpenSolidMode() = Standard_False;
  fix->FixShellTool()->FixFaceMode() = 0;
  // ShapeFix_Shape's last two stages run below, their checks in parallel.
  fix->FixSameParameterMode() = 0;
  fix->FixVertexTolMode() = 0;
  // Where the shell and solid stages would change nothing, Perform would return `merged` with
  // its context empty.
  TopoDS_Shape result = merged;
  if (!ShellAndSolidStagesWithoutChange(merged, runner)) {
    // OCCT's own stages read stored pcurves only in places: they run as OCCT's reader runs them.
    RemovePcurves(merged, KeptPcurves(jobs));
    fix->Perform();
    result = fix->Shape();
  }
  if (!result.IsNull()) {
    if (!SameParameterInParallel(result, runner)) {
      RemovePcurves(result, KeptPcurves(jobs));
      ShapeFix::SameParameter(result, Standard_False);
    }
    // The edge tool works through the shape's context, as after ShapeFix_Face has run.
    Handle(ShapeFix_Edge) edge_tool = fix->FixEdgeTool();
    edge_tool->SetContext(fix->Context());
    FixVertexTolerancesInParallel(result, edge_tool, runner);
    result = fix->Context()->Apply(result);
  }
  if (!result.IsNull()) item->healed = result;
  TopTools_DataMapOfShapeShape second;
  if (!result.IsNull() && result != merged) RecordModifications(merged, fix->Context(), &second);
  for (TopTools_DataMapOfShapeShape::Iterator it(merged_faces); it.More(); it.Next()) {
    const TopoDS_Shape* again = second.Seek(it.Value());
    item->modified.Bind(it.Key(), again != nullptr ? *again : it.Value());
  }
  for (TopTools_DataMapOfShapeShape::Iterator it(merged_edges_vertices); it.More(); it.Next()) {
    if (it.Value().ShapeType() == TopAbs_VERTEX) {
      // Kept only where the finishing stages left it, as OCCT's record goes no deeper than edges.
      TopoDS_Shape replaced;
      if (fix->Context()->Status(it.Value(), replaced, Standard_True) != 0 &&
          !replaced.IsSame(it.Value()))
        continue;
      item->modified.Bind(it.Key(), it.Value());
      continue;
    }
    const TopoDS_Shape* again = second.Seek(it.Value());
    item->modified.Bind(it.Key(), again != nullptr ? *again : it.Value());
  }
}

}  // namespace

void RemovePcurves(const TopoDS_Shape& shape, const std::vector<Handle(Geom2d_Curve)>& pcurves) {
  if (pcurves.empty() || shape.IsNull()) return;
  std::unordered_set<const Geom2d_Curve*> remove;
  for (const Handle(Geom2d_Curve) & pcurve : pcurves) remove.insert(pcurve.get());
  TopTools_IndexedMapOfShape edges;
  TopExp::MapShapes(shape, TopAbs_EDGE, edges);
  for (int i = 1; i <= edges.Extent(); ++i) {
    Handle(BRep_TEdge) te = Handle(BRep_TEdge)::DownCast(edges(i).TShape());
    if (te.IsNull()) continue;
    BRep_ListOfCurveRepresentation& curves = te->ChangeCurves();
    for (BRep_ListIteratorOfListOfCurveRepresentation c(curves); c.More();) {
      const Handle(BRep_CurveRepresentation)& rep = c.Value();
      if (rep->IsCurveOnSurface() && !rep->IsCurveOnClosedSurface() &&
          remove.count(rep->PCurve().get()) > 0) {
        curves.Remove(c);
      } else {
        c.Next();
      }
    }
  }
}

HealStats HealItems(const std::vector<BrepItem*>& items, int threads,
                    const std::function<bool()>& stop) {
  HealStats stats;
  auto start = std::chrono::steady_clock::now();
  auto seconds = [&] {
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    start = now;
    return elapsed;
  };
  std::vector<std::unique_ptr<FaceJob>> jobs;
  std::vector<std::vector<FaceJob*>> item_jobs(items.size());
  std::vector<TopTools_MapOfShape> shared(items.size());
  for (size_t i = 0; i < items.size(); ++i) {
    if (items[i]->raw.IsNull()) continue;
    shared[i] = SharedEdges(items[i]->raw);
    std::vector<TopoDS_Face> faces;
    Faces(items[i]->raw, &faces);
    for (const TopoDS_Face& face : faces) {
      auto job = std::make_unique<FaceJob>();
      job->item = items[i];
      job->item_index = i;
      job->raw = face;
      job->order = item_jobs[i].size();
      item_jobs[i].push_back(job.get());
      jobs.push_back(std::move(job));
    }
  }
  const ParallelRunner runner(threads);
  std::atomic<bool> stopped{false};
  // An item with one face that cannot be merged is healed whole by HealItem: its other faces
  // are not fixed in vain.
  static const char* const kSkipped = "skipped";
  const std::unique_ptr<std::atomic<bool>[]> refused(new std::atomic<bool>[items.size()]);
  for (size_t i = 0; i < items.size(); ++i) refused[i] = false;
  auto fix_jobs = [&](const std::vector<FaceJob*>& some) {
    runner.For(
        0, static_cast<int>(some.size()),
        [&](int j) {
          if (stopped.load() || (stop && stop())) {
            stopped = true;
            return;
          }
          FaceJob* job = some[j];
          if (refused[job->item_index].load()) {
            job->failure = kSkipped;
            return;
          }
          ResetOutputs(job);
          try {
            OCC_CATCH_SIGNALS
            if (!CopyFace(job)) {
              job->failure = "located sub-shapes";
            } else {
              FixFace(job);
              job->failure = CheckMergeable(job, shared[job->item_index]);
            }
          } catch (...) {
            job->failure = "an exception";
          }
          if (job->failure != nullptr) refused[job->item_index] = true;
        },
        Partition::kOnePerTask);
  };
  std::vector<FaceJob*> all(jobs.size());
  for (size_t j = 0; j < jobs.size(); ++j) all[j] = jobs[j].get();
  fix_jobs(all);
  // In an item where a face's fixing cut a shared edge's range, each face must find its edges
  // and vertices as OCCT's run leaves them for it: cut, with the tolerances the faces before it
  // raised. It is fixed again with them. Each round settles at least the first face whose input
  // changed; an item still unsettled after a few rounds is healed whole. (Elsewhere the faces
  // see the item as built, which the merge makes equal to OCCT's result.)
  static constexpr int kRounds = 6;
  std::vector<char> in_order(items.size(), 0);
  for (int round = 0; round <= kRounds && !stopped; ++round) {
    std::vector<FaceJob*> again;
    for (size_t i = 0; i < items.size(); ++i) {
      if (refused[i].load()) continue;
      for (const FaceJob* job : item_jobs[i])
        if (!job->cut.empty()) in_order[i] = 1;
      if (!in_order[i]) continue;
      const size_t before_again = again.size();
      FoundState state;  // as the faces fixed so far left the item's shared edges and vertices
      for (FaceJob* job : item_jobs[i]) {
        FoundState found;
        for (TopExp_Explorer ex(job->raw, TopAbs_EDGE); ex.More(); ex.Next()) {
          const TopoDS_TShape* edge = ex.Current().TShape().get();
          if (auto range = state.ranges.find(edge); range != state.ranges.end())
            found.ranges.insert(*range);
          if (auto raised = state.tolerances.find(edge); raised != state.tolerances.end())
            found.tolerances.insert(*raised);
        }
        for (TopExp_Explorer ex(job->raw, TopAbs_VERTEX); ex.More(); ex.Next()) {
          const TopoDS_TShape* vertex = ex.Current().TShape().get();
          if (auto raised = state.tolerances.find(vertex); raised != state.tolerances.end())
            found.tolerances.insert(*raised);
        }
        if (found != job->found) {
          job->found = std::move(found);
          again.push_back(job);
        }
        for (const auto& [edge, range] : job->cut) state.ranges[edge] = range;
        auto raise = [&](const TopoDS_Shape& raw, double tolerance, double raw_tolerance) {
          if (tolerance <= raw_tolerance) return;
          double& known = state.tolerances[raw.TShape().get()];
          known = std::max(known, tolerance);
        };
        for (TopTools_DataMapOfShapeShape::Iterator it(job->healed_of_shared); it.More(); it.Next())
          raise(it.Key(), BRep_Tool::Tolerance(TopoDS::Edge(it.Value())),
                BRep_Tool::Tolerance(TopoDS::Edge(it.Key())));
        for (TopTools_DataMapOfShapeReal::Iterator it(job->vertex_tolerances); it.More(); it.Next())
          raise(it.Key(), it.Value(), BRep_Tool::Tolerance(TopoDS::Vertex(it.Key())));
      }
      if (round == kRounds && again.size() > before_again) {
        refused[i] = true;
        if (stats.refused.empty()) stats.refused = "cut edges unsettled";
      }
    }
    if (again.empty() || round == kRounds) break;
    fix_jobs(again);
    stats.faces_fixed_again += static_cast<int>(again.size());
  }
  for (char order : in_order) stats.items_in_order += order;
  stats.face_seconds = seconds();
  if (stopped) return stats;
  std::atomic<int> parallel{0};
  std::mutex refused_mutex;
  runner.For(
      0, static_cast<int>(items.size()),
      [&](int i) {
        BrepItem* item = items[i];
        bool mergeable = !item_jobs[i].empty() && !refused[i].load();
        for (FaceJob* job : item_jobs[i]) {
          if (job->failure == nullptr) continue;
          mergeable = false;
          if (job->failure == kSkipped) continue;
          std::lock_guard<std::mutex> lock(refused_mutex);
          if (stats.refused.empty()) stats.refused = job->failure;
          break;
        }
        if (mergeable) {
          try {
            OCC_CATCH_SIGNALS
            Merger merger(item_jobs[i], shared[i]);
            TopoDS_Shape merged = merger.Rebuild(item->raw);
            FinishItem(item, merged, merger.faces(), merger.RawToMerged(), item_jobs[i], runner);
            ++parallel;
            return;
          } catch (...) {
          }
        }
        HealItem(item);
      },
      Partition::kOnePerTask);
  stats.finish_seconds = seconds();
  stats.items_face_parallel = parallel.load();
  stats.kept_pcurves = KeptPcurves(jobs);
  return stats;
}

}  // namespace rdmesh::step
