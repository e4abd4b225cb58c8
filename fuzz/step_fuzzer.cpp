// libFuzzer target: the model reader on arbitrary bytes taken as a STEP file.
// Built with -DRDMESH_FUZZ=ON and clang (scripts/fuzz_smoke.sh, bench/robustness/fuzz_long.sh).
// RDMESH_FUZZ_LAST_INPUT=FILE writes each input to FILE before it runs: a fault inside OCCT while
// its own signal handlers are installed kills the process before libFuzzer can save the input.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include "rdmesh/engine.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  static const char* const last_input = std::getenv("RDMESH_FUZZ_LAST_INPUT");
  if (last_input != nullptr) std::ofstream(last_input, std::ios::binary) << bytes;
  rdmesh::Result<std::shared_ptr<const rdmesh::Model>> model =
      rdmesh::LoadModelFromBytes(bytes, rdmesh::ModelFormat::kStep, "fuzz.step");
  if (model.ok()) {
    rdmesh::ModelInfo info = rdmesh::GetModelInfo(**model);
    if (info.faces <= 0) __builtin_trap();  // a loaded model always has faces
  } else if (model.status().message().rfind("cannot read 'fuzz.step'", 0) != 0 &&
             model.status().message().find("'fuzz.step' holds no faces") == std::string::npos) {
    __builtin_trap();  // every refusal names the file
  }
  return 0;
}
