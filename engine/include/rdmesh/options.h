#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// MeshOptions::max_deviation_rel when it is not set.
inline constexpr double kDefaultMaxDeviationRel = 1e-3;

/// The share of the deviation a compressed .glb's position rounding may use
/// (MeshOptions::compress, WriteOptions::compress): the run meshes to (1 - share) of the
/// deviation and the writer moves no vertex farther than share times it, so the sum stays within
/// the request.
inline constexpr double kCompressRoundingShare = 0.015;

/// What a meshing run should reach. A plain struct: every field has a usable default.
/// Lengths are in model units (OCCT reads STEP in millimetres).
struct MeshOptions {
  /// Largest distance between mesh and surface, in model units. 0 = use max_deviation_rel.
  double max_deviation = 0.0;
  /// Largest distance as a fraction of the model's bounding-box diagonal. Used when
  /// max_deviation is 0. 0 (with max_deviation 0) = no deviation criterion. Unset =
  /// kDefaultMaxDeviationRel (MaxDeviationRel reads it); a run with levels of detail refuses a
  /// set one, since each level sets its own (ResolveLevels).
  std::optional<double> max_deviation_rel;
  /// Representation-deficit tolerance (scale free; RD of a segment turning by theta ~ theta^2/24).
  /// 0 = off.
  double rd_tolerance = 0.0;
  /// Triangle budget for the whole model. 0 = none. When set, the run finds the smallest
  /// deviation whose mesh has at most this many triangles.
  int64_t max_triangles = 0;
  /// Never split an edge or a triangle below this 3D edge length (model units). 0 = off.
  double min_edge_length = 0.0;
  /// Split every edge longer than this (model units); also puts nodes inside planar faces.
  /// 0 = off.
  double max_edge_length = 0.0;
  /// Convert every face to a B-spline surface before meshing (default: exact surfaces).
  bool nurbs = false;
  /// Worker threads. 0 = all cores. The mesh does not depend on it.
  int threads = 0;
  /// Mesh only these face ids (1-based). Empty = all faces.
  std::vector<int> face_ids;
  /// Stop the run with kDeadlineExceeded after this many seconds. 0 = no limit.
  double timeout_seconds = 0.0;
  /// MeshResult::edges: an edge whose faces meet at a dihedral angle above this (degrees, in
  /// [0, 180]) is sharp. It changes no triangle or node. (The service carries it as
  /// MeshOptions.sharp_edge_angle; the CLI has no flag for it and writes the default.)
  double sharp_edge_angle = kDefaultSharpEdgeAngle;
  /// The mesh is for a compressed .glb (WriteOptions::compress): the run meshes to
  /// (1 - kCompressRoundingShare) of the deviation, leaving the rest to the writer's rounding of
  /// positions; MeshSummary::requested_deviation still reports the whole deviation. Needs a
  /// deviation (max_deviation or max_deviation_rel) and no max_triangles budget.
  bool compress = false;
  /// Mesh off the surface: on a face that bends one way (sphere, cylinder, cone, a convex or
  /// concave B-spline...), the interior nodes move off the surface by up to
  /// kOffSurfaceShare of the deviation, toward its outer side, so that the triangles lie on
  /// both sides of it within the deviation, with about half as many as on the surface.
  /// FaceMesh::offset says how far each face's nodes moved (0: kept on the surface, and
  /// FaceMesh::offset_reason why). Normals stay the surface's at each node's foot.
  bool off_surface = false;
};

/// With MeshOptions::off_surface: the share of the deviation the interior nodes lie off the
/// surface by, the rest kept as a margin for what the refinement's estimate misses.
inline constexpr double kOffSurfaceShare = 0.95;

/// The relative deviation a run uses: max_deviation_rel, or its default when unset.
inline double MaxDeviationRel(const MeshOptions& options) {
  return options.max_deviation_rel.value_or(kDefaultMaxDeviationRel);
}

/// Checks ranges and combinations; kInvalidArgument with a readable message, naming the field,
/// when out of range. The one check of options: the CLI and the service call it before a run,
/// MeshModel again at its start.
Status ValidateOptions(const MeshOptions& options);

}  // namespace rdmesh
