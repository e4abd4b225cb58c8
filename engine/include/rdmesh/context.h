#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>

#include "rdmesh/status.h"

namespace rdmesh {

struct FaceMesh;

/// Wall seconds on the steady clock since `start`: how the engine, the CLI and the service time
/// their stages.
inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Progress of a run: what stage it is in and how many faces are done.
struct Progress {
  enum class Stage { kLoading, kEdges, kFaces, kAssembly, kDone };
  Stage stage = Stage::kLoading;
  int64_t done = 0;   ///< faces (or edges) finished
  int64_t total = 0;  ///< faces (or edges) to do
};

/// Carries cancellation, a deadline and progress callbacks into a run. The engine polls it
/// between faces and inside long loops; a stop request ends the run within well under a second.
/// Thread-safe: Cancel() may be called from any thread while a run uses the context.
class Context {
 public:
  using ProgressFn = std::function<void(const Progress&)>;
  /// Called once per face as soon as it is meshed, from a worker thread; calls are serialised
  /// (never two at once), in completion order (not face order).
  using FaceDoneFn = std::function<void(const FaceMesh&)>;

  Context() = default;
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  void Cancel() { cancelled_.store(true); }
  bool cancelled() const { return cancelled_.load(); }

  /// Stop the run when this point in time passes. The earliest deadline set wins: a later one
  /// (say the engine's timeout_seconds after a caller's shorter deadline) leaves it unchanged.
  void SetDeadline(std::chrono::steady_clock::time_point deadline);
  /// Convenience: SetDeadline(now + seconds) (ignored when seconds <= 0).
  void SetTimeout(double seconds);

  /// True when the run should stop (cancelled or past its deadline). Cheap; call often.
  bool ShouldStop() const;
  /// Ok, or kCancelled / kDeadlineExceeded.
  Status StopStatus() const;

  /// Whether a load keeps the model's XCAF document (names, colours and the assembly tree, which
  /// the .glb and .obj writers and the model store carry). On by default. Off, a STEP file whose
  /// product structure is plain (no assembly, every root a named shape of its own) loads without
  /// OCCT's document framework: the same shape, ids and ModelInfo, but no document. The rdmesh
  /// CLI turns it off for the formats that carry no colours, where loading that framework was
  /// half of the process's start-up.
  void set_keep_document(bool keep) { keep_document_ = keep; }
  bool keep_document() const { return keep_document_; }

  void set_progress_callback(ProgressFn fn) { progress_ = std::move(fn); }
  void set_face_callback(FaceDoneFn fn) { face_done_ = std::move(fn); }

  /// Engine side: report progress / a finished face (serialised internally).
  void ReportProgress(const Progress& progress);
  void ReportFace(const FaceMesh& face);

 private:
  std::atomic<bool> cancelled_{false};
  bool keep_document_ = true;
  std::atomic<int64_t> deadline_ns_{0};  // steady_clock ns since epoch; 0 = none
  ProgressFn progress_;
  FaceDoneFn face_done_;
  std::mutex callback_mutex_;
};

}  // namespace rdmesh
