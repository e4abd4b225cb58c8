#pragma once
// Loading a module of the engine (a shared object beside the executable) that a program linked to
// rdmesh_engine_lean loads the first time it needs it: OCCT's readers (occt_readers.h) and OCCT's
// document framework (xcaf_api.h). Internal to the engine.

#include <string>

#include "rdmesh/status.h"

namespace rdmesh {

/// Loads `file` from the executable's folder and calls its extern "C" `entry`, which returns the
/// module's table of entry points: a struct whose first member is its int version, which must
/// be `version` (a module of another build is refused rather than called). `what` names the
/// module in errors: kResourceExhausted when the loader cannot map it (a memory limit), else
/// kInternal.
Result<const void*> LoadEngineModule(const std::string& file, const char* entry,
                                     const std::string& what, int version);

}  // namespace rdmesh
