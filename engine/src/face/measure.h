#pragma once
// How well one triangle stands for its surface patch, from surface evaluations only:
// the estimated deviation (largest surface-triangle distance), the representation deficit a
// split would remove, its longest edge, and whether it is valid (no fold). On a B-spline the
// deviation also looks between the knot lines the triangle crosses and at the halves of each
// piece: one quadratic through the edge midpoints cannot follow a cubic piece, let alone
// several.

#include "core/geom.h"
#include "geometry/offset_surface.h"
#include "geometry/surface.h"

namespace rdmesh {

/// The stop criteria of face refinement; a 0 turns a criterion off.
struct FaceCriteria {
  double max_deviation = 0;     ///< model units
  double rd_tolerance = 0;      ///< triangle RD (A_S - A_T) / A_T
  double max_length = 0;        ///< longest 3D edge, model units
  double min_length = 0;        ///< never split a triangle whose longest edge is below 2x this
  double min_normal_cos = 0.5;  ///< a triangle's normal must lie within acos(this) of its
                                ///< corners' surface normals (fold guard)
  /// Where set, the deviation allowed varies over the face: max_deviation times this scale
  /// (in (0, 1]) at the triangle (DeviationLimit). Off the surface, a face that bends one way
  /// in parts is offset there and may take twice the band, and stays on it elsewhere.
  const UvGrid* deviation_scale = nullptr;
  /// Off the surface: the face's own surface (the one meshed is its offset), against which the
  /// final check also measures each triangle both ways and splits where it misses own_deviation.
  /// An offset that bends both ways where it was read to bend one (a 2% curvature of the other
  /// sign along a long triangle) puts the mesh outside the offset, past the band.
  Surface* own_surface = nullptr;
  double own_deviation = 0;
};

/// The deviation allowed for the triangle with corners uv[i]: max_deviation, times the least of
/// deviation_scale at its corners and centroid where that is set.
double DeviationLimit(const FaceCriteria& c, const Vec2 uv[3]);

struct TriangleMeasure {
  double deviation = 0;   ///< model units
  double rd = 0;          ///< area gain of a split at the centroid: RD estimate; computed
                          ///< only when FaceCriteria::rd_tolerance is on (0 otherwise)
  double max_length = 0;  ///< longest 3D edge
  double violation = 0;   ///< max over criteria of value / limit: <= 1 meets them all
  double agreement = 1;   ///< TriangleAgreement, when the caller measured it
  Vec2 worst_uv;          ///< where the deviation peaks (a good split point)
  bool exact = false;     ///< the deviation is the surface's exact distance (sphere,
                          ///< cylinder, cone: Surface::quadric), not an estimate from samples
};

/// Measures the triangle with corners uv[i] / xyz[i] (xyz are the nodes' mesh positions).
TriangleMeasure MeasureTriangle(Surface& surface, const Vec2 uv[3], const Vec3 xyz[3],
                                const FaceCriteria& criteria);

/// MeasureTriangle for a caller that only wants triangles whose violation stays below `limit`:
/// false when part of the samples shows that it does not (more samples can only raise the
/// deviation), with m->violation a lower bound >= limit; true with *m as MeasureTriangle gives
/// it (whose violation may still reach the limit). Skips the edge-midpoint samples of a
/// triangle whose centroid is over the limit already (then nothing else is set), and the
/// knot-line samples of one whose other samples are.
bool MeasureTriangleBelow(Surface& surface, const Vec2 uv[3], const Vec3 xyz[3],
                          const FaceCriteria& criteria, double limit, TriangleMeasure* m);

/// The largest of a measured triangle's ratios to the criteria other than the deviation (its
/// longest edge over max_length, its RD over rd_tolerance; 0 where neither is set).
double OtherCriteriaRatio(const FaceCriteria& c, const TriangleMeasure& m);

/// How well the triangle's 3D normal agrees with the surface normals at its corners (`normals`,
/// oriented as Su x Sv): the smallest cosine between them. kInvalid when the (u,v) orientation
/// is not positive or the triangle is degenerate in 3D other than at a pole (two corners at one
/// point); 1 for a pole triangle. Operations keep it above 0 (no fold) and never push it below
/// FaceCriteria::min_normal_cos where it was above.
constexpr double kInvalid = -2.0;
double TriangleAgreement(const Vec2 uv[3], const Vec3 xyz[3], const Vec3 normals[3]);

/// Adds to *m, measured by MeasureTriangle, what its plane heights miss where the triangle is
/// tilted against the surface: the mesh's distance to the surface is measured along the
/// surface's normal, a height over the triangle's plane along the plane's, which is shorter by
/// the cosine between them (about 0.6 on a cylinder triangle whose long edge spans 46 degrees:
/// gmsh_angled at 3e-3). At worst the surface bends within the plane of a triangle that stands
/// against it, off its edges, where a sliver across a curved profile leaves a trench. Each
/// edge-midpoint sample's height over its edge along the mean of the edge's corner normals
/// (`normals`, as for TriangleAgreement) raises the deviation and violation; edge i (opposite
/// corner i) only when bit i of `edges` is set.
void MeasureEdgeHeights(Surface& surface, const Vec2 uv[3], const Vec3 xyz[3],
                        const Vec3 normals[3], const FaceCriteria& criteria, int edges,
                        TriangleMeasure* m);

/// The distance from points of the triangle to the surface (to the nearest surface point, as the
/// yardstick measures it): at the centroid, the three interior points of barycentric
/// (1/2, 1/4, 1/4) and its turns (the points the yardstick samples inside a triangle), and at the
/// quarter points of edge i (opposite corner i) when bit i of `edges` is set. On a thin triangle
/// tilted over an uneven parametrisation, S at a point's (u,v) weights lands well beside that
/// point, and the plane height there (the estimate's) says little about the mesh at the point.
/// So S is sampled at the (u,v) of every node of the barycentric grid of step 1/4, and each point
/// gets two Gauss-Newton steps toward its nearest surface point, with S's derivatives from the
/// grid; a point still over `suspect` gets up to six more in (u,v), with derivatives by
/// differences and steps as long as the triangle's longest (u,v) side, within the face's bounds
/// (the nearest point can lie in a neighbour's patch, or across the width of a sliver in (u,v)).
/// Every distance is from the point to a surface point, so the result never reads under the
/// distance to the (untrimmed) surface, and over it only where the search falls short. Returns
/// the largest distance, its (u,v) into *where. Costs 16 + 2 surface points per point (at most
/// 42), and up to 18 more per suspect point: for a final check, not for refinement's search.
double DenseDeviation(Surface& surface, const Vec2 uv[3], const Vec3 xyz[3], int edges,
                      double suspect, Vec2* where);

/// The distance from the surface over the triangle to the mesh, the other way round from
/// DenseDeviation (the yardstick measures both): S at the (u,v) of every node of the barycentric
/// grid of step 1/8 but the corners, and at `extra` (a peak the estimate found) when it lies
/// strictly inside, each to the nearest of the `count` triangles whose corners are
/// near[3k..3k+2] (the triangle and its neighbours). A grid cell whose corners' largest reading
/// plus its sag (from the grid's second differences, then from its edges' midpoints) passes
/// `limit` is split in four and read again, down to 1/64 of a cell: a sliver's grid can step over
/// a bulge beside its corner. Points of edge i (opposite corner i) only when bit i of `edges` is
/// set: an edge grid's chord holds its own deviation, and S at a boundary node's (u,v) lies off
/// the edge where the B-rep's edge lies off its surface. A surface that bends away beside a
/// tilted triangle's plane lies farther from the triangle than above its plane, which is what the
/// estimate measures. Returns the largest, its (u,v) into *where. Costs 45 surface points, and
/// at most 400 more where cells are split.
double SurfaceSideDeviation(Surface& surface, const Vec2 uv[3], Vec2 extra, int edges,
                            const Vec3* near, int count, double limit, Vec2* where);

/// Sum of the 3D areas of the three triangles a split at q makes, over the triangle's area.
double SplitAreaRatio(Surface& surface, const Vec2 uv[3], const Vec3 xyz[3], Vec2 q);

}  // namespace rdmesh
