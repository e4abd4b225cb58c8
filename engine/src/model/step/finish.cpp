// OCC_CATCH_SIGNALS below must turn faults inside OCCT's modelling classes into exceptions, in
// TBB's worker threads too, when the caller has OCCT's fault handlers installed (model_readers'
// ScopedOcctFaultHandlers); it has to be defined before any OCCT header.
#define OCC_CONVERT_SIGNALS 1

#include "model/step/finish.h"

#include <Adaptor3d_CurveOnSurface.hxx>
#include <BRepLib.hxx>
#include <BRep_Builder.hxx>
#include <BRep_TEdge.hxx>
#include <BRep_TVertex.hxx>
#include <BRep_Tool.hxx>
#include <Geom2dAdaptor_Curve.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <ShapeAnalysis_Edge.hxx>
#include <ShapeBuild_ReShape.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopTools_MapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Vertex.hxx>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <unordered_map>
#include <vector>

namespace rdmesh::step {

namespace {

// Number of points ShapeFix::SameParameter checks an edge on a plane at.
constexpr int kPlaneControlPoints = 23;

double Tolerance(const TopoDS_Vertex& vertex) { return BRep_Tool::Tolerance(vertex); }

void SetVertexTolerance(const TopoDS_Vertex& vertex, double tolerance) {
  Handle(BRep_TVertex)::DownCast(vertex.TShape())->Tolerance(tolerance);
}

// The plane under a face's surface (possibly trimmed), or null.
Handle(Geom_Plane) PlaneOf(const TopoDS_Face& face) {
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face);
  Handle(Geom_Plane) plane = Handle(Geom_Plane)::DownCast(surface);
  if (plane.IsNull()) {
    Handle(Geom_RectangularTrimmedSurface) trimmed =
        Handle(Geom_RectangularTrimmedSurface)::DownCast(surface);
    if (!trimmed.IsNull()) plane = Handle(Geom_Plane)::DownCast(trimmed->BasisSurface());
  }
  return plane;
}

// The largest squared distance between an edge's 3D curve and its pcurve on a plane face at
// ShapeFix::SameParameter's control points; -1 where it checks nothing.
double PlaneDeviation(const TopoDS_Edge& edge, const TopoDS_Face& face,
                      const Handle(Geom_Plane) & plane) {
  double f, l;
  Handle(Geom_Curve) curve = BRep_Tool::Curve(edge, f, l);
  if (curve.IsNull()) return -1.;
  Handle(Geom2d_Curve) c2d = BRep_Tool::CurveOnSurface(edge, face, f, l);
  if (c2d.IsNull()) return -1.;
  Handle(GeomAdaptor_Surface) surface = new GeomAdaptor_Surface(plane);
  Handle(Geom2dAdaptor_Curve) pcurve = new Geom2dAdaptor_Curve(c2d, f, l);
  Adaptor3d_CurveOnSurface on_surface(pcurve, surface);
  double worst = -1.;
  for (int i = 0; i < kPlaneControlPoints; ++i) {
    const double par = (f * (kPlaneControlPoints - 1 - i) + l * i) / (kPlaneControlPoints - 1);
    worst = std::max(worst, curve->Value(par).SquareDistance(on_surface.Value(par)));
  }
  return worst;
}

}  // namespace

