// OCC_CATCH_SIGNALS below must turn faults inside OCCT's modelling classes into exceptions, in
// TBB's worker threads too, when the caller has OCCT's fault handlers installed (model_readers'
// ScopedOcctFaultHandlers); it has to be defined before any OCCT header.
#define OCC_CONVERT_SIGNALS 1

#include "model/step/finish.h"

#include <Adaptor3d_CurveOnSurface.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepClass3d_SolidExplorer.hxx>
#include <BRepLib.hxx>
#include <BRep_Builder.hxx>
#include <BRep_TEdge.hxx>
#include <BRep_TVertex.hxx>
#include <BRep_Tool.hxx>
#include <Geom2dAdaptor_Curve.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <IntCurvesFace_Intersector.hxx>
#include <NCollection_IndexedDataMap.hxx>
#include <Precision.hxx>
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
#include <TopTools_ShapeMapHasher.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <TopoDS_Vertex.hxx>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <gp.hxx>
#include <gp_Lin.hxx>
#include <math_BullardGenerator.hxx>
#include <memory>
#include <numeric>
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

// How ShapeFix_Shell::FixFaceOrientation and ShapeFix_Shell::Perform (faces not fixed) see a
// shell. kChanges: they may change something (a face repeated, INTERNAL or without edges, faces
// in several connected parts, an edge used more than twice or twice the same way). Otherwise
// they rebuild nothing: kClosed, every edge but degenerated ones used twice; kOpen, some once.
enum class ShellState { kChanges, kClosed, kOpen };

