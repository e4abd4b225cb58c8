#include "boundary/edge_grids.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRep_Tool.hxx>
#include <Extrema_GenLocateExtPS.hxx>
#include <Extrema_POnSurf.hxx>
#include <Geom2d_Curve.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_Surface.hxx>
#include <Precision.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "boundary/edge_discretize.h"
#include "boundary/pcurves.h"
#include "core/parallel.h"
#include "geometry/surface.h"
#include "geometry/surface_type.h"
#include "model/model.h"

namespace rdmesh {

namespace {

bool Developable(const TopoDS_Face& face) {
  SurfaceType type = FaceSurfaceType(face);
  return type == SurfaceType::kPlane || type == SurfaceType::kCylinder ||
         type == SurfaceType::kCone || type == SurfaceType::kExtrusion;
}

// Polyline samples that decide whether an edge is shorter than its tolerance.
constexpr int kLengthSamples = 8;
// Polyline samples of an edge's length in a face's perimeter (for its width).
constexpr int kWidthSamples = 16;
// Parameter steps at which an edge's curve is compared with its faces: a first look, and where
// that finds a gap, a finer one (a gap may peak over a few hundredths of the edge: gmsh_solid_56
// edge 94).
constexpr int kGapSamples = 8;
constexpr int kFineGapSamples = 64;
// Golden-section steps of CurveDistance: its interval shrinks by 0.618 a step.
constexpr int kCurveDistanceSteps = 20;
// A gap below this fraction of the deviation leaves the edge's budget as it is (well within the
// slack of a measured deviation; meshes stay the same where edges lie on their faces).
constexpr double kGapIgnored = 0.01;
// Where a gap leaves less, the chords still get this fraction of the deviation (a gap of up to
// 0.95 of it then puts the mesh up to 1.05 of it off the face, where the chords would need
// ever more segments to do better).
constexpr double kMinChordShare = 0.05;
// An edge whose tolerance is coarser than the deviation is discretised by its curve alone when
// that lies within this fraction of the deviation of its faces' surfaces (GridTolerance).
constexpr double kCurveOnSurface = 0.1;

// Parameter samples over an edge's range that look for where its curve passes through a vertex
// (ThroughVertexRange), and the golden-section steps that then close in on that point.
constexpr int kThroughSamples = 64;
constexpr int kThroughSteps = 60;

// The length of the polyline through `samples` + 1 even parameter steps of [f, l].
double PolylineLength(Curve& curve, double f, double l, int samples) {
  double length = 0;
  Vec3 prev = curve.Point(f);
  for (int k = 1; k <= samples; ++k) {
    Vec3 x = curve.Point(f + (l - f) * k / samples);
    length += Dist(prev, x);
    prev = x;
  }
  return length;
}

// The parameter in [a, b] where the curve comes nearest to x, where it has one minimum there
// (`steps` of golden section), and that distance.
double NearestParameter(Curve& curve, Vec3 x, double a, double b, int steps, double* distance) {
  constexpr double kInvPhi = 0.6180339887498949;
  double c = b - kInvPhi * (b - a), d = a + kInvPhi * (b - a);
  double fc = Dist(curve.Point(c), x), fd = Dist(curve.Point(d), x);
  for (int k = 0; k < steps; ++k) {
    if (fc < fd) {
      b = d, d = c, fd = fc;
      c = b - kInvPhi * (b - a), fc = Dist(curve.Point(c), x);
    } else {
      a = c, c = d, fc = fd;
      d = a + kInvPhi * (b - a), fd = Dist(curve.Point(d), x);
    }
  }
  *distance = std::min(fc, fd);
  return fc < fd ? c : d;
}

// The range an edge's grid covers: the edge's own, but where its curve passes through an end
// vertex inside the range (within the edge's tolerance), leaves that vertex's tolerance and
// comes back near it at the range's end, the grid ends where the curve passes through. A reader
// that finds the range by projecting the vertex onto the curve (STEP's EDGE_CURVE) can stop on
// the return's local minimum: KiCad's Bourns 8100 toroids have B-spline edges that run on 0.018
// mm past their vertex and back to 2.2e-4 of it, a loop that the face next to it does not have
// and the planar sliver beside it folds over. Closed edges (one vertex) keep their range.
void ThroughVertexRange(const TopoDS_Edge& edge, Curve& curve, double* f, double* l) {
  TopoDS_Vertex ends[2];
  TopExp::Vertices(edge, ends[0], ends[1]);
  if (ends[0].IsNull() || ends[1].IsNull() || ends[0].IsSame(ends[1])) return;
  const double tolerance = std::max(BRep_Tool::Tolerance(edge), Precision::Confusion());
  const double first = *f, last = *l;
  for (int end = 0; end < 2; ++end) {
    const gp_Pnt p = BRep_Tool::Pnt(ends[end]);
    const Vec3 vertex{p.X(), p.Y(), p.Z()};
    const double at = end == 0 ? first : last;
    if (!(Dist(curve.Point(at), vertex) > tolerance)) continue;
    double d[kThroughSamples + 1];
    auto param = [&](int k) { return first + (last - first) * k / kThroughSamples; };
    for (int k = 0; k <= kThroughSamples; ++k) d[k] = Dist(curve.Point(param(k)), vertex);
    double best = HUGE_VAL, through = at;
    int best_k = -1;
    for (int k = 1; k < kThroughSamples; ++k) {
      if (!(d[k] <= d[k - 1] && d[k] <= d[k + 1])) continue;
      double distance;
      const double t =
          NearestParameter(curve, vertex, param(k - 1), param(k + 1), kThroughSteps, &distance);
      if (distance < best) best = distance, through = t, best_k = k;
    }
    if (best_k < 0 || !(best <= tolerance)) continue;
    // Only a loop: a curve that stays within the vertex's tolerance past it keeps its range.
    const double reach = BRep_Tool::Tolerance(ends[end]);
    bool leaves = false;
    for (int k = end == 0 ? 1 : best_k + 1; k < (end == 0 ? best_k : kThroughSamples); ++k)
      leaves = leaves || d[k] > reach;
    if (!leaves) continue;
    (end == 0 ? *f : *l) = through;
  }
  if (!(*f < *l)) *f = first, *l = last;
}

// The two vertices of a collapsed (non-degenerate, shorter than tolerance) edge are one node:
// every grid names the smallest vertex id of its group and takes that vertex's point, so all
// faces share one node there and triangles across the collapsed edge vanish.
void MergeCollapsedEdgeVertices(const Model& model, std::vector<EdgeGrid>* grids) {
  const int nv = model.vertices.Extent();
  std::vector<int> parent(nv + 1);
  for (int v = 0; v <= nv; ++v) parent[v] = v;
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  bool any = false;
  for (int e = 1; e <= model.edge_count(); ++e) {
    const EdgeGrid& g = (*grids)[e - 1];
    if (!g.degenerate || g.first_vertex == g.last_vertex || BRep_Tool::Degenerated(model.edge(e)))
      continue;
    int a = find(g.first_vertex), b = find(g.last_vertex);
    if (a == b) continue;
    parent[std::max(a, b)] = std::min(a, b);
    any = true;
  }
  if (!any) return;
  for (EdgeGrid& g : *grids) {
    if (g.t.empty()) continue;
    g.first_vertex = find(g.first_vertex);
    g.last_vertex = find(g.last_vertex);
    auto point = [&](int v) {
      gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(model.vertices(v)));
      return Vec3{p.X(), p.Y(), p.Z()};
    };
    if (!g.xyz.empty()) g.xyz.front() = point(g.first_vertex), g.xyz.back() = point(g.last_vertex);
  }
}

// Per face id - 1: the largest tangential sagitta its edges' chords may have,
// narrow_face_fraction x area / perimeter (seams and degenerate edges are no boundary), or
// infinity where that is no tighter than the deviation (which bounds the whole sagitta) or
// where the face is narrower than the deviation.
std::vector<double> NarrowFaceLimits(const Model& model, const FacePcurves& pcurves,
                                     const GridCriteria& gc, const std::vector<int>& source,
                                     const ParallelRunner& runner) {
  const int nf = model.face_count(), ne = model.edge_count();
  std::vector<double> limit(nf, INFINITY);
  if (!(gc.max_deviation > 0) || !(gc.narrow_face_fraction > 0)) return limit;
  const double width = gc.max_deviation / gc.narrow_face_fraction;  // area / perimeter below it
  // Each TShape's length once, on its first edge id: a rigidly placed copy has that length.
  auto copied = [&](int e) {
    return source[e - 1] != e && RigidlyPlaced(model.edge(e)) &&
           RigidlyPlaced(model.edge(source[e - 1]));
  };
  std::vector<double> length(ne, 0.0);
  runner.For(1, ne + 1, [&](int e) {
    if (copied(e)) return;
    const TopoDS_Edge& edge = model.edge(e);
    if (BRep_Tool::Degenerated(edge)) return;
    try {
      double t0, t1;
      BRep_Tool::Range(edge, t0, t1);
      std::unique_ptr<Curve> curve = MakeEdgeCurve(edge);
      ThroughVertexRange(edge, *curve, &t0, &t1);
      length[e - 1] = PolylineLength(*curve, t0, t1, kWidthSamples);
    } catch (const Standard_Failure&) {
      length[e - 1] = 0;
    }
  });
  for (int e = 1; e <= ne; ++e)
    if (copied(e)) length[e - 1] = length[source[e - 1] - 1];
  runner.For(1, nf + 1, [&](int f) {
    const TopoDS_Face& face = model.face(f);
    double area = model.face_area[f - 1], perimeter = 0;
    if (const std::vector<int>* rim = pcurves.Rim(f)) {
      for (int e : *rim) perimeter += length[e - 1];
    } else {
      for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
        const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
        if (!BRep_Tool::IsClosed(edge, face)) perimeter += length[model.edges.FindIndex(edge) - 1];
      }
    }
    // Narrower than the deviation, a face is not resolved at all: it may stand as a line.
    if (perimeter > 0 && area / perimeter < width && area / perimeter >= gc.max_deviation)
      limit[f - 1] = gc.narrow_face_fraction * area / perimeter;
  });
  return limit;
}

