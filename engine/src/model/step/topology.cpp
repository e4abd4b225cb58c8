// OCC_CATCH_SIGNALS below must turn faults inside OCCT's modelling classes into exceptions, in
// TBB's worker threads too, when the caller has OCCT's fault handlers installed (model_readers'
// ScopedOcctFaultHandlers); it has to be defined before any OCCT header.
#define OCC_CONVERT_SIGNALS 1

#include "model/step/topology.h"

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepLib.hxx>
#include <BRepLib_MakeEdge.hxx>
#include <BRep_Builder.hxx>
#include <BRep_CurveRepresentation.hxx>
#include <BRep_GCurve.hxx>
#include <BRep_ListIteratorOfListOfCurveRepresentation.hxx>
#include <BRep_TEdge.hxx>
#include <BRep_TVertex.hxx>
#include <BRep_Tool.hxx>
#include <ElCLib.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <GeomConvert_Units.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_BoundedCurve.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_SphericalSurface.hxx>
#include <Geom_SurfaceOfRevolution.hxx>
#include <Geom_ToroidalSurface.hxx>
#include <Precision.hxx>
#include <ShapeAlgo.hxx>
#include <ShapeAlgo_AlgoContainer.hxx>
#include <ShapeAnalysis_Curve.hxx>
#include <ShapeAnalysis_Edge.hxx>
#include <ShapeBuild.hxx>
#include <ShapeBuild_Edge.hxx>
#include <ShapeBuild_ReShape.hxx>
#include <ShapeExtend.hxx>
#include <ShapeExtend_WireData.hxx>
#include <ShapeFix.hxx>
#include <ShapeFix_Edge.hxx>
#include <ShapeFix_EdgeProjAux.hxx>
#include <ShapeFix_Face.hxx>
#include <ShapeFix_Shape.hxx>
#include <ShapeFix_Shell.hxx>
#include <ShapeFix_Solid.hxx>
#include <ShapeFix_Wire.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <TopAbs.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_DataMapOfShapeReal.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_MapOfShape.hxx>
#include <TopTools_ShapeMapHasher.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <TopoDS_Vertex.hxx>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "core/parallel.h"
#include "geometry/surface_type.h"
#include "model/step/finish.h"

