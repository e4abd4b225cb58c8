#pragma once
// The OCCT readers behind LoadModel; format detection (FormatFromContent, ResolveFormat) is
// public, in rdmesh/model_info.h. Internal to the engine (model.cpp).

#include <string>

#include "model/read_shape.h"
#include "rdmesh/context.h"
#include "rdmesh/model_info.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Reads `bytes` (the whole file) as `format` (not kAuto). `path` is the file on disk when there
/// is one (IGES is read from a file; a temporary one is written when `path` is empty). `name`
/// is used in messages. Checks the header and trailer first, so truncated files fail cleanly.
/// kParseError with "cannot read 'name': reason", or the context's stop status.
/// Thread-safe: all OCCT reading is serialised by one process-wide mutex.
Result<ReadShape> ReadModelBytes(const std::string& bytes, ModelFormat format,
                                 const std::string& path, const std::string& name,
                                 const Context* context);

/// The checks ReadModelBytes makes on STEP bytes before OCCT transfers them: the text scan of
/// step_precheck.h, then OCCT's parser and its complaints about references. Parses, does not
/// transfer. Ok, or the kParseError ReadModelBytes would return. For tests over many files.
Status CheckStepBytes(const std::string& bytes, const std::string& name);

}  // namespace rdmesh