// The faces beside an edge whose limit is below `max_sagitta`, as EdgeGrid sides: each holds
// its own surface evaluator and pcurve (one thread uses them).
std::vector<EdgeSide> NarrowSides(const Model& model, const FacePcurves& pcurves, int edge_id,
                                  const TopoDS_Edge& edge, const std::vector<int>& faces,
                                  const std::vector<double>& limit, double max_sagitta) {
  std::vector<EdgeSide> sides;
  for (int f : faces) {
    if (!(limit[f - 1] < max_sagitta)) continue;
    const TopoDS_Face& face = model.face(f);
    Handle(Geom2d_Curve) pcurve = pcurves.Find(f, face, edge_id, edge).curve;
    if (pcurve.IsNull()) continue;
    std::shared_ptr<Surface> surface = MakeFaceSurface(face, false, pcurves.Bounds(model, f));
    sides.push_back({[surface, pcurve](double t) {
                       gp_Pnt2d q = pcurve->Value(t);
                       return surface->Normal(q.X(), q.Y());
                     },
                     limit[f - 1]});
  }
  return sides;
}

// The distance from x to the curve over [a, b], where it has one minimum (golden section).
double CurveDistance(Curve& curve, Vec3 x, double a, double b) {
  const double ends = std::min(Dist(curve.Point(a), x), Dist(curve.Point(b), x));
  double inside;
  NearestParameter(curve, x, a, b, kCurveDistanceSteps, &inside);
  return std::min(ends, inside);
}

