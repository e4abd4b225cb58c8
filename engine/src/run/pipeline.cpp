#include "run/pipeline.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "assembly/assemble.h"
#include "assembly/edge_lines.h"
#include "boundary/edge_grids.h"
#include "boundary/face_domain.h"
#include "boundary/heal.h"
#include "boundary/pcurves.h"
#include "core/parallel.h"
#include "face/face_mesher.h"
#include "model/model.h"
#include "run/off_surface.h"

namespace rdmesh {

namespace {

// What an off-surface run decides before its faces (run/off_surface.h); empty otherwise.
struct OffSurfacePlan {
  std::vector<int8_t> bend_sides;      // per face id - 1
  std::vector<MovedEdge> edges;        // per edge id - 1: moved with their faces
  std::map<int, Vec3> moved_vertices;  // vertex id -> its point, moved with its circle
};

using Clock = std::chrono::steady_clock;

// Representative face mesh cap: far above any sane request, it only stops runaway refinement.
constexpr int64_t kFaceTriangleCap = 20'000'000;

// The faces and edges a run works on.
struct Selection {
  std::vector<bool> wanted;       // per face id - 1: asked for (all faces when none is named)
  std::vector<bool> mesh_it;      // per face id - 1: meshed (representatives of the wanted faces)
  std::vector<bool> edge_needed;  // per edge id - 1: bounds a wanted or meshed face
  std::vector<int> todo;          // the face ids to mesh, ascending
  int64_t wanted_count = 0;
};

// Per-face reports to the context (may be null): the face, then the progress of the kFaces stage.
class FaceReporter {
 public:
  FaceReporter(Context* context, int64_t total) : context_(context), total_(total) {}
  void Finished(const FaceMesh& face) {
    if (!context_) return;
    context_->ReportFace(face);
    context_->ReportProgress({Progress::Stage::kFaces, ++done_, total_});
  }