bool SameParameterInParallel(const TopoDS_Shape& shape, const ParallelRunner& runner) {
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  std::vector<TopoDS_Edge> occurrences;
  for (TopExp_Explorer ex(shape, TopAbs_EDGE); ex.More(); ex.Next()) {
    const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
    const int index = edge_faces.FindIndex(edge);
    if (index == 0 || edge_faces(index).IsEmpty()) return false;  // an edge of no face
    // ShapeFix would reparameterise such an edge (BRepLib::SameParameter) or its ranges
    // (TempSameRange), where OCCT's order matters.
    if (!BRep_Tool::SameRange(edge)) return false;
    if (!BRep_Tool::Degenerated(edge) && !BRep_Tool::SameParameter(edge)) return false;
    occurrences.push_back(edge);
  }
  const int nb_edges = edge_faces.Extent();
  // Deviations of every edge on each of its faces, and what its vertices need.
  std::vector<std::vector<double>> deviations(nb_edges);
  std::vector<std::array<double, 2>> vertex_needs(nb_edges, {0., 0.});
  std::atomic<bool> failed{false};
  runner.For(
      0, nb_edges,
      [&](int i) {
        const TopoDS_Edge edge = TopoDS::Edge(edge_faces.FindKey(i + 1));
        if (BRep_Tool::Degenerated(edge)) return;
        try {
          OCC_CATCH_SIGNALS
          ShapeAnalysis_Edge sae;
          for (const TopoDS_Shape& face : edge_faces(i + 1)) {
            double deviation = 0.;
            sae.CheckSameParameter(edge, TopoDS::Face(face), deviation);
            deviations[i].push_back(deviation);
          }
          double t1 = 0., t2 = 0.;
          sae.CheckVertexTolerance(edge, t1, t2);
          vertex_needs[i] = {t1, t2};
        } catch (...) {
          failed = true;
        }
      },
      Partition::kOnePerTask);
  if (failed) return false;
  // Replayed in ShapeFix::SameParameter's order: every edge as often as the explorer meets it.
  BRep_Builder builder;
  ShapeAnalysis_Edge sae;
  for (const TopoDS_Edge& edge : occurrences) {
    if (BRep_Tool::Degenerated(edge)) {
      builder.SameParameter(edge, Standard_True);
      continue;
    }
    const int index = edge_faces.FindIndex(edge) - 1;
    const TopoDS_Vertex v1 = sae.FirstVertex(edge), v2 = sae.LastVertex(edge);
    // The needs were measured on the edge as MapShapesAndAncestors keyed it.
    const TopoDS_Edge& key = TopoDS::Edge(edge_faces.FindKey(index + 1));
    const bool flipped = sae.FirstVertex(key).IsSame(v2) && !v1.IsSame(v2);
    const double need1 = vertex_needs[index][flipped ? 1 : 0];
    const double need2 = vertex_needs[index][flipped ? 0 : 1];
    for (double deviation : deviations[index]) {
      const double edge_tolerance = BRep_Tool::Tolerance(edge);
      if (!v1.IsNull()) SetVertexTolerance(v1, std::max(deviation, Tolerance(v1)));
      if (!v2.IsNull()) SetVertexTolerance(v2, std::max(deviation, Tolerance(v2)));
      if (deviation > edge_tolerance) {
        builder.UpdateEdge(edge, deviation);
        // ShapeFix_Edge::FixVertexTolerance(edge): the vertices cover the curves' ends.
        const double tolerance = BRep_Tool::Tolerance(edge);
        const double t1 = std::max(need1, tolerance), t2 = std::max(need2, tolerance);
        if (!v1.IsNull() && !v2.IsNull() && (t1 > Tolerance(v1) || t2 > Tolerance(v2))) {
          builder.UpdateVertex(v1, t1);
          builder.UpdateVertex(v2, t2);
        }
      }
    }
  }
  // Edges on planes (no pcurves stored): their tolerance covers the 3D curve's distance to the
  // plane's projection of it.
  std::vector<std::pair<TopoDS_Edge, TopoDS_Face>> on_planes;
  for (TopExp_Explorer f(shape, TopAbs_FACE); f.More(); f.Next()) {
    const TopoDS_Face& face = TopoDS::Face(f.Current());
    if (PlaneOf(face).IsNull()) continue;
    for (TopExp_Explorer e(face, TopAbs_EDGE); e.More(); e.Next())
      on_planes.emplace_back(TopoDS::Edge(e.Current()), face);
  }
  std::vector<double> plane_deviation(on_planes.size(), -1.);
  runner.For(
      0, static_cast<int>(on_planes.size()),
      [&](int i) {
        try {
          OCC_CATCH_SIGNALS
          plane_deviation[i] =
              PlaneDeviation(on_planes[i].first, on_planes[i].second, PlaneOf(on_planes[i].second));
        } catch (...) {
          failed = true;
        }
      },
      Partition::kAuto);
  if (failed) return false;  // nothing half-done: the first loop cannot throw
  for (size_t i = 0; i < on_planes.size(); ++i) {
    const TopoDS_Edge& edge = on_planes[i].first;
    if (plane_deviation[i] < 0.) continue;
    const double tol0 = BRep_Tool::Tolerance(edge);
    if (!(plane_deviation[i] > tol0 * tol0)) continue;
    const double tolerance = 1.00005 * std::sqrt(plane_deviation[i]);
    if (tolerance < tol0) continue;
    builder.UpdateEdge(edge, tolerance);
    for (TopoDS_Iterator v(edge); v.More(); v.Next())
      builder.UpdateVertex(TopoDS::Vertex(v.Value()), tolerance);
  }
  return true;
}

