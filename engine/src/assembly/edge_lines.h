#pragma once
// The edge lines of an assembled mesh (BuildEdgeLines, rdmesh/engine.h), with a run's pcurve
// table: a meshing run builds them before it lets go of its pcurves, so each edge's faces are
// looked up in the table rather than asked of OCCT again.

#include <vector>

#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

class FacePcurves;
class Model;

/// BuildEdgeLines(model, mesh, sharp_angle, threads), the pcurves and seams of the faces taken
/// from `pcurves` (a face it was not built for is asked of OCCT): the same lines.
Result<std::vector<EdgeLine>> BuildEdgeLines(const Model& model, const Mesh& mesh,
                                             double sharp_angle, int threads,
                                             const FacePcurves& pcurves);

}  // namespace rdmesh