ShellState ShellStateOf(const TopoDS_Shape& shell) {
  std::vector<TopoDS_Shape> faces;
  TopTools_MapOfShape distinct;
  for (TopoDS_Iterator it(shell); it.More(); it.Next()) {
    const TopoDS_Shape& face = it.Value();
    if (face.ShapeType() != TopAbs_FACE || !distinct.Add(face)) return ShellState::kChanges;
    if (face.Orientation() != TopAbs_FORWARD && face.Orientation() != TopAbs_REVERSED)
      return ShellState::kChanges;
    faces.push_back(face);
  }
  // One face is a shell GetShells takes apart and builds again.
  if (faces.size() < 2) return ShellState::kChanges;
  struct Uses {
    int count = 0;
    int face[2] = {0, 0};
    TopAbs_Orientation orientation[2] = {TopAbs_FORWARD, TopAbs_FORWARD};
  };
  NCollection_IndexedDataMap<TopoDS_Shape, Uses, TopTools_ShapeMapHasher> uses;
  for (size_t f = 0; f < faces.size(); ++f) {
    bool any = false;
    for (TopExp_Explorer ex(faces[f], TopAbs_EDGE); ex.More(); ex.Next()) {
      const TopoDS_Shape& edge = ex.Current();
      if (edge.Orientation() != TopAbs_FORWARD && edge.Orientation() != TopAbs_REVERSED)
        return ShellState::kChanges;
      any = true;
      int index = uses.FindIndex(edge);
      if (index == 0) index = uses.Add(edge, Uses());
      Uses& use = uses.ChangeFromIndex(index);
      if (use.count == 2) return ShellState::kChanges;
      use.face[use.count] = static_cast<int>(f);
      use.orientation[use.count] = edge.Orientation();
      ++use.count;
    }
    if (!any) return ShellState::kChanges;
  }
  std::vector<int> parent(faces.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&parent](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  bool open = false, bounded = false;
  for (int i = 1; i <= uses.Extent(); ++i) {
    const Uses& use = uses(i);
    const bool degenerated = BRep_Tool::Degenerated(TopoDS::Edge(uses.FindKey(i)));
    if (!degenerated) bounded = true;
    if (use.count == 1) {
      open = open || !degenerated;
      continue;
    }
    if (use.orientation[0] == use.orientation[1]) return ShellState::kChanges;
    parent[root(use.face[0])] = root(use.face[1]);
  }
  for (size_t f = 1; f < faces.size(); ++f)
    if (root(static_cast<int>(f)) != root(0)) return ShellState::kChanges;
  // Without edges that are not degenerated OCCT finds the shell neither closed nor open.
  if (!bounded) return ShellState::kChanges;
  return open ? ShellState::kOpen : ShellState::kClosed;
}

// The normal BRepClass3d_SClassifier shoots its ray against (its FaceNormal): the surface's,
// reversed on a reversed face; false where it vanishes.
bool ProbeNormal(const TopoDS_Face& face, double u, double v, gp_Dir* normal) {
  gp_Pnt point;
  gp_Vec d1u, d1v;
  BRep_Tool::Surface(face)->D1(u, v, point, d1u, d1v);
  gp_Vec n = d1u.Crossed(d1v);
  if (n.Magnitude() <= gp::Resolution()) return false;
  n.Normalize();
  normal->SetXYZ(n.XYZ());
  if (face.Orientation() == TopAbs_REVERSED) normal->Reverse();
  return true;
}

// ShapeFix_Solid::SolidFromShell's test: whether the solid bounded by `shell` holds the infinite
// point (then OCCT reverses the shell), as BRepClass3d_SolidClassifier::PerformInfinitePoint
// answers it: the same probes from the same random sequence, against each face's
// IntCurvesFace_Intersector in the same order. Its explorer builds those one face after the
// other, with a box and a tree of edges the test does not read; here they are built in
// parallel, on separate faces. An exception counts as no, as in SolidFromShell.
bool InsideOut(const TopoDS_Shape& shell, const ParallelRunner& runner) {
  try {
    OCC_CATCH_SIGNALS
    BRep_Builder builder;
    TopoDS_Solid solid;
    builder.MakeSolid(solid);
    builder.Add(solid, shell);
    std::vector<TopoDS_Face> faces;
    for (TopExp_Explorer ex(solid, TopAbs_FACE); ex.More(); ex.Next())
      faces.push_back(TopoDS::Face(ex.Current()));
    const int count = static_cast<int>(faces.size());
    if (count == 0) return true;  // the classifier's solid without faces: IN
    // B-spline and Bezier surfaces and curves compute their resolution once and keep it
    // (Geom_BSplineSurface::Resolution): asked here, as the intersectors of faces on other than
    // elementary surfaces ask, before faces that share such a surface or basis curve are built
    // together.
    for (const TopoDS_Face& face : faces) {
      BRepAdaptor_Surface surface(face, Standard_False);
      const GeomAbs_SurfaceType type = surface.GetType();
      if (type == GeomAbs_Plane || type == GeomAbs_Cylinder || type == GeomAbs_Cone ||
          type == GeomAbs_Sphere || type == GeomAbs_Torus)
        continue;
      surface.UResolution(1.);
      surface.VResolution(1.);
    }
    std::vector<std::unique_ptr<IntCurvesFace_Intersector>> intersectors(faces.size());
    std::atomic<bool> failed{false};
    runner.For(
        0, count,
        [&](int i) {
          try {
            OCC_CATCH_SIGNALS
            intersectors[i] = std::make_unique<IntCurvesFace_Intersector>(
                faces[i], Precision::Confusion(), Standard_True, Standard_False);
          } catch (...) {
            failed = true;
          }
        },
        Partition::kOnePerTask);
    if (failed) return false;
    constexpr int kProbesPerFace = 10;
    math_BullardGenerator random;
    for (int attempt = 0; attempt < kProbesPerFace; ++attempt) {
      for (const TopoDS_Face& face : faces) {
        double param = 0.1 + 0.8 * random.NextReal();
        gp_Pnt point;
        double u = 0., v = 0.;
        gp_Dir normal;
        if (!BRepClass3d_SolidExplorer::FindAPointInTheFace(face, point, u, v, param) ||
            !ProbeNormal(face, u, v, &normal))
          continue;
        const gp_Lin line(point, -normal);
        double nearest = RealLast();
        TopAbs_State state = TopAbs_OUT;
        IntCurveSurface_TransitionOnCurve transition = IntCurveSurface_Tangent;
        for (const auto& intersector : intersectors) {
          intersector->Perform(line, -RealLast(), nearest);
          if (!intersector->IsDone() || intersector->NbPnt() == 0) continue;
          int first = 1;
          for (int i = 2; i <= intersector->NbPnt(); ++i)
            if (intersector->WParameter(i) < intersector->WParameter(first)) first = i;
          nearest = intersector->WParameter(first);
          state = intersector->State(first);
          transition = intersector->Transition(first);
        }
        if (state == TopAbs_IN) {
          if (transition == IntCurveSurface_Out) return true;
          if (transition == IntCurveSurface_In) return false;
        }
      }
    }
    return false;  // ON
  } catch (const Standard_Failure&) {
    return false;
  }
}

// The shells ShapeFix_Shape's stages would meet in `shape`, with their states, and the shells
// of its solids; false where those stages would do more than look at them (a face fixed, a solid
// of several shells or of an open one, a sub-shape met twice or located).
bool CollectShells(const TopoDS_Shape& shape, TopTools_MapOfShape* seen,
                   std::vector<std::pair<TopoDS_Shape, ShellState>>* shells,
                   std::vector<TopoDS_Shape>* solid_shells) {
  if (!shape.Location().IsIdentity() || !seen->Add(shape)) return false;
  switch (shape.ShapeType()) {
    case TopAbs_COMPOUND:
    case TopAbs_COMPSOLID:
      for (TopoDS_Iterator it(shape); it.More(); it.Next())
        if (!CollectShells(it.Value(), seen, shells, solid_shells)) return false;
      return true;
    case TopAbs_SOLID: {
      TopoDS_Iterator it(shape);
      if (!it.More()) return false;
      const TopoDS_Shape shell = it.Value();
      it.Next();
      if (it.More() || shell.ShapeType() != TopAbs_SHELL || !shell.Location().IsIdentity())
        return false;
      if (ShellStateOf(shell) != ShellState::kClosed) return false;
      solid_shells->push_back(shell);
      return true;
    }
    case TopAbs_SHELL: {
      const ShellState state = ShellStateOf(shape);
      if (state == ShellState::kChanges) return false;
      shells->emplace_back(shape, state);
      return true;
    }
    default:
      return false;
  }
}

}  // namespace

bool ShellAndSolidStagesWithoutChange(const TopoDS_Shape& shape, const ParallelRunner& runner) {
  TopTools_MapOfShape seen;
  std::vector<std::pair<TopoDS_Shape, ShellState>> shells;
  std::vector<TopoDS_Shape> solid_shells;
  if (shape.IsNull() || !CollectShells(shape, &seen, &shells, &solid_shells)) return false;
  for (const TopoDS_Shape& shell : solid_shells)
    if (InsideOut(shell, runner)) return false;
  // ShapeFix_Shell::Perform clears the flag of a shell with free edges; ShapeFix_Solid sets it
  // on the shell of a solid it found closed.
  for (auto& [shell, state] : shells)
    if (state == ShellState::kOpen && shell.Closed()) shell.Closed(false);
  for (TopoDS_Shape& shell : solid_shells) shell.Closed(true);
  return true;
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