// How far the edge's 3D curve lies from one face's boundary, at `samples` + 1 even parameter steps:
// the largest distance of S(p(t)), the point of the face's pcurve (kept within the surface's own
// range: IntoSurfaceRange), from C(t) (`exact` false: the curve at the same parameter, no less than
// the next) or from the curve near t (`exact` true: between the neighbouring steps, which a pcurve
// whose parameter runs ahead of the curve's does not inflate). A face's mesh follows the curve (its
// boundary nodes are curve points), the face's trim follows the pcurve, so a chord's points lie up
// to this much farther from the face than from the curve: along the normal (off the surface) or
// within the surface (outside the trim: gmsh_solid_56 edge 94, 0.019 mm within its tolerance).
double FaceGap(const Adaptor3d_Surface& surface, const Geom2d_Curve& pcurve, double p0, double p1,
               Curve& curve, double first, double last, int samples, bool exact) {
  double gap = 0;
  auto param = [&](int k) { return first + (last - first) * std::clamp(k, 0, samples) / samples; };
  for (int k = 0; k <= samples; ++k) {
    const double t = param(k);
    // (A pcurve's range is the curve's on a same-parameter edge; else mapped linearly.)
    const double tp = p0 == first && p1 == last ? t : p0 + (p1 - p0) * k / samples;
    const gp_Pnt2d q = pcurve.Value(tp);
    const Vec2 uv = IntoSurfaceRange(surface, {q.X(), q.Y()});
    const gp_Pnt s = surface.Value(uv.x, uv.y);
    const Vec3 x{s.X(), s.Y(), s.Z()};
    const double d =
        exact ? CurveDistance(curve, x, param(k - 1), param(k + 1)) : Dist(curve.Point(t), x);
    if (std::isfinite(d)) gap = std::max(gap, d);
  }
  return gap;
}

