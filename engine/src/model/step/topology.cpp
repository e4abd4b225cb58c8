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
#include <ShapeExtend_WireData.hxx>
#include <ShapeFix_Edge.hxx>
#include <ShapeFix_EdgeProjAux.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <TopAbs.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <TopoDS_Vertex.hxx>
#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

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

}  // namespace rdmesh::step
