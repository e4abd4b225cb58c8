// Loads one model file and prints what came of it on stdout, as "code faces\nmessage" (the
// StatusCode as a number, the face count of a loaded model, the status message).
// ModelTest.MutatedFilesNeverCrash runs it in a fresh process per file, as the service runs
// OCCT in worker processes: no state of one load (nor of the tests before it) reaches the next.
//
//   load_model_child FILE

#include <cstdio>

#include "rdmesh/engine.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s FILE\n", argv[0]);
    return 2;
  }
  auto model = rdmesh::LoadModel(argv[1]);
  std::printf("%d %d\n%s", static_cast<int>(model.status().code()),
              model.ok() ? rdmesh::GetModelInfo(**model).faces : 0,
              model.status().message().c_str());
  return 0;
}