void FixVertexTolerancesInParallel(const TopoDS_Shape& shape, const Handle(ShapeFix_Edge) & tool,
                                   const ParallelRunner& runner) {
  std::vector<std::pair<TopoDS_Edge, TopoDS_Face>> pairs;
  int faces = 0;
  for (TopExp_Explorer f(shape, TopAbs_FACE); f.More(); f.Next()) {
    ++faces;
    const TopoDS_Face& face = TopoDS::Face(f.Current());
    for (TopExp_Explorer e(face, TopAbs_EDGE); e.More(); e.Next())
      pairs.emplace_back(TopoDS::Edge(e.Current()), face);
  }
  if (faces <= 1) return;  // ShapeFix_Shape checks vertices of shapes of several faces only
  // What each edge's vertices need on each face (ShapeAnalysis_Edge::CheckVertexTolerance).
  std::vector<std::array<double, 2>> needs(pairs.size(), {0., 0.});
  std::vector<char> checked(pairs.size(), 0);
  runner.For(
      0, static_cast<int>(pairs.size()),
      [&](int i) {
        try {
          OCC_CATCH_SIGNALS
          ShapeAnalysis_Edge sae;
          double t1 = 0., t2 = 0.;
          sae.CheckVertexTolerance(pairs[i].first, pairs[i].second, t1, t2);
          if (sae.Status(ShapeExtend_FAIL1)) return;  // no vertices: nothing to fix
          needs[i] = {t1, t2};
          checked[i] = 1;
        } catch (...) {
        }
      },
      Partition::kAuto);
  // Replayed in order, with OCCT's own call wherever a vertex needs more: its copies, through the
  // context, are those of ShapeFix_Shape.
  std::unordered_map<const void*, double> current;  // vertex TShape -> tolerance so far
  auto tolerance_of = [&](const TopoDS_Vertex& vertex) {
    auto found = current.find(vertex.TShape().get());
    return found != current.end() ? found->second : BRep_Tool::Tolerance(vertex);
  };
  ShapeAnalysis_Edge sae;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const TopoDS_Edge& edge = pairs[i].first;
    const TopoDS_Vertex v1 = sae.FirstVertex(edge), v2 = sae.LastVertex(edge);
    if (checked[i]) {
      if (!(needs[i][0] > tolerance_of(v1) || needs[i][1] > tolerance_of(v2))) continue;
    }
    // Unchecked pairs (an exception, a missing curve) go to OCCT's call as they are.
    tool->FixVertexTolerance(edge, pairs[i].second);
    if (!v1.IsNull())
      current[v1.TShape().get()] = BRep_Tool::Tolerance(TopoDS::Vertex(tool->Context()->Apply(v1)));
    if (!v2.IsNull())
      current[v2.TShape().get()] = BRep_Tool::Tolerance(TopoDS::Vertex(tool->Context()->Apply(v2)));
  }
}

namespace {

// The (edge, face, face) triples EncodeRegularity codes, in its order; false when an edge comes
// twice (then OCCT's own call runs).
bool RegularityTriples(const TopoDS_Shape& shape, TopTools_MapOfShape* done,
                       TopTools_MapOfShape* edges,
                       std::vector<std::array<TopoDS_Shape, 3>>* triples) {
  TopoDS_Shape unlocated = shape;
  unlocated.Location(TopLoc_Location());
  if (!done->Add(unlocated)) return true;
  if (unlocated.ShapeType() == TopAbs_COMPOUND || unlocated.ShapeType() == TopAbs_COMPSOLID) {
    for (TopoDS_Iterator it(unlocated); it.More(); it.Next())
      if (!RegularityTriples(it.Value(), done, edges, triples)) return false;
    return true;
  }
  TopTools_IndexedDataMapOfShapeListOfShape map;
  TopExp::MapShapesAndAncestors(unlocated, TopAbs_EDGE, TopAbs_FACE, map);
  for (int i = 1; i <= map.Extent(); ++i) {
    const TopoDS_Edge& edge = TopoDS::Edge(map.FindKey(i));
    TopoDS_Face f1, f2;
    bool found = false;
    for (TopTools_ListOfShape::Iterator it(map(i)); it.More() && !found; it.Next()) {
      if (f1.IsNull()) {
        f1 = TopoDS::Face(it.Value());
      } else if (!f1.IsSame(it.Value())) {
        found = true;
        f2 = TopoDS::Face(it.Value());
      }
    }
    if (!found && !f1.IsNull()) {  // a seam
      for (TopExp_Explorer ex(f1, TopAbs_EDGE); ex.More() && !found; ex.Next()) {
        if (edge.IsSame(ex.Current()) && edge.Orientation() != ex.Current().Orientation()) {
          found = true;
          f2 = f1;
        }
      }
    }
    if (!found) continue;
    if (!edges->Add(edge.Located(TopLoc_Location()).Oriented(TopAbs_FORWARD))) return false;
    triples->push_back({edge, f1, f2});
  }
  return true;
}

}  // namespace

void EncodeRegularityInParallel(const TopoDS_Shape& shape, double angle,
                                const ParallelRunner& runner) {
  TopTools_MapOfShape done, edges;
  std::vector<std::array<TopoDS_Shape, 3>> triples;
  if (!RegularityTriples(shape, &done, &edges, &triples)) {
    BRepLib::EncodeRegularity(shape, angle);
    return;
  }
  runner.For(
      0, static_cast<int>(triples.size()),
      [&](int i) {
        TopoDS_Edge edge = TopoDS::Edge(triples[i][0]);
        try {
          OCC_CATCH_SIGNALS
          BRepLib::EncodeRegularity(edge, TopoDS::Face(triples[i][1]), TopoDS::Face(triples[i][2]),
                                    angle);
        } catch (...) {
          // OCCT's loop stops at an exception; the continuity stays uncoded here too
        }
      },
      Partition::kAuto);
}

}  // namespace rdmesh::step
