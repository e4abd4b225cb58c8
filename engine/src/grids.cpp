#include "grids.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <BRep_Tool.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <unordered_map>

#include "edge_grid.h"
#include "model.h"
#include "model_info.h"
#include "surface.h"

namespace rdmesh {

namespace {

bool Developable(const TopoDS_Face& face) {
  SurfaceType type = FaceSurfaceType(face);
  return type == SurfaceType::kPlane || type == SurfaceType::kCylinder ||
         type == SurfaceType::kCone || type == SurfaceType::kExtrusion;
}

}  // namespace

Status BuildEdgeGrids(const Model& model, const GridCriteria& gc, int threads,
                      const std::vector<bool>& edge_needed, Context* context,
                      std::vector<EdgeGrid>* grids) {
  const int ne = model.edge_count();
  grids->assign(ne, EdgeGrid());
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(model.shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  // The first edge id of each TShape computes the parameters; the others copy them.
  std::vector<int> source(ne);
  std::unordered_map<const void*, int> first;
  std::vector<double> factor(ne, 1.0);
  for (int e = 1; e <= ne; ++e) {
    const TopoDS_Edge& edge = model.edge(e);
    source[e - 1] = first.emplace(edge.TShape().get(), e).first->second;
    const TopTools_ListOfShape* faces = edge_faces.Seek(edge);
    if (faces)
      for (const TopoDS_Shape& f : *faces)
        if (!Developable(TopoDS::Face(f))) factor[e - 1] = gc.curved_face_factor;
  }
  for (int e = 1; e <= ne; ++e)
    factor[source[e - 1] - 1] = std::min(factor[source[e - 1] - 1], factor[e - 1]);

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
          c.rd_tolerance = gc.rd_tolerance;
          c.max_length = gc.max_length;
          c.min_length = std::max(gc.min_length, BRep_Tool::Tolerance(edge));
          c.min_segments = g.first_vertex == g.last_vertex ? 3 : 1;
          g.t = DiscretizeCurve(*curve, f, l, c);
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
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(0, static_cast<int>(sources.size()), [&](int i) {
      if (context && context->ShouldStop()) return;
      build(sources[i], true);
    });
    tbb::parallel_for(0, static_cast<int>(copies.size()), [&](int i) { build(copies[i], false); });
  });
  if (context && context->ShouldStop()) return context->StopStatus();
  return Status::Ok();
}

}  // namespace rdmesh