// The largest FaceGap over the edge's faces that have a pcurve: a first look at kGapSamples
// steps, and on a face where that finds more than `ignored`, a finer one.
double EdgeFaceGap(const Model& model, const FacePcurves& pcurves, int edge_id,
                   const TopoDS_Edge& edge, Curve& curve, double first, double last,
                   const std::vector<int>& faces, double ignored) {
  double gap = 0;
  for (int f : faces) {
    const TopoDS_Face& face = model.face(f);
    const Pcurve found = pcurves.Find(f, face, edge_id, edge);
    const Handle(Geom2d_Curve)& pcurve = found.curve;
    const double p0 = found.first, p1 = found.last;
    if (pcurve.IsNull()) continue;
    // OCCT's adaptor (the face's placement applied): a handful of points, no tables to build.
    const BRepAdaptor_Surface surface(face, false);
    double g = FaceGap(surface, *pcurve, p0, p1, curve, first, last, kGapSamples, false);
    if (g > ignored)
      g = FaceGap(surface, *pcurve, p0, p1, curve, first, last, kFineGapSamples, true);
    gap = std::max(gap, g);
  }
  return gap;
}

// How far the edge's 3D curve lies from the surfaces of its faces (not from their pcurves): the
// largest distance to the nearest surface point, at kGapSamples + 1 even steps; infinity where a
// projection finds nothing. Only whether it is below `enough` decides, and its value below: so
// each sample first takes the surface point a local search finds from its pcurve's point (an
// upper bound of the nearest within the surface's bounds), and the global projection only where
// that is not below `enough`; the first sample at or above it ends the search.
double CurveSurfaceGap(const Model& model, const FacePcurves& pcurves, int edge_id,
                       const TopoDS_Edge& edge, Curve& curve, double first, double last,
                       const std::vector<int>& faces, double enough) {
  double gap = 0;
  for (int f : faces) {
    const TopoDS_Face& face = model.face(f);
    TopLoc_Location location;
    const Handle(Geom_Surface)& surface = BRep_Tool::Surface(face, location);
    if (surface.IsNull()) return INFINITY;
    const gp_Trsf to_surface = location.Transformation().Inverted();
    double u0, u1, v0, v1;
    surface->Bounds(u0, u1, v0, v1);
    const GeomAdaptor_Surface adaptor(surface);
    Extrema_GenLocateExtPS local(adaptor);
    const Pcurve found = pcurves.Find(f, face, edge_id, edge);
    // One global projector per face, as GeomAPI_ProjectPointOnSurf(point, surface) sets it up,
    // built on first need: its grid of surface points is built once, not for every point (a
    // B-spline's, over its whole range, was most of axom_boxed_sphere's edge stage).
    GeomAPI_ProjectPointOnSurf projection;
    bool projector = false;
    for (int k = 0; k <= kGapSamples; ++k) {
      const Vec3 x = curve.Point(first + (last - first) * k / kGapSamples);
      const gp_Pnt p = gp_Pnt(x.x, x.y, x.z).Transformed(to_surface);
      double d = INFINITY;
      if (!found.curve.IsNull()) {
        const gp_Pnt2d start =
            found.curve->Value(found.first + (found.last - found.first) * k / kGapSamples);
        local.Perform(p, start.X(), start.Y(), Standard_True);
        if (local.IsDone()) {
          double u, v;
          local.Point().Parameter(u, v);
          if (u >= u0 && u <= u1 && v >= v0 && v <= v1) d = p.Distance(adaptor.Value(u, v));
        }
      }
      if (!(d < enough)) {
        if (!projector) projection.Init(surface, u0, u1, v0, v1, Precision::Confusion());
        projector = true;
        projection.Perform(p);
        if (!projection.IsDone() || projection.NbPoints() == 0) return INFINITY;
        d = projection.LowerDistance();
      }
      gap = std::max(gap, d);
      if (!(gap < enough)) return gap;
    }
  }
  return gap;
}

