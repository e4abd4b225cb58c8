#include "rdmesh/options.h"

#include <cmath>
#include <string>

namespace rdmesh {

namespace {
bool Finite(double x) { return std::isfinite(x); }
}  // namespace

Status ValidateOptions(const MeshOptions& o) {
  const double rel = MaxDeviationRel(o);
  if (!Finite(o.max_deviation) || o.max_deviation < 0)
    return InvalidArgument("max_deviation must be a finite length >= 0 (model units)");
  if (!Finite(rel) || rel < 0 || rel > 0.5)
    return InvalidArgument(
        "max_deviation_rel must lie in [0, 0.5] (fraction of the bbox diagonal)");
  if (o.max_deviation == 0 && rel > 0 && rel < 1e-7)
    return InvalidArgument(
        "max_deviation_rel below 1e-7 of the diagonal is finer than the geometry");
  if (!Finite(o.rd_tolerance) || o.rd_tolerance < 0 || o.rd_tolerance > 1)
    return InvalidArgument("rd_tolerance must lie in [0, 1]");
  if (o.max_triangles < 0) return InvalidArgument("max_triangles must be >= 0");
  if (o.max_triangles > 0 && o.max_triangles < 1)
    return InvalidArgument("max_triangles must be >= 1");
  if (!Finite(o.min_edge_length) || o.min_edge_length < 0)
    return InvalidArgument("min_edge_length must be a finite length >= 0");
  if (!Finite(o.max_edge_length) || o.max_edge_length < 0)
    return InvalidArgument("max_edge_length must be a finite length >= 0");
  if (o.max_edge_length > 0 && o.min_edge_length > o.max_edge_length)
    return InvalidArgument("min_edge_length must not exceed max_edge_length");
  if (o.threads < 0 || o.threads > 1024) return InvalidArgument("threads must lie in [0, 1024]");
  if (!Finite(o.timeout_seconds) || o.timeout_seconds < 0)
    return InvalidArgument("timeout_seconds must be >= 0");
  if (!Finite(o.sharp_edge_angle) || o.sharp_edge_angle < 0 || o.sharp_edge_angle > 180)
    return InvalidArgument("sharp_edge_angle must lie in [0, 180] degrees");
  if (o.off_surface && o.max_triangles == 0 && o.max_deviation == 0 && rel == 0)
    return InvalidArgument(
        "off_surface needs a max deviation (absolute or relative) or a triangle budget: the "
        "nodes leave the surface by a share of the deviation");
  if (o.compress && (o.max_triangles > 0 || (o.max_deviation == 0 && rel == 0)))
    return InvalidArgument(
        "compress needs a max deviation (absolute or relative) and no triangle budget: its "
        "position rounding is a share of that deviation");
  for (int id : o.face_ids)
    if (id < 1) return InvalidArgument("face_ids start at 1 (got " + std::to_string(id) + ")");
  if (o.max_deviation == 0 && rel == 0 && o.rd_tolerance == 0 && o.max_edge_length == 0 &&
      o.max_triangles == 0)
    return InvalidArgument(
        "no stop criterion: set a max deviation, an RD tolerance, a max edge length "
        "or a triangle budget");
  return Status::Ok();
}

}  // namespace rdmesh
