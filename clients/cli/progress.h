#pragma once
// A one-line progress display on stderr for long runs.

#include <chrono>

#include "rdmesh/context.h"

namespace rdmesh::cli {

/// Shows "meshing: faces done/total" on stderr, overwritten in place. Only when `enabled` and
/// stderr is a terminal, only once the run is older than one second, at most 10 times a second.
/// Update() may be called from any thread but not concurrently (Context serialises callbacks).
class TerminalProgress {
 public:
  explicit TerminalProgress(bool enabled);
  ~TerminalProgress() { Finish(); }
  TerminalProgress(const TerminalProgress&) = delete;
  TerminalProgress& operator=(const TerminalProgress&) = delete;

  void Update(const Progress& progress);
  /// Erases the progress line if one was shown.
  void Finish();

 private:
  bool enabled_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace rdmesh::cli
