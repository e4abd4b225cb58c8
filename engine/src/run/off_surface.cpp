#include "run/off_surface.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <cmath>
#include <memory>

#include "boundary/pcurves.h"
#include "core/parallel.h"
#include "face/refine_constants.h"
#include "geometry/offset_surface.h"
#include "geometry/surface.h"
#include "geometry/surface_type.h"
#include "model/model.h"

namespace rdmesh {

namespace {

// BendSide's samples: the centres of a grid of this many cells a side over the face's (u,v)
// bounds.
constexpr int kBendGrid = 6;
// A curve is checked for its bend, and against its faces, at this many steps along it.
constexpr int kCurveSamples = 24;
// Its direction away from its bend may turn between steps by at most acos(this) (an inflection
// flips it).
constexpr double kCurveTurn = 0.5;
// The edges at a vertex must move it the same way, within acos(this).
constexpr double kSameWay = 0.999;

bool CircleOf(const TopoDS_Edge& edge, Circle* circle) {
  BRepAdaptor_Curve curve(edge);
  if (curve.GetType() != GeomAbs_Circle) return false;
  const gp_Circ c = curve.Circle();
  circle->center = {c.Location().X(), c.Location().Y(), c.Location().Z()};
  circle->axis = {c.Axis().Direction().X(), c.Axis().Direction().Y(), c.Axis().Direction().Z()};
  return true;
}

// The unit direction away from the circle's axis at p, within its plane.
Vec3 Radial(const Circle& c, Vec3 p) {
  const Vec3 d = p - c.center;
  return Normalized(d - Dot(d, c.axis) * c.axis);
}

}  // namespace

std::vector<int8_t> FaceBendSides(const Model& model, const FacePcurves& pcurves,
                                  const std::vector<int>& faces, bool nurbs, int threads) {
  std::vector<int8_t> sides(model.face_count(), 0);
  const ParallelRunner runner(threads);
  runner.For(0, static_cast<int>(faces.size()), [&](int i) {
    const int f = faces[i];
    try {
      if (FaceSurfaceType(model.face(f)) == SurfaceType::kPlane) return;
      const UvBounds b = pcurves.Bounds(model, f);
      std::unique_ptr<Surface> surface = MakeFaceSurface(model.face(f), nurbs, b);
      std::vector<Vec2> samples;
      for (int k = 0; k < kBendGrid; ++k)
        for (int j = 0; j < kBendGrid; ++j)
          samples.push_back({b.umin + (k + 0.5) / kBendGrid * (b.umax - b.umin),
                             b.vmin + (j + 0.5) / kBendGrid * (b.vmax - b.vmin)});
      sides[f - 1] = static_cast<int8_t>(BendSide(*surface, samples, kBendStep * (b.umax - b.umin),
                                                  kBendStep * (b.vmax - b.vmin), kBendTolerance));
    } catch (const Standard_Failure&) {
      sides[f - 1] = 0;  // stays on its surface
    }
  });
  return sides;
}

namespace {

// The axis of a cylinder or cone face, as a circle's (centre: a point on it).
bool AxisOf(const TopoDS_Face& face, Circle* axis) {
  BRepAdaptor_Surface surface(face);
  gp_Ax1 ax;
  if (surface.GetType() == GeomAbs_Cylinder)
    ax = surface.Cylinder().Axis();
  else if (surface.GetType() == GeomAbs_Cone)
    ax = surface.Cone().Axis();
  else
    return false;
  axis->center = {ax.Location().X(), ax.Location().Y(), ax.Location().Z()};
  axis->axis = {ax.Direction().X(), ax.Direction().Y(), ax.Direction().Z()};
  return true;
}

// The curve's curvature vector at t (toward its centre of curvature, of length 1 / radius);
// zero where the derivative vanishes.
gp_Vec CurvatureVector(const BRepAdaptor_Curve& curve, double t) {
  gp_Pnt p;
  gp_Vec d1, d2;
  curve.D2(t, p, d1, d2);
  const double l2 = d1.SquareMagnitude();
  if (!(l2 > 0)) return gp_Vec(0, 0, 0);
  return (d2 - d1 * (d2.Dot(d1) / l2)) / l2;
}

// The unit direction away from the centre of curvature (the principal normal, reversed) of a
// curvature vector k: where a chord's middle falls short of the arc. Zero where it does not bend.
Vec3 AwayFrom(const gp_Vec& k, double scale) {
  const double norm = k.Magnitude();
  if (!(norm * scale > 1e-6)) return {};
  return {-k.X() / norm, -k.Y() / norm, -k.Z() / norm};
}

Vec3 AwayFromBend(const BRepAdaptor_Curve& curve, double t, double scale) {
  return AwayFrom(CurvatureVector(curve, t), scale);
}

// Where the edge's nodes move, as a unit direction at the curve's point `at` (parameter t).
Vec3 MoveDirection(const MovedEdge& m, const BRepAdaptor_Curve& curve, double t, Vec3 at,
                   double scale) {
  return m.kind == MovedEdge::kCurve ? AwayFromBend(curve, t, scale) : Radial(m.axis, at);
}

// Whether edge `e` is a straight line whose faces are all planes.
bool LineBetweenPlanes(const Model& model, int e) {
  if (BRepAdaptor_Curve(model.edge(e)).GetType() != GeomAbs_Line) return false;
  for (int id : model.edge_faces[e - 1])
    if (FaceSurfaceType(model.face(id)) != SurfaceType::kPlane) return false;
  return true;
}

bool SameAxis(const Circle& a, const Circle& b, double scale) {
  if (Norm(Cross(a.axis, b.axis)) > 1e-9) return false;
  const Vec3 d = b.center - a.center;
  return Norm(d - Dot(d, a.axis) * a.axis) <= 1e-9 * scale;
}

}  // namespace

double MovedEdgeScale(const MovedEdge& edge, double deviation, double distance) {
  const double band = 2 * distance;
  if (edge.kind != MovedEdge::kCircle && edge.kind != MovedEdge::kCurve) return band;
  if (!(edge.radius > 0) || !(deviation > 0) || std::isinf(edge.radius)) return band;
  return band * edge.radius / (edge.radius + distance * deviation);
}

std::vector<MovedEdge> OffsetEdges(const Model& model, const FacePcurves& pcurves,
                                   const std::vector<int8_t>& bend_sides,
                                   const std::vector<bool>& edge_needed) {
  const int ne = model.edge_count();
  const double scale = std::max(1.0, model.info.diagonal);
  std::vector<MovedEdge> candidate(ne);
  for (int e = 1; e <= ne; ++e) {
    if (!edge_needed.empty() && !edge_needed[e - 1]) continue;
    try {
      const TopoDS_Edge& edge = model.edge(e);
      if (BRep_Tool::Degenerated(edge) || model.edge_faces[e - 1].empty()) continue;
      MovedEdge m;
      BRepAdaptor_Curve curve(edge);
      const bool line = curve.GetType() == GeomAbs_Line;
      if (line) {
        // A ruling of cylinders or cones about one axis: it moves with them, away from it. A
        // plane beside them (a fillet's tangent plane) takes the move too: its triangles along
        // the line then leave it by no more than the line does.
        m.kind = MovedEdge::kRuling;
        bool first = true;
        for (int id : model.edge_faces[e - 1]) {
          if (FaceSurfaceType(model.face(id)) == SurfaceType::kPlane) continue;
          Circle axis;
          if (!AxisOf(model.face(id), &axis) || (!first && !SameAxis(m.axis, axis, scale))) {
            m.kind = MovedEdge::kNone;
            break;
          }
          if (first) m.axis = axis, first = false;
        }
        if (first) m.kind = MovedEdge::kNone;  // planes only: nothing to move with
      } else if (CircleOf(edge, &m.axis)) {
        m.kind = MovedEdge::kCircle;
        m.radius = curve.Circle().Radius();
      } else {
        // Another curve that bends one way along its length (no inflection, nowhere straight):
        // its nodes move away from its centre of curvature.
        m.kind = MovedEdge::kCurve;
        double f, l;
        BRep_Tool::Range(edge, f, l);
        Vec3 last;
        m.radius = HUGE_VAL;
        for (int k = 0; k <= kCurveSamples && m.kind == MovedEdge::kCurve; ++k) {
          const gp_Vec bend = CurvatureVector(curve, f + (l - f) * k / kCurveSamples);
          const Vec3 away = AwayFrom(bend, scale);
          if (Norm(away) == 0 || (k > 0 && Dot(away, last) < kCurveTurn)) m.kind = MovedEdge::kNone;
          last = away;
          const double curvature = bend.Magnitude();
          m.radius = std::min(m.radius, curvature > 0 ? 1 / curvature : HUGE_VAL);
        }
      }
      if (m.kind == MovedEdge::kNone) continue;
      bool ok = true;
      for (int id : model.edge_faces[e - 1]) {
        const TopoDS_Face& face = model.face(id);
        // A plane's curve bends within it, and the move stays in it; a ruling leaves a plane
        // by the offset at most, which its deviation allows.
        if (FaceSurfaceType(face) == SurfaceType::kPlane) continue;
        if (bend_sides[id - 1] == 0) {
          ok = false;
          break;
        }
        // The face's offset must move the edge's middle away from the axis, as its nodes go.
        double pf, pl;
        Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, face, pf, pl);
        if (pcurve.IsNull()) {
          ok = false;
          break;
        }
        std::unique_ptr<Surface> surface = MakeFaceSurface(face, false, pcurves.Bounds(model, id));
        for (int k = 1; k < kCurveSamples && ok; ++k) {
          const double t = pf + (pl - pf) * k / kCurveSamples;
          const gp_Pnt2d q = pcurve->Value(t);
          const Vec3 at = surface->Point(q.X(), q.Y());
          ok = bend_sides[id - 1] *
                   Dot(surface->Normal(q.X(), q.Y()), MoveDirection(m, curve, t, at, scale)) >
               0.5;
        }
        if (!ok) break;
      }
      if (ok) candidate[e - 1] = m;
    } catch (const Standard_Failure&) {
      candidate[e - 1] = MovedEdge();
    }
  }
  // A vertex moves when every edge at it is a candidate that moves it the same way, an edge of
  // one face, or a line between planes (whose segment from the moved vertex then leaves them by
  // the offset at most).
  const int nv = model.vertices.Extent();
  std::vector<Vec3> way(nv + 1);  // the first candidate's direction at the vertex
  std::vector<uint8_t> blocked(nv + 1, 0);
  for (int e = 1; e <= ne; ++e) {
    TopoDS_Vertex ends[2];
    TopExp::Vertices(model.edge(e), ends[0], ends[1]);
    double f = 0, l = 0;
    if (candidate[e - 1].kind != MovedEdge::kNone) BRep_Tool::Range(model.edge(e), f, l);
    for (int end = 0; end < 2; ++end) {
      const TopoDS_Vertex& v = ends[end];
      const int id = v.IsNull() ? 0 : model.vertices.FindIndex(v);
      if (id == 0) continue;
      if (candidate[e - 1].kind == MovedEdge::kNone) {
        if (model.edge_faces[e - 1].size() > 1 && !LineBetweenPlanes(model, e)) blocked[id] = 1;
        continue;
      }
      const gp_Pnt p = BRep_Tool::Pnt(v);
      const Vec3 d = MoveDirection(candidate[e - 1], BRepAdaptor_Curve(model.edge(e)),
                                   end == 0 ? f : l, {p.X(), p.Y(), p.Z()}, scale);
      if (Norm(way[id]) == 0)
        way[id] = d;
      else if (!(Dot(way[id], d) >= kSameWay))
        blocked[id] = 1;
    }
  }
  std::vector<MovedEdge> moved(ne);
  for (int e = 1; e <= ne; ++e) {
    if (candidate[e - 1].kind == MovedEdge::kNone) continue;
    TopoDS_Vertex ends[2];
    TopExp::Vertices(model.edge(e), ends[0], ends[1]);
    bool free = true;
    for (const TopoDS_Vertex& v : ends) {
      const int id = v.IsNull() ? 0 : model.vertices.FindIndex(v);
      free = free && id > 0 && !blocked[id];
    }
    if (free) moved[e - 1] = candidate[e - 1];
  }
  return moved;
}

