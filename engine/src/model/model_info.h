#pragma once
// The ModelInfo summary of a loaded model. Internal to the engine (model.cpp).

#include "model/model.h"
#include "rdmesh/mesh.h"

namespace rdmesh {

/// Counts, bounding box, surface types, part names, instances and closedness of `model`, whose
/// shape, id maps and face_representative are already filled. Leaves name, format and the
/// length unit to the caller. Without `bounding_box`, bbox and diagonal stay 0 (the tight box is
/// the slow part: a caller that knows them sets them). May throw Standard_Failure on broken
/// topology.
ModelInfo ComputeModelInfo(const Model& model, bool bounding_box = true);

}  // namespace rdmesh
