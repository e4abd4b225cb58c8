#include "run/off_surface.h"

#include <BRepAdaptor_Curve.hxx>
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

struct Circle {
  Vec3 center, axis;
};

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

std::vector<uint8_t> OffsetCircles(const Model& model, const FacePcurves& pcurves,
                                   const std::vector<int8_t>& bend_sides,
                                   const std::vector<bool>& edge_needed) {
  const int ne = model.edge_count();
  std::vector<uint8_t> candidate(ne, 0);
  for (int e = 1; e <= ne; ++e) {
    if (!edge_needed.empty() && !edge_needed[e - 1]) continue;
    try {
      const TopoDS_Edge& edge = model.edge(e);
      Circle circle;
      if (BRep_Tool::Degenerated(edge) || !CircleOf(edge, &circle)) continue;
      double f, l;
      BRep_Tool::Range(edge, f, l);
      bool ok = !model.edge_faces[e - 1].empty();
      for (int id : model.edge_faces[e - 1]) {
        if (!ok) break;
        const TopoDS_Face& face = model.face(id);
        if (FaceSurfaceType(face) == SurfaceType::kPlane) continue;  // the move stays in it
        if (bend_sides[id - 1] == 0) {
          ok = false;
          break;
        }
        // The face's offset must move the circle's middle away from the axis, as its nodes go.
        double pf, pl;
        Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, face, pf, pl);
        if (pcurve.IsNull()) {
          ok = false;
          break;
        }
        const gp_Pnt2d q = pcurve->Value(0.5 * (pf + pl));
        std::unique_ptr<Surface> surface = MakeFaceSurface(face, false, pcurves.Bounds(model, id));
        const Vec3 at = surface->Point(q.X(), q.Y());
        ok = bend_sides[id - 1] * Dot(surface->Normal(q.X(), q.Y()), Radial(circle, at)) > 0.5;
      }
      candidate[e - 1] = ok;
    } catch (const Standard_Failure&) {
      candidate[e - 1] = 0;
    }
  }
  // Each vertex of a candidate: at it, that circle and edges of one face only.
  std::vector<int> circle_at(model.vertices.Extent() + 1, 0);   // the one candidate, -1 more
  std::vector<uint8_t> shared(model.vertices.Extent() + 1, 0);  // an edge of several faces
  for (int e = 1; e <= ne; ++e) {
    TopoDS_Vertex ends[2];
    TopExp::Vertices(model.edge(e), ends[0], ends[1]);
    for (const TopoDS_Vertex& v : ends) {
      const int id = v.IsNull() ? 0 : model.vertices.FindIndex(v);
      if (id == 0) continue;
      if (candidate[e - 1])
        circle_at[id] = circle_at[id] == 0 || circle_at[id] == e ? e : -1;
      else if (model.edge_faces[e - 1].size() > 1)
        shared[id] = 1;
    }
  }
  std::vector<uint8_t> circles(ne, 0);
  for (int e = 1; e <= ne; ++e) {
    if (!candidate[e - 1]) continue;
    TopoDS_Vertex ends[2];
    TopExp::Vertices(model.edge(e), ends[0], ends[1]);
    bool own = true;
    for (const TopoDS_Vertex& v : ends) {
      const int id = v.IsNull() ? 0 : model.vertices.FindIndex(v);
      own = own && id > 0 && circle_at[id] == e && !shared[id];
    }
    circles[e - 1] = own;
  }
  return circles;
}

void MoveCircleGrids(const Model& model, const std::vector<uint8_t>& circles, double distance,
                     std::vector<EdgeGrid>* grids, std::map<int, Vec3>* vertices) {
  for (int e = 1; e <= model.edge_count(); ++e) {
    EdgeGrid& g = (*grids)[e - 1];
    Circle circle;
    if (!circles[e - 1] || g.xyz.empty() || !CircleOf(model.edge(e), &circle)) continue;
    for (Vec3& p : g.xyz) p = p + distance * Radial(circle, p);
    for (int v : {g.first_vertex, g.last_vertex}) {
      const gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(model.vertices(v)));
      const Vec3 at{p.X(), p.Y(), p.Z()};
      (*vertices)[v] = at + distance * Radial(circle, at);
    }
    g.xyz.front() = (*vertices)[g.first_vertex], g.xyz.back() = (*vertices)[g.last_vertex];
  }
}

}  // namespace rdmesh