namespace rdmesh::step {

bool IsBrepItem(const Entities& entities, const Instance& instance) {
  std::string_view type = entities.SimpleType(instance);
  return type == "MANIFOLD_SOLID_BREP" || type == "BREP_WITH_VOIDS" ||
         type == "SHELL_BASED_SURFACE_MODEL" || type == "GEOMETRIC_CURVE_SET" ||
         type == "GEOMETRIC_SET";
}

void OrderEdgeParameters(const Handle(Geom_Curve) & curve, double& w1, double& w2, double preci) {
  const double first = curve->FirstParameter();
  const double last = curve->LastParameter();
  const double eps = Precision::PConfusion();
  auto clamp = [first, last](double w) { return w < first ? first : w > last ? last : w; };
  if (curve->IsKind(STANDARD_TYPE(Geom_BoundedCurve)) && !curve->IsClosed()) {
    w1 = clamp(w1);
    w2 = clamp(w2);
  }
  if (w1 < w2) return;
  auto reverse_curve = [&] {
    w1 = curve->ReversedParameter(w1);
    w2 = curve->ReversedParameter(w2);
    curve->Reverse();
  };
  if (curve->IsPeriodic()) {
    ElCLib::AdjustPeriodic(first, last, eps, w1, w2);
  } else if (curve->IsClosed()) {
    if (std::abs(w2 - first) < eps) {
      w2 = last;  // the end projected on the seam's first side
    } else if (std::abs(w1 - last) < eps) {
      w1 = first;
    } else {
      if (curve->Value(w1).Distance(curve->Value(first)) < preci) w1 = first;
      if (curve->Value(w2).Distance(curve->Value(last)) < preci) w2 = last;
      if (std::abs(w2 - w1) < eps) {
        w1 = first;
        w2 = last;
      } else if (w1 > w2) {
        std::swap(w1, w2);
      }
    }
  } else if (curve->IsKind(STANDARD_TYPE(Geom_BSplineCurve))) {
    Handle(Geom_BSplineCurve) spline = Handle(Geom_BSplineCurve)::DownCast(curve);
    if (spline->StartPoint().Distance(spline->EndPoint()) <= preci) {
      if (std::abs(w2 - first) < eps)
        w2 = last;
      else if (std::abs(w1 - last) < eps)
        w1 = first;
      else
        std::swap(w1, w2);
    } else if (w1 > w2) {
      reverse_curve();
    }
    if (w1 == w2) {
      w1 = first;
      w2 = last;
    }
  } else {
    if (w1 > w2) reverse_curve();
    if (w1 == w2) {
      w1 -= eps;
      w2 += eps;
    }
  }
}

namespace {

// An edge on the 3D curve of `edge` over its range, with new vertices at the curve's ends: the
// scratch edge on which CheckPCurve below compares pcurves. Null when `edge` has no 3D curve.
TopoDS_Edge EdgeOnItsCurve(const TopoDS_Edge& edge) {
  Handle(Geom_Curve) curve;
  double first = 0., last = 0.;
  if (!ShapeAnalysis_Edge().Curve3d(edge, curve, first, last, Standard_False)) return TopoDS_Edge();
  BRepBuilderAPI_MakeEdge make(curve, curve->Value(first), curve->Value(last), first, last);
  ShapeBuild_Edge().SetRange3d(make, first, last);
  return make.Edge();
}

}  // namespace

bool CheckPCurve(const TopoDS_Edge& edge, const TopoDS_Face& face, double preci, bool seam) {
  Handle(Geom2d_Curve) pcurve;
  double w1 = 0., w2 = 0.;
  ShapeAnalysis_Edge sae;
  if (!sae.PCurve(edge, face, pcurve, w1, w2, Standard_False)) return false;

  Handle(Geom_Surface) surface = BRep_Tool::Surface(face);
  double u_first, u_last, v_first, v_last;
  surface->Bounds(u_first, u_last, v_first, v_last);
  const gp_Pnt2d uv1 = pcurve->Value(w1);
  const gp_Pnt2d uv2 = pcurve->Value(w2);
  // Several periods (an angle in degrees read as radians): divided before subtracting, so that
  // infinite bounds stay comparable.
  const double du = std::abs(uv1.X() - uv2.X());
  const double dv = std::abs(uv1.Y() - uv2.Y());
  if (du / 8. > (u_last / 6. - u_first / 6.) || dv / 8. > (v_last / 6. - v_first / 6.)) {
    ShapeBuild_Edge().RemovePCurve(edge, face);
    return false;
  }

  Handle(Geom_Curve) curve;
  double c_first = 0., c_last = 0.;
  sae.Curve3d(edge, curve, c_first, c_last, Standard_False);
  const TopoDS_Vertex v1 = TopExp::FirstVertex(edge);
  const TopoDS_Vertex v2 = TopExp::LastVertex(edge);
  const gp_Pnt end1 = curve.IsNull() ? BRep_Tool::Pnt(v1) : curve->Value(c_first);
  const gp_Pnt end2 = curve.IsNull() ? BRep_Tool::Pnt(v2) : curve->Value(c_last);
  if (!(end1.Distance(surface->Value(uv1.X(), uv1.Y())) <= preci &&
        end2.Distance(surface->Value(uv2.X(), uv2.Y())) <= preci)) {
    ShapeBuild_Edge().RemovePCurve(edge, face);
    return false;
  }
  if (curve.IsNull()) return false;

  BRep_Builder builder;
  TopoDS_Edge scratch = EdgeOnItsCurve(edge);
  Handle(Geom2d_Curve) other;  // a seam's second pcurve
  if (seam) {
    double f, l;
    if (!sae.PCurve(TopoDS::Edge(edge.Reversed()), face, other, f, l, Standard_False) ||
        other == pcurve)
      other = Handle(Geom2d_Curve)::DownCast(pcurve->Copy());
    builder.UpdateEdge(scratch, pcurve, other, face, 0.);
  } else {
    builder.UpdateEdge(scratch, pcurve, face, 0.);
  }
  builder.Range(scratch, face, w1, w2);
  builder.SameRange(scratch, Standard_False);
  // XSAlgo's read.stdsameparameter.mode is 0: the scratch edge keeps its same-parameter flag.
  Handle(ShapeFix_Edge) fix = new ShapeFix_Edge;
  fix->FixSameParameter(scratch);
  double tolerance = BRep_Tool::Tolerance(scratch);
  bool same_range = BRep_Tool::SameRange(scratch);
  bool same_parameter = BRep_Tool::SameParameter(scratch);
  if (tolerance > std::min(1., 2. * preci) || !same_range) {
    TopoDS_Edge projected = EdgeOnItsCurve(edge);
    fix->FixAddPCurve(projected, face, seam, preci);
    fix->FixSameParameter(projected);
    const double projected_tolerance = BRep_Tool::Tolerance(projected);
    if (projected_tolerance < tolerance || !same_range) {
      same_range = BRep_Tool::SameRange(projected);
      same_parameter = BRep_Tool::SameParameter(projected);
      tolerance = projected_tolerance;
      scratch = projected;
    }
  }

  sae.PCurve(scratch, face, pcurve, w1, w2, Standard_False);
  if (seam) {
    double f, l;
    sae.PCurve(TopoDS::Edge(scratch.Reversed()), face, other, f, l, Standard_False);
    if (edge.Orientation() == TopAbs_REVERSED)
      builder.UpdateEdge(edge, other, pcurve, face, tolerance);
    else
      builder.UpdateEdge(edge, pcurve, other, face, tolerance);
  } else {
    builder.UpdateEdge(edge, pcurve, face, tolerance);
  }
  builder.UpdateVertex(v1, tolerance);
  builder.UpdateVertex(v2, tolerance);
  builder.Range(edge, face, w1, w2);
  if (BRep_Tool::SameRange(edge)) builder.SameRange(edge, same_range);
  if (BRep_Tool::SameParameter(edge)) builder.SameParameter(edge, same_parameter);
  return true;
}

namespace {

// The translation of one representation item (StepToTopoDS_Builder with its StepToTopoDS_Tool):
// entity id -> shape, for vertices, edges, loops, faces and shells.
class ItemBuilder {
 public:
  ItemBuilder(Geometry& geometry, BrepItem* item)
      : geometry_(geometry), entities_(geometry.entities()), item_(item), units_(item->units) {}

  TopoDS_Shape Build();

 private:
  TopoDS_Shape Shell(uint64_t id, uint64_t from);
  TopoDS_Shape CurveSet(const Entity& set);
  TopoDS_Face Face(uint64_t id, uint64_t from);
  TopoDS_Wire EdgeLoop(const Entity& bound, const TopoDS_Face& face,
                       const Handle(Geom_Surface) & surface, uint64_t surface_id, bool same_sense);
  TopoDS_Wire VertexLoop(uint64_t id, uint64_t from);
  TopoDS_Vertex Vertex(uint64_t id, uint64_t from);
  TopoDS_Edge Edge(const Entity& edge_curve);
  Handle(Geom2d_Curve)
      PCurve(uint64_t pcurve_id, uint64_t from, const Handle(Geom_Surface) & conv_surface);
  gp_Pnt VertexPoint(uint64_t vertex_id, uint64_t from);

