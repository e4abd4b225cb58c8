#pragma once
// The starting triangulation of a face: a constrained Delaunay triangulation of its boundary
// segments (and seed points) in scaled (u,v), by CGAL with exact predicates. CGAL stays in
// cdt.cpp alone.

#include <array>
#include <vector>

#include "core/geom.h"
#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh {

struct CdtResult {
  std::vector<std::array<int, 3>> triangles;  ///< counter-clockwise point indices, inside only
  /// Per triangle, per corner i: whether the edge opposite corner i is a constraint.
  std::vector<std::array<bool, 3>> constrained;
};

/// Triangulates the region bounded by `segments` (point index pairs; holes by the even-odd
/// nesting rule). `inner` segments are constraints inside the region, with it on both sides
/// (they bound nothing). Points must be distinct; segments must not cross. Fails with a reason
/// otherwise, or with the context's stop status when it asks to stop (`context` may be null).
Status ConstrainedTriangulation(const std::vector<Vec2>& points,
                                const std::vector<std::array<int, 2>>& segments,
                                const std::vector<std::array<int, 2>>& inner,
                                const Context* context, CdtResult* result);
/// The same without inner segments.
inline Status ConstrainedTriangulation(const std::vector<Vec2>& points,
                                       const std::vector<std::array<int, 2>>& segments,
                                       const Context* context, CdtResult* result) {
  return ConstrainedTriangulation(points, segments, {}, context, result);
}

}  // namespace rdmesh
