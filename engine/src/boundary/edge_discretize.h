#pragma once
// Edge grid: the discretisation of one B-rep edge's curve, done once and shared by every face
// that uses the edge (which is what makes the model's mesh watertight).
//
// 1. Greedy representation-deficit refinement: split the worst segment at the point that
//    maximises the sum of its two sub-chords, until every segment is well inside the criteria.
// 2. Arc-length optimisation: from that fine grid, the error density gives the fewest segments
//    that meet the criteria; the points are placed so that every segment carries the same share
//    of it (equal sagittas on a circle), then checked exactly.

#include <functional>
#include <vector>

#include "geometry/surface.h"
#include "rdmesh/context.h"

namespace rdmesh {

/// A face beside the edge. A chord strays from the curve within the face's tangent plane by the
/// tangential part of its sagitta: its triangles cover ground outside the face (a hole's chord
/// reaches over the hole) or leave some of it bare. On a face that is narrow next to the
/// tolerance, that part must stay a small fraction of the face's width.
struct EdgeSide {
  std::function<Vec3(double t)> normal;  ///< the face's unit normal at C(t) (zero where undefined)
  double max_overshoot = 0;              ///< largest tangential sagitta, model units
};

struct EdgeGridCriteria {
  double max_sagitta = 0;       ///< largest curve-chord distance, model units; 0 = off
  double rd_tolerance = 0;      ///< largest segment RD (L_S - L_E) / L_E; 0 = off
  double max_length = 0;        ///< longest chord, model units; 0 = off
  double min_length = 0;        ///< never split a chord shorter than twice this; 0 = off
  int min_segments = 1;         ///< closed edges need 3
  std::vector<EdgeSide> sides;  ///< narrow faces beside the edge; usually none
};

/// What one segment [a, b] of a curve looks like to the criteria.
struct SegmentMeasure {
  double chord = 0;    ///< |C(a) C(b)|
  double sagitta = 0;  ///< largest distance from the curve to the chord
  double rd = 0;       ///< (L_S - L_E) / L_E, from the gain of the best split (x 4/3)
  double split = 0;    ///< t*, the parameter of the best split
  double across = 0;   ///< largest tangential sagitta / EdgeSide::max_overshoot over the sides
};

/// Measures [a, b] with a derivative-free search for the farthest / best split point (in closed
/// form on a line or a circle: Curve::shape); `sides` (may be null or empty) also gives
/// SegmentMeasure::across, at the farthest point.
SegmentMeasure MeasureSegment(Curve& curve, double a, double b,
                              const std::vector<EdgeSide>* sides = nullptr);

/// How far a segment is from meeting the criteria: <= 1 means it meets them.
double SegmentViolation(const SegmentMeasure& m, const EdgeGridCriteria& c);

/// Parameters first = t0 < t1 < ... < tn = last of the optimised grid. When `context` (may be
/// null) asks to stop, returns early with a grid that is not to be used.
std::vector<double> DiscretizeCurve(Curve& curve, double first, double last,
                                    const EdgeGridCriteria& criteria,
                                    const Context* context = nullptr);

}  // namespace rdmesh
