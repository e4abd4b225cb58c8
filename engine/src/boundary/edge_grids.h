#pragma once
// The edge grids of a whole model: every B-rep edge discretised once (edges that are the same
// TShape under several locations share their parameters), in parallel.

#include <vector>

#include "core/geom.h"
#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh {

class FacePcurves;
class Model;

/// One B-rep edge's grid: curve parameters and world points, endpoints at the vertices.
struct EdgeGrid {
  std::vector<double> t;
  std::vector<Vec3> xyz;
  int first_vertex = 0;  ///< vertex id at t.front()
  int last_vertex = 0;   ///< vertex id at t.back()
  bool degenerate = false;
  double moved = 0;  ///< how far MoveEdgeGrids moved its nodes off the curve (off-surface runs)
};

struct GridCriteria {
  double max_deviation = 0;  ///< model units; 0 = off
  double rd_tolerance = 0;   ///< edge RD; 0 = off
  double max_length = 0;
  double min_length = 0;
  /// Sagitta allowed on edges next to doubly curved faces, as a fraction of max_deviation: a
  /// triangle with a side of length a on a sphere deviates a^2/6 k where the side's own sagitta
  /// is a^2/8 k, so its boundary segments should be shorter than a pure curve criterion asks.
  double curved_face_factor = 0.8;
  /// On a face whose width, measured as area / perimeter (w / 2 for a strip of width w), lies
  /// between max_deviation and max_deviation / this, the tangential part of an edge chord's
  /// sagitta (how far the chord strays within the face: over a hole, or short of the rim)
  /// stays below this fraction of that width. A chord then takes or adds at most about 2/3 of
  /// this fraction of its share of the face's area. 0 = off.
  double narrow_face_fraction = 0.5;
  /// Per edge id - 1, a factor on max_deviation for that edge alone (the circles an off-surface
  /// run moves off their curve: run/off_surface.h); empty = 1 for every edge.
  std::vector<double> edge_scale;
};

/// Grids indexed by edge id - 1. `edge_needed[e-1]` false skips an edge (face subsets).
Status BuildEdgeGrids(const Model& model, const FacePcurves& pcurves, const GridCriteria& criteria,
                      int threads, const std::vector<bool>& edge_needed, Context* context,
                      std::vector<EdgeGrid>* grids);

}  // namespace rdmesh