 private:
  Context* context_;
  const int64_t total_;
  std::atomic<int64_t> done_{0};
};

bool Stopped(const Context* context) { return context && context->ShouldStop(); }

// A face that is not part of the result.
FaceMesh SkippedFace(const Model& model, int f) {
  FaceMesh skipped;
  skipped.face_id = f;
  skipped.status = FaceStatus::kSkipped;
  skipped.reason = "not requested";
  skipped.exact_area = model.face_area[f - 1];
  return skipped;
}

// 1. Select faces: the wanted ones, the representatives meshed for them, and their edges.
Result<Selection> SelectFaces(const Model& model, const MeshOptions& options) {
  const int nf = model.face_count();
  Selection sel;
  sel.wanted.assign(nf, options.face_ids.empty());
  for (int id : options.face_ids) {
    if (id > nf)
      return Status(StatusCode::kInvalidArgument,
                    "face id " + std::to_string(id) + " is out of range 1.." + std::to_string(nf));
    sel.wanted[id - 1] = true;
  }
  // Off the surface, every face is meshed for itself: a placed copy rebuilds its boundary from
  // its own edges, which would bring the nodes of its seams back onto the surface.
  sel.mesh_it.assign(nf, false);
  for (int f = 1; f <= nf; ++f)
    if (sel.wanted[f - 1])
      sel.mesh_it[options.off_surface ? f - 1 : model.face_representative[f - 1] - 1] = true;
  sel.edge_needed.assign(model.edge_count(), false);
  for (int f = 1; f <= nf; ++f) {
    if (!sel.wanted[f - 1] && !sel.mesh_it[f - 1]) continue;
    for (int e : model.face_edges[f - 1]) sel.edge_needed[e - 1] = true;
  }
  for (int f = 1; f <= nf; ++f)
    if (sel.mesh_it[f - 1]) sel.todo.push_back(f);
  sel.wanted_count = std::count(sel.wanted.begin(), sel.wanted.end(), true);
  return sel;
}

// 3. Edge grids: every needed edge discretised once.
Status MakeEdgeGrids(const Model& model, const FacePcurves& pcurves, const MeshOptions& options,
                     double deviation, const Selection& sel, const OffSurfacePlan& plan,
                     Context* context, std::vector<EdgeGrid>* grids) {
  if (context) context->ReportProgress({Progress::Stage::kEdges, 0, model.edge_count()});
  GridCriteria gc;
  gc.max_deviation = deviation;
  gc.rd_tolerance = options.rd_tolerance / 5;  // faces carry ~5x the RD of their edges
  gc.max_length = options.max_edge_length;
  gc.min_length = options.min_edge_length;
  if (!plan.edges.empty()) {
    gc.edge_scale.assign(model.edge_count(), 1.0);
    for (int e = 1; e <= model.edge_count(); ++e)
      if (plan.edges[e - 1].kind == MovedEdge::kCircle ||
          plan.edges[e - 1].kind == MovedEdge::kCurve)
        gc.edge_scale[e - 1] = MovedEdgeScale(plan.edges[e - 1], deviation, kOffSurfaceShare);
  }
  return BuildEdgeGrids(model, pcurves, gc, options.threads, sel.edge_needed, context, grids);
}

// 5. Mesh faces, in parallel; each slot is written by one task.
Status MeshFaces(const Model& model, const FacePcurves& pcurves, const MeshOptions& options,
                 double deviation, const Selection& sel, const std::vector<EdgeGrid>& grids,
                 const OffSurfacePlan& plan,
                 const std::vector<std::vector<SingularLine>>& singular_lines,
                 FaceSurfaces* surfaces, Context* context, FaceReporter* reporter,
                 std::vector<FaceMesh>* faces, std::vector<std::vector<NodeRef>>* refs) {
  FaceJob job;
  job.criteria.max_deviation = deviation;
  job.criteria.rd_tolerance = options.rd_tolerance;
  job.criteria.max_length = options.max_edge_length;
  job.criteria.min_length = options.min_edge_length;
  job.max_triangles = kFaceTriangleCap;
  job.nurbs = options.nurbs;
  job.off_surface = options.off_surface;
  job.bend_sides = &plan.bend_sides;
  job.moved_vertices = &plan.moved_vertices;
  job.singular_lines = &singular_lines;
  job.surfaces = surfaces;
  const ParallelRunner runner(options.threads);
  runner.For(
      0, static_cast<int>(sel.todo.size()),
      [&](int i) {
        int f = sel.todo[i];
        if (Stopped(context)) return;
        (*faces)[f - 1] = MeshFace(model, pcurves, f, grids, job, context, &(*refs)[f - 1]);
        if (sel.wanted[f - 1]) reporter->Finished((*faces)[f - 1]);
      },
      Partition::kOnePerTask);
  if (Stopped(context)) return context->StopStatus();
  return Status::Ok();
}

// 6. Place instances: copies reuse their representative's mesh; faces not asked for (and
// representatives meshed only for their copies) are skipped.
Status PlaceInstances(const Model& model, const FacePcurves& pcurves, const Selection& sel,
                      const std::vector<EdgeGrid>& grids, int threads, Context* context,
                      FaceReporter* reporter, std::vector<FaceMesh>* faces,
                      std::vector<std::vector<NodeRef>>* refs) {
  const int nf = model.face_count();
  // The copies in parallel: each task writes its own slot and refs, only reads its
  // representative's, and makes its own evaluators (FaceSurfaces lends a face's to one task at a
  // time). They are reported afterwards, in face order.
  std::vector<int> copies, reps;
  std::vector<int> source_of(nf, -1);  // per representative id - 1: its index in `reps`
  for (int f = 1; f <= nf; ++f) {
    const int rep = model.face_representative[f - 1];
    if (!sel.wanted[f - 1] || rep == f || sel.mesh_it[f - 1]) continue;  // meshed for itself
    copies.push_back(f);
    if ((*faces)[rep - 1].status != FaceStatus::kOk || source_of[rep - 1] >= 0) continue;
    source_of[rep - 1] = static_cast<int>(reps.size());
    reps.push_back(rep);
  }
  // Each representative's boundary once, then the copies.
  const Result<FaceDomain> none = Status(StatusCode::kInternal, "instance boundary not built");
  std::vector<Result<FaceDomain>> sources(reps.size(), none);
  const ParallelRunner runner(threads);
  runner.For(0, static_cast<int>(reps.size()), [&](int i) {
    if (Stopped(context)) return;
    sources[i] = CopySource(model, pcurves, reps[i], grids);
  });
  if (Stopped(context)) return context->StopStatus();
  runner.For(0, static_cast<int>(copies.size()), [&](int i) {
    if (Stopped(context)) return;
    const int f = copies[i], rep = model.face_representative[f - 1];
    const int s = source_of[rep - 1];
    (*faces)[f - 1] = PlaceCopy(model, pcurves, f, (*faces)[rep - 1], (*refs)[rep - 1],
                                s >= 0 ? sources[s] : none,  // none: the representative failed
                                grids, &(*refs)[f - 1]);
  });
  if (Stopped(context)) return context->StopStatus();
  for (int f : copies) reporter->Finished((*faces)[f - 1]);
  // Faces not asked for are skipped, representatives meshed only for their copies among them.
  for (int f = 1; f <= nf; ++f) {
    if (sel.wanted[f - 1]) continue;
    (*faces)[f - 1] = SkippedFace(model, f);
    (*refs)[f - 1].clear();
  }
  return Status::Ok();
}

// 8. Summarise: counts, areas and the largest estimated deviation of the assembled result.
void Summarise(const std::vector<EdgeGrid>& grids, double deviation, MeshResult* result) {
  MeshSummary& s = result->summary;
  s.triangles = result->mesh.triangle_count();
  s.nodes = result->mesh.node_count();
  s.requested_deviation = deviation;
  for (const FaceMesh& f : result->faces) {
    if (f.status == FaceStatus::kOk)
      ++s.faces_ok;
    else if (f.status == FaceStatus::kFailed)
      ++s.faces_failed;
    else
      ++s.faces_skipped;
    s.estimated_deviation = std::max(s.estimated_deviation, f.max_deviation);
    if (f.status != FaceStatus::kSkipped) s.exact_area += f.exact_area;
    s.mesh_area += f.area;
  }
  for (const EdgeGrid& g : grids) {
    if (g.t.size() < 2) continue;
    ++s.edges;
    s.edge_segments += static_cast<int64_t>(g.t.size()) - 1;
  }
}

}  // namespace

Result<MeshResult> MeshAtDeviation(const Model& model, const MeshOptions& options, double deviation,
                                   Context* context, FaceSurfaces* surfaces, RunOutput output) {
  auto t0 = Clock::now();
  MeshResult result;
  result.faces.resize(model.face_count());
  Result<Selection> sel = SelectFaces(model, options);
  if (!sel.ok()) return sel.status();

  // 2. Pcurves: each face's, looked up once for the stages that follow.
  std::vector<int> faces;
  for (int f = 1; f <= model.face_count(); ++f)
    if (sel->wanted[f - 1] || sel->mesh_it[f - 1]) faces.push_back(f);
  FacePcurves pcurves = FacePcurves::Build(model, faces, options.threads, context);
  if (Stopped(context)) return context->StopStatus();

  // Off the surface: which way each face bends, and the edges that move with their faces.
  OffSurfacePlan plan;
  if (options.off_surface) {
    plan.bend_sides = FaceBendSides(model, pcurves, sel->todo, options.nurbs, options.threads);
    plan.edges = OffsetEdges(model, pcurves, plan.bend_sides, sel->edge_needed);
  }
  std::vector<EdgeGrid> grids;
  Status st = MakeEdgeGrids(model, pcurves, options, deviation, *sel, plan, context, &grids);
  if (!st.ok()) return st;
  // Lines the surface collapses to a point: the faces keep their triangles off them, from
  // grid points where their edges cross them.
  const std::vector<std::vector<SingularLine>> lines =
      FaceSingularLines(model, pcurves, sel->todo, options.nurbs, options.threads);
  PinSingularLines(model, pcurves, lines, &grids);
  // 4. Heal: split grid segments until every face's boundary loops are valid in (u,v).
  st = HealEdgeGrids(model, pcurves, sel->todo, options.nurbs, options.threads, context, &grids);
  if (!st.ok()) return st;
  if (!plan.edges.empty())
    MoveEdgeGrids(model, plan.edges, kOffSurfaceShare * deviation, &grids, &plan.moved_vertices);
  result.summary.edge_seconds = SecondsSince(t0);

  auto t1 = Clock::now();
  const int64_t total = sel->wanted_count;
  std::vector<std::vector<NodeRef>> refs(model.face_count());
  if (context) context->ReportProgress({Progress::Stage::kFaces, 0, total});
  FaceReporter reporter(context, total);
  st = MeshFaces(model, pcurves, options, deviation, *sel, grids, plan, lines, surfaces, context,
                 &reporter, &result.faces, &refs);
  if (!st.ok()) return st;
  st = PlaceInstances(model, pcurves, *sel, grids, options.threads, context, &reporter,
                      &result.faces, &refs);
  if (!st.ok()) return st;
  result.summary.face_seconds = SecondsSince(t1);

  // 7. Assemble, in face order.
  if (context) context->ReportProgress({Progress::Stage::kAssembly, total, total});
  Assemble(&result.faces, refs, &result.mesh, options.threads);
  Summarise(grids, deviation, &result);
  result.summary.seconds = SecondsSince(t0);
  // 8. Edge lines, from the pcurve table (not counted in the seconds, as before).
  if (output == RunOutput::kMeshAndEdgeLines) {
    Result<std::vector<EdgeLine>> edges =
        BuildEdgeLines(model, result.mesh, options.sharp_edge_angle, options.threads, pcurves);
    if (!edges.ok()) return edges.status();
    result.edges = std::move(*edges);
  }
  pcurves.Release(options.threads);
  if (context) context->ReportProgress({Progress::Stage::kDone, total, total});
  return result;
}

}  // namespace rdmesh