  // An ORIENTED_EDGE (unwrapping one nested oriented edge, as OCCT does) and its EDGE_CURVE.
  struct OrientedEdge {
    uint64_t oriented_id = 0;
    bool orientation = true;
    std::optional<Entity> edge_curve;
  };
  OrientedEdge ReadOrientedEdge(uint64_t id, uint64_t from, bool unwrap);

  bool IsBound(uint64_t id) const { return bound_.count(id) != 0; }
  void Bind(uint64_t id, const TopoDS_Shape& shape) { bound_[id] = shape; }

  Geometry& geometry_;
  const Entities& entities_;
  BrepItem* item_;
  const UnitFactors& units_;
  std::unordered_map<uint64_t, TopoDS_Shape> bound_;
  std::unordered_set<uint64_t> curves_;
};

TopoDS_Vertex ItemBuilder::Vertex(uint64_t id, uint64_t from) {
  auto found = bound_.find(id);
  if (found != bound_.end()) return TopoDS::Vertex(found->second);
  const gp_Pnt point = VertexPoint(id, from);
  BRep_Builder builder;
  TopoDS_Vertex vertex;
  builder.MakeVertex(vertex, point, Precision::Confusion());
  Bind(id, vertex);
  return vertex;
}

gp_Pnt ItemBuilder::VertexPoint(uint64_t id, uint64_t from) {
  const Instance& instance = entities_.Get(id, from);
  if (entities_.SimpleType(instance) != "VERTEX_POINT")
    ThrowUnsupported(entities_.Describe(instance) + " as a vertex");
  Entity vertex = entities_.Simple(instance);
  return geometry_.Point(vertex.Ref(1), id, units_);
}

ItemBuilder::OrientedEdge ItemBuilder::ReadOrientedEdge(uint64_t id, uint64_t from, bool unwrap) {
  // ORIENTED_EDGE(name, *, *, edge_element, orientation)
  const Instance& instance = entities_.Get(id, from);
  if (entities_.SimpleType(instance) != "ORIENTED_EDGE")
    ThrowUnsupported(entities_.Describe(instance) + " in an edge loop");
  Entity oriented = entities_.Simple(instance);
  OrientedEdge result;
  result.oriented_id = id;
  result.orientation = oriented.Logical(4);
  const Instance* element = &entities_.Get(oriented.Ref(3), id);
  if (entities_.SimpleType(*element) == "ORIENTED_EDGE") {
    if (!unwrap) return result;  // StepToTopoDS skips such edges in its vertex checks
    Entity inner = entities_.Simple(*element);
    result.oriented_id = element->id;
    result.orientation = inner.Logical(4);
    element = &entities_.Get(inner.Ref(3), element->id);
  }
  if (entities_.SimpleType(*element) != "EDGE_CURVE")
    ThrowUnsupported(entities_.Describe(*element) + " as an edge");
  result.edge_curve = entities_.Simple(*element);
  return result;
}

Handle(Geom2d_Curve) ItemBuilder::PCurve(uint64_t pcurve_id, uint64_t from,
                                         const Handle(Geom_Surface) & conv_surface) {
  // PCURVE(name, basis_surface, reference_to_curve)
  Entity pcurve = entities_.Simple(entities_.Get(pcurve_id, from));
  const Instance& representation = entities_.Get(pcurve.Ref(2), pcurve_id);
  if (entities_.SimpleType(representation) != "DEFINITIONAL_REPRESENTATION")
    ThrowUnsupported(entities_.Describe(representation) + " as a pcurve's representation");
  Entity definitional = entities_.Simple(representation);
  const Param& items = definitional.List(1);
  if (items.count == 0) return Handle(Geom2d_Curve)();
  Handle(Geom2d_Curve) curve =
      geometry_.Curve2d(definitional.RefItem(items, 0), representation.id, units_);
  if (curve.IsNull()) return curve;
  try {
    OCC_CATCH_SIGNALS
    return GeomConvert_Units::DegreeToRadian(curve, conv_surface, units_.length,
                                             units_.plane_angle);
  } catch (const Standard_Failure&) {
    return Handle(Geom2d_Curve)();
  }
}

// StepToTopoDS_TranslateEdge::MakeFromCurve3D, the path that builds an edge.
TopoDS_Edge ItemBuilder::Edge(const Entity& ec) {
  // EDGE_CURVE(name, edge_start, edge_end, edge_geometry, same_sense)
  const uint64_t id = ec.id();
  auto found = bound_.find(id);
  if (found != bound_.end()) {
    if (BRep_Tool::Degenerated(TopoDS::Edge(found->second)))
      ThrowUnsupported(ec.Name() + ": a degenerated edge in several faces");
    return TopoDS::Edge(found->second);
  }
  const bool same_sense = ec.Logical(4);
  const uint64_t start_id = same_sense ? ec.Ref(1) : ec.Ref(2);
  const uint64_t end_id = same_sense ? ec.Ref(2) : ec.Ref(1);
  TopoDS_Vertex v1 = Vertex(start_id, id);
  v1.Orientation(TopAbs_FORWARD);
  TopoDS_Vertex v2;
  if (end_id == start_id) {
    v2 = v1;
  } else {
    v2 = Vertex(end_id, id);
  }
  v2.Orientation(TopAbs_REVERSED);

  uint64_t curve_id = ec.Ref(3);
  const Instance& curve_instance = entities_.Get(curve_id, id);
  std::string_view curve_type = entities_.SimpleType(curve_instance);
  if (curve_type == "PCURVE") ThrowUnsupported(ec.Name() + ": an edge on a pcurve only");
  if (curve_type == "SURFACE_CURVE" || curve_type == "SEAM_CURVE" ||
      curve_type == "INTERSECTION_CURVE")
    curve_id = entities_.Simple(curve_instance).Ref(1);
  Handle(Geom_Curve) curve = geometry_.SharedCurve(curve_id, curve_instance.id, units_);
  curves_.insert(curve_id);

  const double preci = units_.precision;
  const gp_Pnt pv1 = BRep_Tool::Pnt(v1);
  const gp_Pnt pv2 = BRep_Tool::Pnt(v2);
  gp_Pnt pnt1 = pv1, pnt2 = pv2;
  if (v1.IsSame(v2)) {
    // GetCartesianPoints: the vertices' own points, before any merging.
    pnt1 = VertexPoint(start_id, id);
    pnt2 = VertexPoint(end_id, id);
  }
  ShapeAnalysis_Curve sac;
  gp_Pnt projected;
  double u1 = 0., u2 = 0.;
  sac.Project(curve, pnt1, preci, projected, u1, Standard_False);
  sac.Project(curve, pnt2, preci, projected, u2, Standard_False);
  OrderEdgeParameters(curve, u1, u2, preci);
  GeomAdaptor_Curve adaptor(curve);
  const double d1 = adaptor.Value(u1).Distance(pv1);
  const double d2 = adaptor.Value(u2).Distance(pv2);
  BRep_Builder builder;
  builder.UpdateVertex(v1, 1.000001 * d1);
  builder.UpdateVertex(v2, 1.000001 * d2);
  TopoDS_Edge edge;
  BRepLib_MakeEdge make(curve, v1, v2, u1, u2);
  if (make.IsDone()) {
    edge = make.Edge();
    builder.Range(edge, u1, u2);
  } else if (make.Error() == BRepLib_DifferentPointsOnClosedCurve && curve->IsClosed()) {
    // A closed edge given two vertices: OCCT binds the end vertex to the start one.
    Bind(end_id, v1);
    v2 = TopoDS::Vertex(v1.Reversed());
    make.Init(curve, v1, v2, u1, u2);
    if (!make.IsDone()) ThrowUnsupported(ec.Name() + ": OCCT cannot make this edge");
    edge = make.Edge();
  } else {
    ThrowUnsupported(ec.Name() + ": OCCT cannot make this edge (BRepLib_MakeEdge error " +
                     std::to_string(static_cast<int>(make.Error())) + ")");
  }
  Bind(id, edge);
  return edge;
}

// StepToTopoDS_TranslateVertexLoop.
TopoDS_Wire ItemBuilder::VertexLoop(uint64_t id, uint64_t from) {
  auto found = bound_.find(id);
  if (found != bound_.end()) return TopoDS::Wire(found->second);
  Entity loop = entities_.Simple(entities_.Get(id, from));
  TopoDS_Vertex v1 = Vertex(loop.Ref(1), id);
  TopoDS_Vertex v2 = v1;
  v1.Orientation(TopAbs_FORWARD);
  v2.Orientation(TopAbs_REVERSED);
  BRep_Builder builder;
  TopoDS_Edge edge;
  builder.MakeEdge(edge);
  builder.Add(edge, v1);
  builder.Add(edge, v2);
  builder.Degenerated(edge, Standard_True);
  TopoDS_Wire wire;
  builder.MakeWire(wire);
  wire.Closed(Standard_True);
  builder.Add(wire, edge);
  Bind(id, wire);
  return wire;
}

// A PCURVE of a SURFACE_CURVE's associated geometry (PCURVE_OR_SURFACE), or 0.
uint64_t AssociatedPCurve(const Entities& entities, const Entity& surface_curve,
                          const Param& associated, uint32_t i) {
  const Param& item = surface_curve.Item(associated, i);
  if (item.kind != ParamKind::kRef) return 0;
  const Instance& instance = entities.Get(item.value.ref, surface_curve.id());
  return entities.SimpleType(instance) == "PCURVE" ? instance.id : 0;
}

uint64_t PCurveSurface(const Entities& entities, uint64_t pcurve_id) {
  return entities.Simple(entities.Get(pcurve_id, 0)).Ref(1);
}

// StepToTopoDS_GeometricTool::PCurve: the next associated pcurve (after 1-based `last`) on
// `surface_id`; its 1-based position, or 0.
int NextPCurve(const Entities& entities, const Entity& surface_curve, uint64_t surface_id, int last,
               uint64_t* pcurve_id) {
  const Param& associated = surface_curve.List(2);
  for (uint32_t i = static_cast<uint32_t>(last); i < associated.count; ++i) {
    const uint64_t id = AssociatedPCurve(entities, surface_curve, associated, i);
    if (id != 0 && PCurveSurface(entities, id) == surface_id) {
      *pcurve_id = id;
      return static_cast<int>(i) + 1;
    }
  }
  *pcurve_id = 0;
  return 0;
}

// CheckPCurves of StepToTopoDS_TranslateEdgeLoop.
void CheckPCurves(const TopoDS_Wire& wire, const TopoDS_Face& face, bool is_plane, double preci) {
  if (is_plane) {
    for (TopExp_Explorer ex(wire, TopAbs_EDGE); ex.More(); ex.Next())
      ShapeBuild_Edge().RemovePCurve(TopoDS::Edge(ex.Current()), face);
    return;
  }
  BRep_Builder builder;
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face);
  Handle(ShapeExtend_WireData) data = new ShapeExtend_WireData(wire);
  for (int i = 1; i <= data->NbEdges(); ++i) {
    const TopoDS_Edge& edge = data->Edge(i);
    Handle(Geom2d_Curve) pcurve;
    double w1 = 0., w2 = 0.;
    ShapeAnalysis_Edge sae;
    if (!sae.PCurve(edge, face, pcurve, w1, w2, Standard_False)) continue;
    const double cf = pcurve->FirstParameter();
    const double cl = pcurve->LastParameter();
    if (w1 == w2) {
      ShapeBuild_Edge().RemovePCurve(edge, face);
      continue;
    }
    if (!pcurve->IsPeriodic()) {
      if (w1 < cf) {
        builder.Range(edge, face, cf, w2);
        w1 = cf;
      }
      if (w2 > cl) {
        builder.Range(edge, face, w1, cl);
        w2 = cl;
      }
    }
    if (w1 > w2 && surface->IsUPeriodic()) {
      double u1, u2, v1, v2;
      surface->Bounds(u1, u2, v1, v2);
      ElCLib::AdjustPeriodic(u1, u2, Min(Abs(w2 - w1) / 2, Precision::PConfusion()), w1, w2);
      builder.Range(edge, face, w1, w2);
    }
    CheckPCurve(edge, face, preci, data->IsSeam(i));
  }
}

// StepToTopoDS_TranslateEdgeLoop::Init, for an EDGE_LOOP bound of `face`.
TopoDS_Wire ItemBuilder::EdgeLoop(const Entity& bound, const TopoDS_Face& face,
                                  const Handle(Geom_Surface) & surface, uint64_t surface_id,
                                  bool same_sense) {
  // FACE_BOUND(name, bound, orientation)
  const uint64_t loop_id = bound.Ref(1);
  auto found = bound_.find(loop_id);
  if (found != bound_.end()) return TopoDS::Wire(found->second);
  Entity loop = entities_.Simple(entities_.Get(loop_id, bound.id()));
  const Param& list = loop.List(1);
  const uint32_t count = list.count;
  if (count == 0) ThrowUnsupported(loop.Name() + ": an edge loop without edges");
  const double preci = units_.precision;
  const bool is_plane = surface->IsKind(STANDARD_TYPE(Geom_Plane));
  Handle(Geom_Surface) conv_surface = surface;
  if (auto trimmed = Handle(Geom_RectangularTrimmedSurface)::DownCast(surface))
    conv_surface = trimmed->BasisSurface();
  bool compute_pcurve = false;
  const bool forward_wire = bound.Logical(2);
  BRep_Builder builder;
  TopoDS_Wire wire;
  builder.MakeWire(wire);

  std::vector<OrientedEdge> edges(count);
  for (uint32_t j = 0; j < count; ++j)
    edges[j] = ReadOrientedEdge(loop.RefItem(list, j), loop.id(), /*unwrap=*/true);

  // Vertices and 3D curves first; two vertices at one point on an edge become one.
  for (uint32_t j = 0; j < count; ++j) {
    const Entity& ec = *edges[j].edge_curve;
    uint64_t curve_id = ec.Ref(3);
    const Instance& curve_instance = entities_.Get(curve_id, ec.id());
    std::string_view curve_type = entities_.SimpleType(curve_instance);
    if (curve_type == "SURFACE_CURVE" || curve_type == "SEAM_CURVE" ||
        curve_type == "INTERSECTION_CURVE")
      curve_id = entities_.Simple(curve_instance).Ref(1);
    Handle(Geom_Curve) curve;
    if (curve_type != "PCURVE") {
      curve = geometry_.SharedCurve(curve_id, curve_instance.id, units_);
      curves_.insert(curve_id);
    }
    const bool same = ec.Logical(4);
    const uint64_t vstart = same ? ec.Ref(1) : ec.Ref(2);
    const uint64_t vend = same ? ec.Ref(2) : ec.Ref(1);
    const bool start_bound = IsBound(vstart);
    const bool end_bound = IsBound(vend);
    TopoDS_Vertex v1 = Vertex(vstart, ec.id());
    TopoDS_Vertex v2 = Vertex(vend, ec.id());
    if (BRep_Tool::Pnt(v1).Distance(BRep_Tool::Pnt(v2)) <= Precision::Confusion()) {
      if (!end_bound)
        Bind(vend, v1);
      else if (!start_bound)
        Bind(vstart, v2);
      else
        Bind(vend, v1);
    }
  }

  // Adjacent edges must share their vertex; confused ones are made one, where an edge of the
  // pair is still to be built.
  for (uint32_t j = 0; j < count; ++j) {
    OrientedEdge e1 = ReadOrientedEdge(loop.RefItem(list, j), loop.id(), /*unwrap=*/false);
    OrientedEdge e2 =
        ReadOrientedEdge(loop.RefItem(list, j + 1 < count ? j + 1 : 0), loop.id(), false);
    if (!e1.edge_curve || !e2.edge_curve) continue;
    const Entity& ec1 = *e1.edge_curve;
    const Entity& ec2 = *e2.edge_curve;
    const uint64_t vs1 = e1.orientation ? ec1.Ref(2) : ec1.Ref(1);
    const uint64_t vs2 = e2.orientation ? ec2.Ref(1) : ec2.Ref(2);
    const uint64_t vs11 = e1.orientation ? ec1.Ref(1) : ec1.Ref(2);
    const uint64_t vs22 = e2.orientation ? ec2.Ref(2) : ec2.Ref(1);
    if (vs1 == vs2 || vs1 == vs22 || vs2 == vs11 || vs22 == vs11) continue;
    TopoDS_Vertex v1 = Vertex(vs1, ec1.id());
    TopoDS_Vertex v2 = Vertex(vs2, ec2.id());
    if (v1.IsSame(v2)) continue;
    if (BRep_Tool::Pnt(v1).Distance(BRep_Tool::Pnt(v2)) <= preci) {
      if (!IsBound(ec1.id()))
        Bind(vs1, v2);
      else if (!IsBound(ec2.id()))
        Bind(vs2, v1);
    }
  }

  // The edges, with the file's pcurves on this surface where OCCT takes them.
  bool has_pcurve = true;
  Handle(Geom2d_Curve) c2d, c2d1, c2d2;
  for (uint32_t j = 0; j < count; ++j) {
    const OrientedEdge& oe = edges[j];
    const Entity& ec = *oe.edge_curve;
    TopoDS_Edge edge = Edge(ec);
    const bool same = ec.Logical(4);
    edge.Orientation(oe.orientation == same ? TopAbs_FORWARD : TopAbs_REVERSED);
    bool is_seam = false;
    const Instance& curve_instance = entities_.Get(ec.Ref(3), ec.id());
    std::string_view curve_type = entities_.SimpleType(curve_instance);
    if (curve_type == "SURFACE_CURVE" || curve_type == "SEAM_CURVE" ||
        curve_type == "INTERSECTION_CURVE") {
      Entity sc = entities_.Simple(curve_instance);
      const Param& associated = sc.List(2);
      uint64_t pcurve_id = 0;
      int last = NextPCurve(entities_, sc, surface_id, 0, &pcurve_id);
      has_pcurve = pcurve_id != 0;
      if (is_plane) has_pcurve = false;
      // IsSeamCurve / IsLikeSeam: both associated pcurves on this surface, and the edge used
      // twice in this loop (a seam) or once (two faces on one closed surface).
      bool both_here = false;
      uint64_t pc1 = 0, pc2 = 0;
      if (associated.count == 2) {
        pc1 = AssociatedPCurve(entities_, sc, associated, 0);
        pc2 = AssociatedPCurve(entities_, sc, associated, 1);
        both_here = pc1 != 0 && pc2 != 0 && PCurveSurface(entities_, pc1) == surface_id &&
                    PCurveSurface(entities_, pc2) == surface_id;
      }
      int uses = 0;
      if (both_here) {
        for (uint32_t k = 0; k < count; ++k) {
          // StepToTopoDS compares the loop's oriented edges' elements with the edge curve.
          Entity oriented = entities_.Simple(entities_.Get(loop.RefItem(list, k), loop.id()));
          if (oriented.Ref(3) == ec.id()) ++uses;
        }
      }
      if (both_here && uses == 1) ThrowUnsupported(ec.Name() + ": a seam-like pair of pcurves");
      is_seam = curve_type == "SEAM_CURVE" || (both_here && uses == 2);
      if (is_seam) {
        if (associated.count < 2) ThrowUnsupported(sc.Name() + ": a seam with one pcurve");
        pc1 = AssociatedPCurve(entities_, sc, associated, 0);
        pc2 = AssociatedPCurve(entities_, sc, associated, 1);
        if (pc1 == 0 || pc2 == 0) {
          has_pcurve = false;
        } else {
          c2d1 = PCurve(pc1, sc.id(), conv_surface);
          c2d2 = PCurve(pc2, sc.id(), conv_surface);
          has_pcurve = !c2d1.IsNull() && !c2d2.IsNull();
        }
      } else if (has_pcurve) {
        while (last > 0) {
          Handle(Geom2d_Curve) made = PCurve(pcurve_id, sc.id(), conv_surface);
          if (made.IsNull()) {
            has_pcurve = false;
            break;
          }
          c2d = made;
          last = NextPCurve(entities_, sc, surface_id, last, &pcurve_id);
        }
      }
      if (!has_pcurve) compute_pcurve = true;
    } else {
      compute_pcurve = true;
      has_pcurve = false;
    }

    if (has_pcurve && is_seam) {
      const TopAbs_Orientation wire_o = forward_wire ? TopAbs_FORWARD : TopAbs_REVERSED;
      const TopAbs_Orientation face_o = same_sense ? TopAbs_FORWARD : TopAbs_REVERSED;
      const TopAbs_Orientation cumulated =
          TopAbs::Compose(TopAbs::Compose(edge.Orientation(), wire_o), face_o);
      int forward_pc = ShapeAnalysis_Curve().SelectForwardSeam(c2d1, c2d2);
      if (forward_pc == 0) ThrowUnsupported(ec.Name() + ": a seam curve OCCT cannot map");
      if (cumulated != TopAbs_FORWARD) forward_pc = 3 - forward_pc;
      if (forward_pc == 1)
        builder.UpdateEdge(edge, c2d1, c2d2, face, 0.);
      else
        builder.UpdateEdge(edge, c2d2, c2d1, face, 0.);
    } else if (has_pcurve) {
      if (c2d.IsNull()) ThrowUnsupported(ec.Name() + ": a pcurve OCCT cannot trim");
      builder.UpdateEdge(edge, c2d, face, 0.);
    }
    builder.Add(wire, edge);
  }
  wire.Closed(BRep_Tool::IsClosed(wire));
  Bind(loop_id, wire);

  if (!compute_pcurve) {
    for (TopoDS_Iterator it(wire); it.More(); it.Next()) {
      const TopoDS_Edge& edge = TopoDS::Edge(it.Value());
      ShapeFix_EdgeProjAux projector(face, edge);
      projector.Compute(preci);
      if (projector.IsFirstDone() && projector.IsLastDone()) {
        if (Abs(projector.FirstParam() - projector.LastParam()) < Precision::PConfusion()) continue;
        builder.Range(edge, face, projector.FirstParam(), projector.LastParam());
      } else {
        ShapeBuild_Edge().RemovePCurve(edge, face);
      }
    }
  }
  CheckPCurves(wire, face, is_plane, preci);
  return wire;
}

// Whether StepToTopoDS reverses a face's wires: a torus of negative major radius.
bool NegativeTorus(const Entities& entities, const Instance& surface) {
  const Instance* s = &surface;
  if (entities.SimpleType(*s) == "RECTANGULAR_TRIMMED_SURFACE")
    s = &entities.Get(entities.Simple(*s).Ref(1), s->id);
  std::string_view type = entities.SimpleType(*s);
  if (type != "TOROIDAL_SURFACE" && type != "DEGENERATE_TOROIDAL_SURFACE") return false;
  return entities.Simple(*s).Real(2) < 0;
}

bool IsBSplineSurface(const Entities& entities, const Instance& surface) {
  if (entities.IsComplex(surface)) return entities.HasPart(surface, "B_SPLINE_SURFACE");
  return entities.SimpleType(surface) == "B_SPLINE_SURFACE_WITH_KNOTS";
}

// StepToTopoDS_TranslateFace::Init.
TopoDS_Face ItemBuilder::Face(uint64_t id, uint64_t from) {
  auto found = bound_.find(id);
  if (found != bound_.end()) return TopoDS::Face(found->second);
  const Instance& instance = entities_.Get(id, from);
  std::string_view type = entities_.SimpleType(instance);
  if (type != "ADVANCED_FACE" && type != "FACE_SURFACE")
    ThrowUnsupported(entities_.Describe(instance) + " in a shell");
  // (name, bounds, face_geometry, same_sense)
  Entity fs = entities_.Simple(instance);
  const uint64_t surface_id = fs.Ref(2);
  const Instance& surface_instance = entities_.Get(surface_id, id);
  Handle(Geom_Surface) surface = geometry_.Surface(surface_id, id, units_);
  if (IsBSplineSurface(entities_, surface_instance)) {
    Handle(Geom_Surface) periodic = ShapeAlgo::AlgoContainer()->ConvertToPeriodic(surface);
    if (!periodic.IsNull()) surface = periodic;
  }
  const bool same_sense_face = fs.Logical(3);
  const bool same_sense =
      NegativeTorus(entities_, surface_instance) ? !same_sense_face : same_sense_face;
  TopoDS_Face face;
  BRep_Builder builder;
  builder.MakeFace(face, surface, Precision::Confusion());

  const Param& bounds = fs.List(1);
  const uint32_t nb_bounds = bounds.count;
  for (uint32_t i = 0; i < nb_bounds; ++i) {
    const Instance& bound_instance = entities_.Get(fs.RefItem(bounds, i), id);
    std::string_view bound_type = entities_.SimpleType(bound_instance);
    if (bound_type != "FACE_BOUND" && bound_type != "FACE_OUTER_BOUND")
      ThrowUnsupported(entities_.Describe(bound_instance) + " as a face bound");
    Entity bound = entities_.Simple(bound_instance);
    const Instance& loop = entities_.Get(bound.Ref(1), bound.id());
    std::string_view loop_type = entities_.SimpleType(loop);
    if (loop_type == "VERTEX_LOOP") {
      if (surface->IsKind(STANDARD_TYPE(Geom_SphericalSurface)) ||
          surface->IsKind(STANDARD_TYPE(Geom_BSplineSurface)) ||
          surface->IsKind(STANDARD_TYPE(Geom_SurfaceOfRevolution))) {
        if (nb_bounds == 1) {
          BRepBuilderAPI_MakeFace natural(surface, units_.precision);
          for (TopoDS_Iterator it(natural); it.More(); it.Next()) builder.Add(face, it.Value());
          continue;
        }
      }
      if (surface->IsKind(STANDARD_TYPE(Geom_ToroidalSurface))) continue;
      if (surface->IsKind(STANDARD_TYPE(Geom_Plane))) continue;
      builder.Add(face, VertexLoop(loop.id, bound.id()));
    } else if (loop_type == "EDGE_LOOP") {
      TopoDS_Wire wire = EdgeLoop(bound, face, surface, surface_id, same_sense);
      if (bound.Logical(2))
        wire.Orientation(same_sense ? TopAbs_FORWARD : TopAbs_REVERSED);
      else
        wire.Orientation(same_sense ? TopAbs_REVERSED : TopAbs_FORWARD);
      builder.Add(face, wire);
    } else {
      ThrowUnsupported(entities_.Describe(loop) + " as a face's loop");
    }
  }
  face.Orientation(same_sense_face ? TopAbs_FORWARD : TopAbs_REVERSED);
  Bind(id, face);
  item_->bound.emplace_back(id, face);
  return face;
}

// StepToTopoDS_TranslateShell::Init, for a CLOSED_SHELL, OPEN_SHELL or ORIENTED_CLOSED_SHELL
// (whose faces are those of its closed_shell_element).
TopoDS_Shape ItemBuilder::Shell(uint64_t id, uint64_t from) {
  auto found = bound_.find(id);
  if (found != bound_.end()) return found->second;
  const Instance& instance = entities_.Get(id, from);
  std::string_view type = entities_.SimpleType(instance);
  Entity shell_entity = entities_.Simple(instance);
  const Param* faces = nullptr;
  std::optional<Entity> element;
  if (type == "CLOSED_SHELL" || type == "OPEN_SHELL") {
    faces = &shell_entity.List(1);
  } else if (type == "ORIENTED_CLOSED_SHELL") {
    // (name, *, closed_shell_element, orientation)
    const Instance& inner = entities_.Get(shell_entity.Ref(2), id);
    if (entities_.SimpleType(inner) != "CLOSED_SHELL")
      ThrowUnsupported(entities_.Describe(inner) + " as a closed shell element");
    element = entities_.Simple(inner);
    faces = &element->List(1);
  } else {
    ThrowUnsupported(entities_.Describe(instance) + " as a shell");
  }
  const Entity& owner = element ? *element : shell_entity;
  BRep_Builder builder;
  TopoDS_Shell shell;
  builder.MakeShell(shell);
  for (uint32_t i = 0; i < faces->count; ++i)
    builder.Add(shell, Face(owner.RefItem(*faces, i), owner.id()));
  shell.Closed(BRep_Tool::IsClosed(shell));
  Bind(id, shell);
  item_->bound.emplace_back(id, shell);
  return shell;
}

TopoDS_Shape ItemBuilder::Build() {
  const Instance& instance = entities_.Get(item_->id, 0);
  std::string_view type = entities_.SimpleType(instance);
  Entity e = entities_.Simple(instance);
  BRep_Builder builder;
  TopoDS_Shape result;
  if (type == "MANIFOLD_SOLID_BREP" || type == "BREP_WITH_VOIDS") {
    // (name, outer[, voids])
    TopoDS_Shape outer = Shell(e.Ref(1), e.id());
    outer.Closed(Standard_True);
    TopoDS_Solid solid;
    builder.MakeSolid(solid);
    builder.Add(solid, outer);
    if (type == "BREP_WITH_VOIDS") {
      const Param& voids = e.List(2);
      for (uint32_t i = 0; i < voids.count; ++i) {
        const uint64_t void_id = e.RefItem(voids, i);
        const Instance& void_instance = entities_.Get(void_id, e.id());
        TopoDS_Shape shell = Shell(void_id, e.id());
        shell.Closed(Standard_True);
        if (entities_.SimpleType(void_instance) == "ORIENTED_CLOSED_SHELL" &&
            !entities_.Simple(void_instance).Logical(3))
          shell.Reverse();
        builder.Add(solid, shell);
      }
    }
    result = solid;
  } else if (type == "SHELL_BASED_SURFACE_MODEL") {
    // (name, sbsm_boundary)
    const Param& shells = e.List(1);
    TopoDS_Compound compound;
    builder.MakeCompound(compound);
    TopoDS_Shape last;
    for (uint32_t i = 0; i < shells.count; ++i) {
      const uint64_t shell_id = e.RefItem(shells, i);
      std::string_view shell_type = entities_.SimpleType(entities_.Get(shell_id, e.id()));
      if (shell_type != "OPEN_SHELL" && shell_type != "CLOSED_SHELL")
        ThrowUnsupported(entities_.Describe(entities_.Get(shell_id, e.id())) +
                         " in a shell based surface model");
      last = Shell(shell_id, e.id());
      last.Closed(shell_type == "CLOSED_SHELL");
      builder.Add(compound, last);
    }
    if (shells.count > 1)
      result = compound;
    else
      result = last;
    if (result.IsNull()) ThrowUnsupported(e.Name() + ": no shells");
  } else if (type == "GEOMETRIC_CURVE_SET" || type == "GEOMETRIC_SET") {
    result = CurveSet(e);
  } else {
    ThrowUnsupported(entities_.Describe(instance) + " as a B-rep");
  }
  // The vertices and edges as the tool left them bound (styled items may point at them).
  for (const auto& [id, shape] : bound_) {
    const TopAbs_ShapeEnum type = shape.ShapeType();
    if (type == TopAbs_VERTEX || type == TopAbs_EDGE) item_->bound.emplace_back(id, shape);
  }
  item_->curves.assign(curves_.begin(), curves_.end());
  return result;
}

// StepToTopoDS_Builder::Init(GeometricSet): a compound of an edge per curve, over the curve's
// whole range (BRepBuilderAPI_MakeEdge), and a vertex per point; an element met again in the set
// adds its shape again; an element OCCT cannot make an edge of is left out, as OCCT leaves it.
TopoDS_Shape ItemBuilder::CurveSet(const Entity& set) {
  // (name, elements)
  static const std::set<std::string_view> kComposite = {
      "COMPOSITE_CURVE", "COMPOSITE_CURVE_ON_SURFACE", "BOUNDARY_CURVE", "OUTER_BOUNDARY_CURVE"};
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  const Param& elements = set.List(1);
  std::unordered_map<uint64_t, TopoDS_Shape> done;
  for (uint32_t i = 0; i < elements.count; ++i) {
    const Param& element_param = set.Item(elements, i);
    if (element_param.kind != ParamKind::kRef)
      ThrowUnsupported(set.Name() + ": an element that is not an entity");
    const uint64_t element_id = element_param.value.ref;
    if (auto found = done.find(element_id); found != done.end()) {
      builder.Add(compound, found->second);
      continue;
    }
    const Instance& element = entities_.Get(element_id, set.id());
    std::string_view element_type = entities_.SimpleType(element);
    TopoDS_Shape shape;
    if (element_type == "CARTESIAN_POINT") {
      shape = BRepBuilderAPI_MakeVertex(geometry_.Point(element_id, set.id(), units_)).Vertex();
    } else if (kComposite.count(element_type) != 0) {
      ThrowUnsupported(entities_.Describe(element) + " in a geometric set");
    } else {
      // Geometry::Curve throws Unsupported for what is no curve (surfaces, placements, ...).
      Handle(Geom_Curve) curve = geometry_.Curve(element_id, set.id(), units_);
      BRepBuilderAPI_MakeEdge make(curve, curve->FirstParameter(), curve->LastParameter());
      if (make.IsDone()) shape = make.Edge();
    }
    if (shape.IsNull()) continue;
    builder.Add(compound, shape);
    done.emplace(element_id, shape);
    item_->bound.emplace_back(element_id, shape);
    item_->elements.push_back(element_id);
  }
  return compound;
}

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

void BuildItem(Geometry& geometry, BrepItem* item) {
  item->bound.clear();
  item->elements.clear();
  try {
    OCC_CATCH_SIGNALS
    ItemBuilder builder(geometry, item);
    item->raw = builder.Build();
  } catch (const Standard_Failure& failure) {
    ThrowUnsupported(geometry.entities().Describe(geometry.entities().Get(item->id, 0)) +
                     ": OCCT fails on it (" + failure.DynamicType()->Name() + ")");
  }
}

void PrepareOcct() {
  static std::once_flag once;
  std::call_once(once, [] {
    ShapeAlgo::Init();  // the algorithm container and Shape Healing's messages
    ShapeBuild::PlaneXOY();
    BRepLib::Plane();
  });
}

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
