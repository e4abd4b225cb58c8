#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "common/log.h"
#include "rdmesh/engine.h"
#include "rdmesh/v1/rdmesh.pb.h"
#include "worker/model_cache.h"

namespace rdmesh::server {

/// One Mesh call. The engine runs on a thread of its own; its per-face and progress callbacks
/// turn results into MeshEvent messages (faces split to at most ~1 MiB) and queue them; the
/// calling thread drains the queue and is the only one that writes to the stream. After the run
/// (on the engine thread, queued behind the faces), the welded faces' global ids (FaceNodeIds),
/// the edges and the Summary follow. With a triangle budget the engine meshes the model several
/// times, so faces are then sent after the run, from the final result. With levels of detail,
/// each level is such a run, after a LevelStarted event. Client cancellation, the call's deadline
/// and a failed write all cancel the engine's Context, which stops its workers within a second.
class MeshJob {
 public:
  struct Params {
    std::shared_ptr<const CachedModel> model;  ///< never null
    MeshOptions options;                       ///< validated, threads resolved
    bool with_uv = false;
    bool with_normals = false;
    bool with_topology = false;  ///< FaceNodeIds carry node_dim, node_entity and node_param
    bool with_edges = false;     ///< EdgePolyline events (MeshResult::edges) before the Summary
    /// FaceMesh.triangle_deviation (the engine's estimated deviation of every triangle).
    bool with_deviation = false;
    /// Levels of detail (ResolveLevels: relative deviations, coarsest first): the model is
    /// meshed once per level, each streamed after a LevelStarted event. Empty = one mesh.
    std::vector<double> levels;
    /// The server's --max-triangles: the run is stopped (RESOURCE_EXHAUSTED) when the faces
    /// streamed so far pass it. 0 = no limit.
    int64_t max_triangles = 0;
    /// Queued, unsent events larger than this make the engine's callback wait (back-pressure
    /// from a slow client), in bytes.
    std::size_t max_queued_bytes = 64u << 20;
    /// The call's deadline (system_clock::time_point::max() for none).
    std::chrono::system_clock::time_point deadline = std::chrono::system_clock::time_point::max();
    /// When the call arrived (for Summary.total_seconds).
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  };

  /// Writes one event to the client; false when the stream is broken.
  using WriteFn = std::function<bool(const ::rdmesh::v1::MeshEvent&)>;
  /// True once the client has cancelled the call (or the server is tearing it down).
  using CancelledFn = std::function<bool()>;

  /// `active_jobs` counts engine runs in progress (for GetServerStatus); not owned.
  MeshJob(Params params, const RequestLog* log, std::atomic<int>* active_jobs);

  /// Runs the engine and streams Progress, FaceMesh, FaceNodeIds, EdgePolyline (with_edges) and
  /// Summary events (the caller
  /// sends Started). Returns when the engine thread has finished: ok after the Summary, or why not
  /// (kCancelled, kDeadlineExceeded, kResourceExhausted, or the engine's error).
  Status Run(const WriteFn& write, const CancelledFn& cancelled);

  /// FaceMesh events written by Run.
  int64_t face_messages() const { return face_messages_; }
  /// The engine's summary (valid after a successful Run).
  const MeshSummary& summary() const { return summary_; }

 private:
  Params params_;
  const RequestLog* log_;
  std::atomic<int>* active_jobs_;
  int64_t face_messages_ = 0;
  MeshSummary summary_;
};

}  // namespace rdmesh::server
