#pragma once
// One meshing run at one absolute deviation, in the stages of BRepMesh: select faces, pcurves,
// edge grids, heal, mesh faces, place instances, assemble, summarise (and the edge lines). Edge
// grids are made once per edge, the faces in parallel worker threads, and assembly goes in face
// order, so the output does not depend on the thread count.

#include "rdmesh/context.h"
#include "rdmesh/mesh.h"
#include "rdmesh/options.h"
#include "rdmesh/status.h"

namespace rdmesh {

class FaceSurfaces;
class Model;

/// What a run builds besides the mesh.
enum class RunOutput {
  kMesh,              ///< the mesh alone (a triangle budget's trial runs)
  kMeshAndEdgeLines,  ///< and MeshResult::edges, from the run's pcurve table
};

/// One run at an absolute deviation (model units). `surfaces`: face evaluators lent by earlier
/// runs on the model (levels of detail), null = made per face. kInvalidArgument for a face id
/// out of range, the context's stop status, or the mesh.
Result<MeshResult> MeshAtDeviation(const Model& model, const MeshOptions& options, double deviation,
                                   Context* context, FaceSurfaces* surfaces = nullptr,
                                   RunOutput output = RunOutput::kMesh);

}  // namespace rdmesh
