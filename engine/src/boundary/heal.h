#pragma once
// Healing of the edge grids, between edge discretisation and face meshing: an edge grid made for
// its curve alone can be too coarse for a face that uses it. A chord of a small circle cuts
// across a nearby hole, two one-segment edges close a loop of no area. Every face's boundary
// loops are checked in (u,v), and the grid segments involved in a conflict are split, in every
// face that shares them (the grids stay shared, so the mesh stays watertight), until none is
// left or a conflict cannot be split any further.

#include <vector>

#include "boundary/edge_grids.h"
#include "boundary/pcurves.h"
#include "geometry/singular_lines.h"
#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh {

class Model;

struct HealStats {
  int rounds = 0;  ///< checking rounds run
  int splits = 0;  ///< grid segments split (counted once per edge TShape)
};

/// Splits grid segments (indexed by edge id - 1) until the domains of `faces` (face ids) have no
/// DomainConflict, or no split helps any more. Faces whose domain cannot be built are left to
/// fail with their reason when they are meshed. `nurbs` as in FaceJob. Only fails when stopped.
Status HealEdgeGrids(const Model& model, const FacePcurves& pcurves, const std::vector<int>& faces,
                     bool nurbs, int threads, Context* context, std::vector<EdgeGrid>* grids,
                     HealStats* stats = nullptr);

/// Per face id - 1: the singular lines of `faces` (FindSingularLines), looked for in parallel;
/// none with `nurbs` (the conversion's parameters are not the pcurves') or for other faces.
std::vector<std::vector<SingularLine>> FaceSingularLines(const Model& model,
                                                         const FacePcurves& pcurves,
                                                         const std::vector<int>& faces, bool nurbs,
                                                         int threads);

/// Gives every edge grid a point where the edge's pcurve on a face crosses one of that face's
/// singular lines (`lines` per face id - 1), in every edge that shares the edge's TShape: a line
/// can only be kept out of the triangles between two boundary nodes on it, and the neighbouring
/// faces take the same point, so the mesh stays watertight. A crossing that a grid point already
/// lies on adds nothing. Returns how many points were added.
int PinSingularLines(const Model& model, const FacePcurves& pcurves,
                     const std::vector<std::vector<SingularLine>>& lines,
                     std::vector<EdgeGrid>* grids);

}  // namespace rdmesh
