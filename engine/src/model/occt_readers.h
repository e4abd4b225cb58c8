#pragma once
// OCCT's STEP and IGES readers, apart from the rest of the engine. Their toolkits (TKSTEP*,
// TKIGES, TKXDESTEP, TKXDEIGES) are a third of the dynamic loading of a program that links them,
// and rdmesh's own STEP reader (model/step) needs none of them. `rdmesh_engine` has them built
// in; a program linked to `rdmesh_engine_lean` (the rdmesh CLI) loads them from the module
// rdmesh_occt_readers.so beside its executable the first time a file needs them.
// Internal to the engine (model_readers.cpp).

#include <chrono>
#include <string>

#include "model/read_shape.h"
#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Changes whenever OcctReaderApi or what it passes changes: a module of another build is
/// refused rather than called.
constexpr int kOcctReaderApiVersion = 2;

/// The readers. Each runs under the caller's ReaderMutex, OCCT fault handlers and
/// OCC_CATCH_SIGNALS (ReadModelBytes); OCCT exceptions leave them as thrown.
struct OcctReaderApi {
  int version;
  /// OCCT's STEP reader (STEPCAFControl_Reader, names, colours and layers), after the checks
  /// that refuse a file before the transfer. `start` is when the load began (the "occt_parse"
  /// stage ends now), `fallback` why rdmesh's own reader passed the file on.
  Result<ReadShape> (*read_step)(const std::string& bytes, const std::string& name,
                                 const Context* context,
                                 std::chrono::steady_clock::time_point start,
                                 const std::string& fallback);
  /// OCCT's IGES reader; `path` is the file ("" writes a temporary one).
  Result<ReadShape> (*read_iges)(const std::string& bytes, const std::string& path,
                                 const std::string& name, const Context* context);
  /// CheckStepBytes (model_readers.h): OCCT's parser and its complaints, no transfer.
  Status (*check_step)(const std::string& bytes, const std::string& name);
};

/// "cannot read 'name': reason" (kParseError).
inline Status ParseError(const std::string& name, const std::string& reason) {
  return Status(StatusCode::kParseError, "cannot read '" + name + "': " + reason);
}

/// The readers: built in, or loaded from the module once per process. kInternal with the
/// module's path when it cannot be loaded.
Result<const OcctReaderApi*> OcctReaders();

}  // namespace rdmesh

/// The module's entry point (and the built-in one's, when linked in).
extern "C" const rdmesh::OcctReaderApi* rdmesh_occt_reader_api();
