#include "boundary/heal.h"

#include <BRep_Tool.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS.hxx>
#include <map>
#include <set>
#include <unordered_map>

#include "boundary/face_domain.h"
#include "core/parallel.h"
#include "geometry/surface.h"
#include "model/model.h"

namespace rdmesh {

namespace {

constexpr int kMaxRounds = 12;

// Grid segments [t[k], t[k+1]] to split, as (edge id, k), for the conflicts of one face.
std::vector<std::pair<int, int>> SplitsForFace(const Model& model, const FacePcurves& pcurves,
                                               int face_id, const std::vector<EdgeGrid>& grids,
                                               bool nurbs, const Context* context) {
  std::vector<std::pair<int, int>> splits;
  try {
    std::unique_ptr<Surface> surface =
        MakeFaceSurface(model.face(face_id), nurbs, pcurves.Bounds(model, face_id));
    FaceDomain domain;
    if (!BuildFaceDomain(model, pcurves, face_id, grids, *surface, &domain).ok()) return splits;
    for (const DomainConflict& c : FindConflicts(domain, context)) {
      for (int s : {c.a, c.b}) {
        if (s < 0 || domain.segment_edge[s] == 0 || domain.segment_splittable[s]) continue;
        splits.push_back({domain.segment_edge[s], domain.segment_grid_index[s]});
      }
    }
  } catch (const Standard_Failure&) {
    splits.clear();  // the face fails with the OCCT reason when it is meshed
  }
  return splits;
}

}  // namespace

Status HealEdgeGrids(const Model& model, const FacePcurves& pcurves, const std::vector<int>& faces,
                     bool nurbs, int threads, Context* context, std::vector<EdgeGrid>* grids,
                     HealStats* stats) {
  HealStats local;
  if (!stats) stats = &local;
  *stats = HealStats();
  // Edges of one TShape share their parameters (edge_grids.cpp): split them together.
  const int ne = model.edge_count();
  std::unordered_map<const void*, std::vector<int>> by_tshape;
  std::vector<const void*> tshape(ne);
  for (int e = 1; e <= ne; ++e) {
    tshape[e - 1] = model.edge(e).TShape().get();
    by_tshape[tshape[e - 1]].push_back(e);
  }
  // Per face, the TShapes of its edges: after a round, only faces on a split edge are checked.
  std::vector<std::vector<const void*>> face_tshapes(faces.size());
  for (size_t i = 0; i < faces.size(); ++i)
    for (int e : model.face_edges[faces[i] - 1]) face_tshapes[i].push_back(tshape[e - 1]);
  std::vector<int> todo(faces.size());  // indices into `faces`
  for (size_t i = 0; i < faces.size(); ++i) todo[i] = static_cast<int>(i);
  const ParallelRunner runner(threads);
  for (int round = 0; round < kMaxRounds && !todo.empty(); ++round) {
    if (context && context->ShouldStop()) return context->StopStatus();
    std::vector<std::vector<std::pair<int, int>>> found(todo.size());
    runner.For(0, static_cast<int>(todo.size()), [&](int i) {
      if (context && context->ShouldStop()) return;
      found[i] = SplitsForFace(model, pcurves, faces[todo[i]], *grids, nurbs, context);
    });
    if (context && context->ShouldStop()) return context->StopStatus();
    ++stats->rounds;
    // (TShape's first edge id, k), split from the largest k down so indices stay valid.
    std::set<std::pair<int, int>, std::greater<>> splits;
    for (size_t i = 0; i < todo.size(); ++i) {
      for (const auto& [eid, k] : found[i]) {
        const EdgeGrid& g = (*grids)[eid - 1];
        if (k < 0 || k + 1 >= static_cast<int>(g.t.size())) continue;
        const double range = std::fabs(g.t.back() - g.t.front());
        if (std::fabs(g.t[k + 1] - g.t[k]) <= 1e-9 * range) continue;  // cannot get finer
        splits.insert({by_tshape[tshape[eid - 1]].front(), k});
      }
    }
    if (splits.empty()) break;
    std::map<int, std::unique_ptr<Curve>> curves;
    std::set<const void*> touched;
    for (const auto& [first, k] : splits) {
      touched.insert(tshape[first - 1]);
      for (int e : by_tshape[tshape[first - 1]]) {
        EdgeGrid& g = (*grids)[e - 1];
        if (g.degenerate || k + 1 >= static_cast<int>(g.t.size())) continue;
        try {
          auto& curve = curves[e];
          if (!curve) curve = MakeEdgeCurve(TopoDS::Edge(model.edge(e).Oriented(TopAbs_FORWARD)));
          if (!curve) continue;
          const double t = 0.5 * (g.t[k] + g.t[k + 1]);
          Vec3 xyz = curve->Point(t);
          g.t.insert(g.t.begin() + k + 1, t);
          g.xyz.insert(g.xyz.begin() + k + 1, xyz);
        } catch (const Standard_Failure&) {
          // left as it is: the faces on it fail with the conflict as their reason
        }
      }
      ++stats->splits;
    }
    std::vector<int> next;
    for (size_t i = 0; i < faces.size(); ++i)
      for (const void* t : face_tshapes[i])
        if (touched.count(t)) {
          next.push_back(static_cast<int>(i));
          break;
        }
    todo = std::move(next);
  }
  return Status::Ok();
}

}  // namespace rdmesh
