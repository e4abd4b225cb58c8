#include "progress.h"

#include <unistd.h>

#include <cstdio>

namespace rdmesh::cli {

namespace {

const char* StageName(Progress::Stage stage) {
  switch (stage) {
    case Progress::Stage::kLoading:
      return "loading";
    case Progress::Stage::kEdges:
      return "edges";
    case Progress::Stage::kFaces:
      return "faces";
    case Progress::Stage::kAssembly:
      return "assembling";
    case Progress::Stage::kDone:
      return "done";
  }
  return "";
}

}  // namespace

TerminalProgress::TerminalProgress(bool enabled)
    : enabled_(enabled && ::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

void TerminalProgress::Update(const Progress& progress) {
  if (!enabled_) return;
  auto now = std::chrono::steady_clock::now();
  if (now - start_ < std::chrono::seconds(1)) return;
  if (shown_ && now - last_ < std::chrono::milliseconds(100) && progress.done != progress.total)
    return;
  last_ = now;
  shown_ = true;
  double seconds = std::chrono::duration<double>(now - start_).count();
  if (progress.total > 0) {
    std::fprintf(stderr, "\r\033[Kmeshing: %s %lld/%lld (%.0f s)", StageName(progress.stage),
                 static_cast<long long>(progress.done), static_cast<long long>(progress.total),
                 seconds);
  } else {
    std::fprintf(stderr, "\r\033[Kmeshing: %s (%.0f s)", StageName(progress.stage), seconds);
  }
  std::fflush(stderr);
}

void TerminalProgress::Finish() {
  if (!shown_) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
  shown_ = false;
}

}  // namespace rdmesh::cli
