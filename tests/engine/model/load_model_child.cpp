// Loads one model file and prints what came of it on stdout, as "code faces\nmessage" (the
// StatusCode as a number, the face count of a loaded model, the status message).
// ModelTest.MutatedFilesNeverCrash runs it in a fresh process per file, as the service runs
// OCCT in worker processes: no state of one load (nor of the tests before it) reaches the next.
//
//   load_model_child FILE

#include <cstdio>

#include "rdmesh/engine.h"

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#endif

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s FILE\n", argv[0]);
    return 2;
  }
#if defined(__SANITIZE_ADDRESS__)
  // Not leak-checked: on some broken files OCCT's STEP reader never frees its work session (its
  // objects hold handles to each other, and to our progress indicator), in every frame of
  // OCCT's reader. This program asks whether a load crashes or hangs; the ASan engine_tests
  // check leaks on their own loads of valid files.
  __lsan_disable();
#endif
  auto model = rdmesh::LoadModel(argv[1]);
  std::printf("%d %d\n%s", static_cast<int>(model.status().code()),
              model.ok() ? rdmesh::GetModelInfo(**model).faces : 0,
              model.status().message().c_str());
  return 0;
}
