#pragma once
// Names of model formats for messages (kept out of engine.h so that few files depend on it).

#include "rdmesh/model_info.h"

namespace rdmesh {

/// "the STEP reader", "the IGES reader", "the BREP reader" ("the model reader" for kAuto): what
/// reads a format, for crash and error messages of the CLI and the service.
const char* ReaderName(ModelFormat format);

}  // namespace rdmesh
