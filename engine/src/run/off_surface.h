#pragma once
// The run-level part of meshing off the surface (MeshOptions::off_surface): which way each face
// bends, and the circles whose grids leave their curve with the faces on both sides. A circle
// between a cylinder and its cap, say: with its nodes on the curve, the cylinder's triangles
// along it would have to meet the deviation from the curve's chords alone, which costs what
// leaving the surface gains; moved outward by the offset (within the cap's plane, onto the
// cylinder's offset) and discretised at twice it, its polyline lies within the offset on both
// sides of the curve.

#include <cstdint>
#include <map>
#include <vector>

#include "boundary/edge_grids.h"

namespace rdmesh {

class FacePcurves;
class Model;

/// Per face id - 1, for the faces `faces` lists (0 for the others): +1 or -1 when the face's
/// surface bends away from / toward its parametric normal Su x Sv everywhere on a grid of its
/// (u,v) bounds (BendSide), 0 for a plane, a saddle, or a surface that does not bend.
std::vector<int8_t> FaceBendSides(const Model& model, const FacePcurves& pcurves,
                                  const std::vector<int>& faces, bool nurbs, int threads);

/// A circle or a line about an axis (a point on it, and its unit direction).
struct Circle {
  Vec3 center, axis;
};

/// An edge whose grid moves off its curve with its faces, away from an axis.
struct MovedEdge {
  enum Kind { kNone, kCircle, kRuling, kCurve };
  Kind kind = kNone;
  Circle axis;  ///< a circle's own; a ruling's faces' (cylinders or cones about it); unused for
                ///< a curve, whose nodes move away from its centre of curvature
  /// A circle's radius, a curve's smallest radius of curvature (of its samples): moved away
  /// from its centre by d, the curve's chords rise (radius + d) / radius times as high.
  double radius = 0;
};

/// The chord height an edge grid takes, as a multiple of the deviation, for an edge that moves
/// `distance` (in deviations) off its curve with faces meshed to twice that: its chords, moved,
/// must stay within the offset band.
double MovedEdgeScale(const MovedEdge& edge, double deviation, double distance);

/// Per edge id - 1, of the edges `edge_needed` marks, those that move with their faces:
/// - a circle whose every face is a plane (the move stays in it) or bends toward the circle's
///   axis (an offset along its bend side moves away from the axis);
/// - a line whose faces are cylinders or cones about one axis, bending toward it (a ruling: the
///   line between the halves of a split cylinder);
/// - another curve that bends one way all along (no inflection, nowhere straight), whose faces
///   are planes or bend toward its centre of curvature: it moves away from that centre;
/// with both vertices free to move: every edge at each is such an edge about the same axis, or
/// an edge of one face only (a seam), all moving it the same way. Their vertices move with them
/// (MoveEdgeGrids).
std::vector<MovedEdge> OffsetEdges(const Model& model, const FacePcurves& pcurves,
                                   const std::vector<int8_t>& bend_sides,
                                   const std::vector<bool>& edge_needed);

/// Moves every node of the edges `edges` marks, their vertices included, `distance` away from
/// their axis, square to it (a curve's: away from its centre of curvature); the vertices' new
/// points into *vertices (vertex id to point), for the face domains (which take vertices from the
/// model).
void MoveEdgeGrids(const Model& model, const std::vector<MovedEdge>& edges, double distance,
                   std::vector<EdgeGrid>* grids, std::map<int, Vec3>* vertices);

}  // namespace rdmesh
