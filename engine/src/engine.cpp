// MeshModel: the pipeline. Edge grids once per edge, then every face in parallel worker threads,
// then assembly in face order (so the output does not depend on the thread count).
#include "rdmesh/engine.h"

#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <atomic>
#include <chrono>
#include <cmath>

#include "assemble.h"
#include "budget.h"
#include "face_mesher.h"
#include "grids.h"
#include "heal.h"
#include "model.h"
#include "parallel.h"

namespace rdmesh {

namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Representative face mesh cap: far above any sane request, it only stops runaway refinement.
constexpr int64_t kFaceTriangleCap = 20'000'000;

}  // namespace

Result<MeshResult> MeshAtDeviation(const Model& model, const MeshOptions& options, double deviation,
                                   Context* context, FaceSurfaces* surfaces) {
  auto t0 = Clock::now();
  const int nf = model.face_count();
  MeshResult result;
  result.faces.resize(nf);
  std::vector<bool> wanted(nf, options.face_ids.empty());
  for (int id : options.face_ids) {
    if (id > nf)
      return Status(StatusCode::kInvalidArgument,
                    "face id " + std::to_string(id) + " is out of range 1.." + std::to_string(nf));
    wanted[id - 1] = true;
  }
  // Faces to mesh: representatives of the wanted faces.
  std::vector<bool> mesh_it(nf, false);
  for (int f = 1; f <= nf; ++f)
    if (wanted[f - 1]) mesh_it[model.face_representative[f - 1] - 1] = true;
  std::vector<bool> edge_needed(model.edge_count(), false);
  for (int f = 1; f <= nf; ++f) {
    if (!wanted[f - 1] && !mesh_it[f - 1]) continue;
    for (TopExp_Explorer ex(model.face(f), TopAbs_EDGE); ex.More(); ex.Next()) {
      int e = model.edges.FindIndex(ex.Current());
      if (e > 0) edge_needed[e - 1] = true;
    }
  }

  // 1. Edge grids.
  if (context) context->ReportProgress({Progress::Stage::kEdges, 0, model.edge_count()});
  GridCriteria gc;
  gc.max_deviation = deviation;
  gc.rd_tolerance = options.rd_tolerance / 5;  // faces carry ~5x the RD of their edges
  gc.max_length = options.max_edge_length;
  gc.min_length = options.min_edge_length;
  std::vector<EdgeGrid> grids;
  Status st = BuildEdgeGrids(model, gc, options.threads, edge_needed, context, &grids);
  if (!st.ok()) return st;
  // 1b. Grid healing: split grid segments until every face's boundary loops are valid in (u,v).
  std::vector<int> todo;
  for (int f = 1; f <= nf; ++f)
    if (mesh_it[f - 1]) todo.push_back(f);
  st = HealEdgeGrids(model, todo, options.nurbs, options.threads, context, &grids);
  if (!st.ok()) return st;
  result.summary.edge_seconds = Since(t0);

  // 2. Faces, in parallel; each slot is written by one task.
  auto t1 = Clock::now();
  FaceJob job;
  job.criteria.max_deviation = deviation;
  job.criteria.rd_tolerance = options.rd_tolerance;
  job.criteria.max_length = options.max_edge_length;
  job.criteria.min_length = options.min_edge_length;
  job.max_triangles = kFaceTriangleCap;
  job.nurbs = options.nurbs;
  job.surfaces = surfaces;
  std::vector<std::vector<NodeRef>> refs(nf);
  std::atomic<int64_t> done{0};
  const int64_t total = std::count(wanted.begin(), wanted.end(), true);
  if (context) context->ReportProgress({Progress::Stage::kFaces, 0, total});
  auto finished = [&](const FaceMesh& f) {
    if (!context) return;
    context->ReportFace(f);
    context->ReportProgress({Progress::Stage::kFaces, ++done, total});
  };
  const ParallelRunner runner(options.threads);
  runner.For(
      0, static_cast<int>(todo.size()),
      [&](int i) {
        int f = todo[i];
        if (context && context->ShouldStop()) return;
        result.faces[f - 1] = MeshFace(model, f, grids, job, context, &refs[f - 1]);
        if (wanted[f - 1]) finished(result.faces[f - 1]);
      },
      Partition::kOnePerTask);
  if (context && context->ShouldStop()) return context->StopStatus();
  // Instanced copies reuse their representative's mesh.
  for (int f = 1; f <= nf; ++f) {
    if ((f & 63) == 0 && context && context->ShouldStop()) return context->StopStatus();
    FaceMesh& slot = result.faces[f - 1];
    int rep = model.face_representative[f - 1];
    if (!wanted[f - 1]) {
      if (mesh_it[f - 1]) continue;  // a representative meshed for its copies: see below
      slot = FaceMesh();
      slot.face_id = f;
      slot.status = FaceStatus::kSkipped;
      slot.reason = "not requested";
      slot.exact_area = model.face_area[f - 1];
      refs[f - 1].clear();
      continue;
    }
    if (rep == f) continue;
    std::vector<NodeRef> copy_refs;
    slot = PlaceCopy(model, f, result.faces[rep - 1], refs[rep - 1], grids, &copy_refs, surfaces);
    refs[f - 1] = std::move(copy_refs);
    finished(slot);
  }
  // Representatives that were only meshed for their copies are not part of the result.
  for (int f = 1; f <= nf; ++f) {
    if (wanted[f - 1] || !mesh_it[f - 1]) continue;
    FaceMesh skipped;
    skipped.face_id = f;
    skipped.status = FaceStatus::kSkipped;
    skipped.reason = "not requested";
    skipped.exact_area = model.face_area[f - 1];
    result.faces[f - 1] = std::move(skipped);
    refs[f - 1].clear();
  }
  result.summary.face_seconds = Since(t1);

  // 3. Assembly, in face order.
  if (context) context->ReportProgress({Progress::Stage::kAssembly, total, total});
  Assemble(&result.faces, refs, &result.mesh);
  MeshSummary& s = result.summary;
  s.triangles = result.mesh.triangle_count();
  s.nodes = result.mesh.node_count();
  s.requested_deviation = deviation;
  for (const FaceMesh& f : result.faces) {
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
  s.seconds = Since(t0);
  if (context) context->ReportProgress({Progress::Stage::kDone, total, total});
  return result;
}

Result<MeshResult> MeshModel(const Model& model, const MeshOptions& options, Context* context) {
  return MeshModelWith(model, options, context, nullptr);
}

Result<MeshResult> MeshModelWith(const Model& model, const MeshOptions& options, Context* context,
                                 FaceSurfaces* surfaces) {
  Status st = ValidateOptions(options);
  if (!st.ok()) return st;
  Context local;
  if (!context) context = &local;
  if (options.timeout_seconds > 0) context->SetTimeout(options.timeout_seconds);
  double deviation = options.max_deviation > 0 ? options.max_deviation
                                               : options.max_deviation_rel * model.info.diagonal;
  Result<MeshResult> result = options.max_triangles > 0
                                  ? MeshWithinBudget(model, options, context)
                                  : MeshAtDeviation(model, options, deviation, context, surfaces);
  if (!result.ok()) return result;
  Result<std::vector<EdgeLine>> edges =
      BuildEdgeLines(model, result->mesh, options.sharp_edge_angle);
  if (!edges.ok()) return edges.status();
  result->edges = std::move(*edges);
  return result;
}

}  // namespace rdmesh
