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

/// Per edge id - 1: 1 for a circle whose every face is a plane or bends toward the circle's
/// centre (an offset along its bend side moves away from the axis), of the edges `edge_needed`
/// marks, with both vertices of their own: every edge at each vertex is such a circle or an edge
/// of one face only (a seam). Vertices move with their circle (MoveCircleGrids).
std::vector<uint8_t> OffsetCircles(const Model& model, const FacePcurves& pcurves,
                                   const std::vector<int8_t>& bend_sides,
                                   const std::vector<bool>& edge_needed);

/// Moves every node of the circles `circles` marks, their vertices included, `distance` away
/// from the circle's axis, within its plane; the vertices' new points into *vertices (vertex id
/// to point), for the face domains (which take vertices from the model).
void MoveCircleGrids(const Model& model, const std::vector<uint8_t>& circles, double distance,
                     std::vector<EdgeGrid>* grids, std::map<int, Vec3>* vertices);

}  // namespace rdmesh