// The tolerance an edge's grid heeds: its own, unless that is coarser than the deviation while
// its 3D curve lies on its faces' surfaces much closer (then that distance). A tolerance is what
// the edge's representations may disagree by; a STEP reader's repair can inflate it for pcurves
// that miss (NXP_MPL115A1, issue 35: 0.4 on fillet arcs 0.24 long whose curves lie on both
// faces), and the curve is still the edge: it is neither collapsed nor left coarse.
double GridTolerance(const Model& model, const FacePcurves& pcurves, int edge_id,
                     const TopoDS_Edge& edge, Curve& curve, double first, double last,
                     const std::vector<int>& faces, double max_deviation) {
  const double tolerance = BRep_Tool::Tolerance(edge);
  if (!(max_deviation > 0) || tolerance <= max_deviation) return tolerance;
  const double enough = kCurveOnSurface * max_deviation;
  const double gap =
      CurveSurfaceGap(model, pcurves, edge_id, edge, curve, first, last, faces, enough);
  return gap < enough ? std::max(gap, Precision::Confusion()) : tolerance;
}

}  // namespace

Status BuildEdgeGrids(const Model& model, const FacePcurves& pcurves, const GridCriteria& gc,
                      int threads, const std::vector<bool>& edge_needed, Context* context,
                      std::vector<EdgeGrid>* grids) {
  const int ne = model.edge_count();
  grids->assign(ne, EdgeGrid());
  // The first edge id of each TShape computes the parameters; the others copy them.
  std::vector<int> source(ne);
  std::unordered_map<const void*, int> first;
  for (int e = 1; e <= ne; ++e)
    source[e - 1] = first.emplace(model.edge(e).TShape().get(), e).first->second;
  const ParallelRunner runner(threads);
  // Per face id - 1, its representative's kind of surface (a placed copy has the same).
  std::vector<char> developable(model.face_count());
  runner.For(1, model.face_count() + 1, [&](int f) {
    if (model.face_representative[f - 1] == f) developable[f - 1] = Developable(model.face(f));
  });
  for (int f = 1; f <= model.face_count(); ++f)
    developable[f - 1] = developable[model.face_representative[f - 1] - 1];
  std::vector<double> factor(ne, 1.0);
  for (int e = 1; e <= ne; ++e)
    for (int f : model.edge_faces[e - 1])
      if (!developable[f - 1]) factor[e - 1] = gc.curved_face_factor;
  if (!gc.edge_scale.empty())
    for (int e = 1; e <= ne; ++e) factor[e - 1] *= gc.edge_scale[e - 1];
  for (int e = 1; e <= ne; ++e)
    factor[source[e - 1] - 1] = std::min(factor[source[e - 1] - 1], factor[e - 1]);

  const std::vector<double> narrow = NarrowFaceLimits(model, pcurves, gc, source, runner);

  auto build = [&](int e, bool params) {
    if (!edge_needed.empty() && !edge_needed[e - 1] && !params) return;
    EdgeGrid& g = (*grids)[e - 1];
    try {
      TopoDS_Edge edge = TopoDS::Edge(model.edge(e).Oriented(TopAbs_FORWARD));
      TopoDS_Vertex v0, v1;
      TopExp::Vertices(edge, v0, v1);
      g.first_vertex = model.vertices.FindIndex(v0);
      g.last_vertex = model.vertices.FindIndex(v1);
      double f, l;
      BRep_Tool::Range(edge, f, l);
      g.degenerate = BRep_Tool::Degenerated(edge);
      std::unique_ptr<Curve> curve = MakeEdgeCurve(edge);
      if (params) {
        if (g.degenerate || !curve) {
          g.t = {f, l};
        } else {
          EdgeGridCriteria c;
          c.max_sagitta = gc.max_deviation * factor[e - 1];
          // Where the curve lies off its faces, its chords get what the gap leaves of the
          // deviation. A gap at or above the deviation leaves nothing: the face cannot meet it
          // (face_mesher.cpp reports the B-rep), and the grid keeps its budget.
          const double ignored = kGapIgnored * gc.max_deviation;
          const std::vector<int>& faces = model.edge_faces[e - 1];
          const double gap =
              ignored > 0 ? EdgeFaceGap(model, pcurves, e, edge, *curve, f, l, faces, ignored) : 0;
          if (gap > ignored && gap < gc.max_deviation)
            c.max_sagitta = std::min(
                c.max_sagitta, std::max(gc.max_deviation - gap, kMinChordShare * gc.max_deviation));
          c.rd_tolerance = gc.rd_tolerance;
          c.max_length = gc.max_length;
          const double tolerance =
              GridTolerance(model, pcurves, e, edge, *curve, f, l, faces, gc.max_deviation);
          c.min_length = std::max(gc.min_length, tolerance);
          // The gap and the tolerance above look at the whole range, the grid at its part up to
          // where the curve passes through its vertices.
          double a = f, b = l;
          ThroughVertexRange(edge, *curve, &a, &b);
          // A closed edge, or one whose ends nearly meet, starts from three segments: its
          // end-to-end chord says nothing about its length.
          Vec3 start = curve->Point(a), end = curve->Point(b), mid = curve->Point(0.5 * (a + b));
          bool loops = g.first_vertex == g.last_vertex || Dist(start, end) < 0.5 * Dist(start, mid);
          c.min_segments = loops ? 3 : 1;
          c.sides = NarrowSides(model, pcurves, e, edge, faces, narrow, c.max_sagitta);
          g.t = DiscretizeCurve(*curve, a, b, c, context);
          // An edge no longer than its own tolerance is a point in 3D: it collapses to one node,
          // and faces see it as a pole segment (its pcurve may still span the face).
          if (PolylineLength(*curve, a, b, kLengthSamples) <= tolerance)
            g.t = {a, b}, g.degenerate = true;
        }
      } else {
        g.t = (*grids)[source[e - 1] - 1].t;
      }
      g.xyz.clear();
      for (double t : g.t) g.xyz.push_back(curve ? curve->Point(t) : Vec3{});
    } catch (const Standard_Failure&) {
      g.t.clear();  // the faces on this edge fail with "edge N has no grid"
    }
  };
  std::vector<int> sources, copies;
  for (int e = 1; e <= ne; ++e) (source[e - 1] == e ? sources : copies).push_back(e);
  runner.For(0, static_cast<int>(sources.size()), [&](int i) {
    if (context && context->ShouldStop()) return;
    build(sources[i], true);
  });
  runner.For(0, static_cast<int>(copies.size()), [&](int i) {
    if (context && context->ShouldStop()) return;
    build(copies[i], false);
  });
  if (context && context->ShouldStop()) return context->StopStatus();
  MergeCollapsedEdgeVertices(model, grids);
  return Status::Ok();
}

}  // namespace rdmesh
