#include "boundary/heal.h"

#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS.hxx>
#include <gp_Pnt2d.hxx>
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

// Edge ids by TShape: edges of one TShape share their parameters (edge_grids.cpp), so a grid
// point goes into all of them.
struct TShapeGroups {
  std::vector<const void*> tshape;  // per edge id - 1
  std::unordered_map<const void*, std::vector<int>> edges;
};

TShapeGroups GroupByTShape(const Model& model) {
  TShapeGroups groups;
  const int ne = model.edge_count();
  groups.tshape.resize(ne);
  for (int e = 1; e <= ne; ++e) {
    groups.tshape[e - 1] = model.edge(e).TShape().get();
    groups.edges[groups.tshape[e - 1]].push_back(e);
  }
  return groups;
}

// Inserts parameter t (with its curve point) into edge e's grid as its point k + 1. False when
// the edge has no curve or OCCT fails on it: the grid stays as it was.
bool InsertGridPoint(const Model& model, int e, int k, double t,
                     std::map<int, std::unique_ptr<Curve>>* curves, std::vector<EdgeGrid>* grids) {
  EdgeGrid& g = (*grids)[e - 1];
  try {
    auto& curve = (*curves)[e];
    if (!curve) curve = MakeEdgeCurve(TopoDS::Edge(model.edge(e).Oriented(TopAbs_FORWARD)));
    if (!curve) return false;
    Vec3 xyz = curve->Point(t);
    g.t.insert(g.t.begin() + k + 1, t);
    g.xyz.insert(g.xyz.begin() + k + 1, xyz);
    return true;
  } catch (const Standard_Failure&) {
    return false;
  }
}

}  // namespace

Status HealEdgeGrids(const Model& model, const FacePcurves& pcurves, const std::vector<int>& faces,
                     bool nurbs, int threads, Context* context, std::vector<EdgeGrid>* grids,
                     HealStats* stats) {
  HealStats local;
  if (!stats) stats = &local;
  *stats = HealStats();
  // Edges of one TShape share their parameters (edge_grids.cpp): split them together.
  TShapeGroups groups = GroupByTShape(model);
  const std::vector<const void*>& tshape = groups.tshape;
  auto& by_tshape = groups.edges;
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
        // Where OCCT fails, left as it is: the faces on it fail with the conflict as their reason.
        InsertGridPoint(model, e, k, 0.5 * (g.t[k] + g.t[k + 1]), &curves, grids);
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

std::vector<std::vector<SingularLine>> FaceSingularLines(const Model& model,
                                                         const FacePcurves& pcurves,
                                                         const std::vector<int>& faces, bool nurbs,
                                                         int threads) {
  std::vector<std::vector<SingularLine>> lines(model.face_count());
  if (nurbs) return lines;
  ParallelRunner(threads).For(0, static_cast<int>(faces.size()), [&](int i) {
    const int f = faces[i];
    lines[f - 1] = FindSingularLines(model.face(f), pcurves.Bounds(model, f));
  });
  return lines;
}

int PinSingularLines(const Model& model, const FacePcurves& pcurves,
                     const std::vector<std::vector<SingularLine>>& lines,
                     std::vector<EdgeGrid>* grids) {
  std::vector<std::pair<int, double>> pins;  // (edge id, parameter)
  for (int f = 1; f <= static_cast<int>(lines.size()); ++f) {
    if (lines[f - 1].empty()) continue;
    FaceLoops scratch;
    try {
      const FaceLoops& loops = pcurves.Loops(model, f, &scratch);
      for (const FaceWire& wire : loops.wires) {
        for (const WireEdge& we : wire.edges) {
          if (we.eid <= 0 || we.pcurve.IsNull()) continue;
          const EdgeGrid& g = (*grids)[we.eid - 1];
          if (g.degenerate || g.t.size() < 2) continue;
          for (const SingularLine& line : lines[f - 1]) {
            auto off = [&](double t) {
              const gp_Pnt2d p = we.pcurve->Value(t);
              return (line.axis == 0 ? p.Y() : p.X()) - line.at;
            };
            double before = off(g.t[0]);
            for (size_t k = 0; k + 1 < g.t.size(); ++k) {
              const double after = off(g.t[k + 1]);
              if (before * after < 0) {
                double a = g.t[k], z = g.t[k + 1];
                const double sign_a = before;
                for (int it = 0; it < 80; ++it) {
                  const double m = 0.5 * (a + z);
                  if (m == a || m == z) break;
                  (off(m) * sign_a > 0 ? a : z) = m;
                }
                pins.push_back({we.eid, 0.5 * (a + z)});
              }
              before = after;
            }
          }
        }
      }
    } catch (const Standard_Failure&) {
      // no pins for this face: its lines find no boundary nodes and are left out
    }
  }
  if (pins.empty()) return 0;
  const TShapeGroups groups = GroupByTShape(model);
  std::map<int, std::unique_ptr<Curve>> curves;
  int added = 0;
  for (const auto& [eid, t] : pins) {
    for (int e : groups.edges.at(groups.tshape[eid - 1])) {
      EdgeGrid& g = (*grids)[e - 1];
      if (g.degenerate || g.t.size() < 2) continue;
      const double range = std::fabs(g.t.back() - g.t.front());
      for (size_t k = 0; k + 1 < g.t.size(); ++k) {
        const double lo = std::min(g.t[k], g.t[k + 1]), hi = std::max(g.t[k], g.t[k + 1]);
        if (t < lo || t > hi) continue;
        if (t - lo > 1e-12 * range && hi - t > 1e-12 * range)
          added += InsertGridPoint(model, e, static_cast<int>(k), t, &curves, grids);
        break;
      }
    }
  }
  return added;
}

}  // namespace rdmesh
