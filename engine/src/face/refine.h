#pragma once
// Face refinement: greedy representation-deficit refinement to the stop criteria, then an
// improvement loop toward equidistributed error. Reads as a sequence of named local passes:
//
//   RefineToCriteria   pop the worst triangle, split it at its area-optimal point (or split the
//                      nearby edge), legalise the new node's link by deviation-driven flips
//   CollapsePass       remove interior nodes while every triangle they touch stays within the
//                      criteria
//   FlipPass           flip edges where the larger deviation of the pair drops
//   SmoothPass         move interior nodes to lower the largest deviation in their hull

#include <cstdint>
#include <vector>

#include "face/measure.h"
#include "face/work_mesh.h"
#include "geometry/surface.h"
#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh {

struct RefineStats {
  int64_t splits = 0;
  int64_t edge_splits = 0;
  int64_t rescues = 0;   ///< splits that flipped a folded child's outer edge with them
  int64_t reshapes = 0;  ///< flips that gave a triangle no split could refine another shape
  int64_t flips = 0;
  int64_t collapses = 0;
  int64_t moves = 0;
  bool budget_hit = false;        ///< stopped at the triangle cap
  int64_t refined_triangles = 0;  ///< triangles after the splits, before the improvement passes
  double max_violation = 0;       ///< worst triangle afterwards (<= 1: all criteria met)
  int64_t over = 0;               ///< triangles over the criteria afterwards
  /// Of those, folded ones left unsplit since splits hand their fold on (Refiner::StuckFold:
  /// where the surface's normal reverses inside, a twisted patch, or where a first
  /// triangulation fans across a turn, which a retry's start avoids).
  int64_t stuck_folds = 0;
  double max_deviation = 0;  ///< worst estimated deviation afterwards, model units
  /// 1 per working-mesh triangle (dead ones 0): its estimated deviation afterwards, model units.
  std::vector<double> deviation;
};

/// Refines `mesh` on `surface` until every triangle meets `criteria` (or `max_triangles` is
/// reached), then improves it. `scale_u`, `scale_v` make (u,v) roughly isometric.
/// With `settle_rounds` > 0 (a first triangulation seeded at about the final density, as
/// SphereLatticeSeeds), its edges are first flipped and its free nodes moved by deviation
/// (Refiner::Settle) before any split, so that near-misses are moved rather than split.
/// Returns kCancelled / kDeadlineExceeded when the context asks to stop.
Status RefineFace(WorkMesh* mesh, Surface& surface, const FaceCriteria& criteria, double scale_u,
                  double scale_v, int64_t max_triangles, bool improve, Context* context,
                  RefineStats* stats, int settle_rounds = 0);

/// Triangle t of `mesh` measured against `surface` both ways: from points of the triangle to
/// the surface (DenseDeviation), and where that is within `limit`, from the surface over it to
/// the nearest of it and its neighbours, and, where that is over, of every triangle at its
/// corners (SurfaceSideDeviation). Edges of the boundary are not read (their chords hold their
/// own deviation). The largest reading, its (u,v) into *where. Off the surface, the final check
/// of the offset's mesh against the face's own surface.
double BothWaysDeviation(const WorkMesh& mesh, int t, Surface& surface, double limit, Vec2* where);

}  // namespace rdmesh