void MoveEdgeGrids(const Model& model, const std::vector<MovedEdge>& edges, double distance,
                   std::vector<EdgeGrid>* grids, std::map<int, Vec3>* vertices) {
  const double scale = std::max(1.0, model.info.diagonal);
  for (int e = 1; e <= model.edge_count(); ++e) {
    EdgeGrid& g = (*grids)[e - 1];
    const MovedEdge& m = edges[e - 1];
    if (m.kind == MovedEdge::kNone || g.xyz.empty()) continue;
    const BRepAdaptor_Curve curve(model.edge(e));
    g.moved = distance;
    for (size_t k = 0; k < g.xyz.size(); ++k)
      g.xyz[k] = g.xyz[k] + distance * MoveDirection(m, curve, g.t[k], g.xyz[k], scale);
    for (int end = 0; end < 2; ++end) {
      const int v = end == 0 ? g.first_vertex : g.last_vertex;
      const gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(model.vertices(v)));
      const Vec3 at{p.X(), p.Y(), p.Z()};
      (*vertices)[v] =
          at + distance * MoveDirection(m, curve, end == 0 ? g.t.front() : g.t.back(), at, scale);
    }
    g.xyz.front() = (*vertices)[g.first_vertex], g.xyz.back() = (*vertices)[g.last_vertex];
  }
}

}  // namespace rdmesh
