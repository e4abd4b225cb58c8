// Levels of detail: one loaded model meshed at several relative deviations, coarsest first.
// Each level is an ordinary MeshModel run (its own edge grids, faces meshed against them), so a
// level's mesh is the mesh of a single run at that deviation. What does not depend on the
// deviation is shared: the loaded model, and the face evaluators (FaceSurfaces), made by the
// first level that meshes a face and lent to the next ones.
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "face/face_mesher.h"
#include "model/model.h"
#include "rdmesh/engine.h"
#include "run/facade.h"

namespace rdmesh {

Result<std::vector<double>> ResolveLevels(std::vector<double> levels_rel,
                                          const MeshOptions& options) {
  if (levels_rel.empty()) return InvalidArgument("lod: no level given");
  if (static_cast<int>(levels_rel.size()) > kMaxLevels)
    return InvalidArgument("lod: at most " + std::to_string(kMaxLevels) + " levels");
  if (options.max_deviation > 0)
    return InvalidArgument("lod levels are relative deviations: leave max_deviation at 0");
  if (options.max_deviation_rel)
    return InvalidArgument("lod levels are relative deviations: leave max_deviation_rel unset");
  if (options.max_triangles > 0)
    return InvalidArgument("lod levels are deviations: they do not combine with max_triangles");
  for (double level : levels_rel) {
    if (!std::isfinite(level) || level <= 0 || level > 0.5)
      return InvalidArgument(
          "lod: each level must lie in (0, 0.5] (fraction of the bbox diagonal)");
    Status valid = ValidateOptions(LevelOptions(options, level));
    if (!valid.ok()) return InvalidArgument("lod: " + valid.message());
  }
  std::sort(levels_rel.begin(), levels_rel.end(), std::greater<double>());
  if (std::adjacent_find(levels_rel.begin(), levels_rel.end()) != levels_rel.end())
    return InvalidArgument("lod: two levels are equal");
  return levels_rel;
}

MeshOptions LevelOptions(const MeshOptions& options, double level_rel) {
  MeshOptions level = options;
  level.max_deviation = 0.0;
  level.max_deviation_rel = level_rel;
  return level;
}

Status MeshModelLevels(const Model& model, const MeshOptions& options,
                       const std::vector<double>& levels_rel, Context* context,
                       const LevelCallbacks& callbacks) {
  Context local;
  if (!context) context = &local;
  // The timeout covers the whole run; each level's MeshModel sets the same deadline again, and
  // the earliest deadline wins.
  if (options.timeout_seconds > 0) context->SetTimeout(options.timeout_seconds);
  FaceSurfaces surfaces(model.face_count());
  for (int i = 0; i < static_cast<int>(levels_rel.size()); ++i) {
    if (context->ShouldStop()) return context->StopStatus();
    if (callbacks.started) callbacks.started(i);
    Result<MeshResult> result =
        MeshModelWith(model, LevelOptions(options, levels_rel[i]), context, &surfaces);
    if (!result.ok()) return result.status();
    if (callbacks.done) {
      Status st = callbacks.done(i, std::move(*result));
      if (!st.ok()) return st;
    }
  }
  return Status::Ok();
}

}  // namespace rdmesh
