#pragma once

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/log.h"
#include "daemon/job_limiter.h"
#include "daemon/model_index.h"
#include "rdmesh/options.h"
#include "rdmesh/v1/rdmesh.grpc.pb.h"
#include "worker/call_worker.h"
#include "worker/worker_pool.h"

namespace rdmesh::server {

/// Limits and settings of the service (rdmeshd's flags).
struct ServiceConfig {
  int threads = 0;                          ///< engine threads per job; 0 = all cores
  int max_jobs = 2;                         ///< meshing jobs running at once
  int max_queue = 16;                       ///< jobs waiting for a slot before RESOURCE_EXHAUSTED
  uint64_t max_model_bytes = 256ull << 20;  ///< largest model file, bytes
  int64_t max_triangles = 50'000'000;       ///< largest result, triangles; 0 = no limit
  uint64_t cache_bytes = 1ull << 30;        ///< model cache size, file bytes
  std::string spool_dir;                    ///< where uploaded bytes are kept for the workers
  int max_workers = 0;                      ///< worker processes; 0 = max_jobs + 2
  WorkerSettings worker;                    ///< limits of each worker process
  std::string token;                        ///< bearer token; empty = no authentication
  std::string data_root;                    ///< root of server-side reads; empty = off
  std::string version = "0.1.0";
};

/// The rdmesh.v1.Rdmesh service. Handlers run on gRPC's sync-server threads. Everything that
/// reads or meshes a model runs in a worker process (WorkerPool): a Mesh call borrows a worker
/// (preferably one that has parsed the model already), forwards its events to the client, and
/// returns it; a worker that crashes or passes a limit fails that call only and is replaced.
/// Thread-safe.
class RdmeshService final : public ::rdmesh::v1::Rdmesh::Service {
 public:
  explicit RdmeshService(ServiceConfig config);

  grpc::Status UploadModel(grpc::ServerContext* context,
                           grpc::ServerReader<::rdmesh::v1::ModelChunk>* reader,
                           ::rdmesh::v1::ModelInfo* response) override;
  grpc::Status GetModelInfo(grpc::ServerContext* context, const ::rdmesh::v1::ModelRef* request,
                            ::rdmesh::v1::ModelInfo* response) override;
  grpc::Status Mesh(grpc::ServerContext* context, const ::rdmesh::v1::MeshRequest* request,
                    grpc::ServerWriter<::rdmesh::v1::MeshEvent>* writer) override;
  grpc::Status GetServerStatus(grpc::ServerContext* context,
                               const ::rdmesh::v1::GetServerStatusRequest* request,
                               ::rdmesh::v1::ServerStatus* response) override;

  /// Shutdown has begun: refuse new jobs (UNAVAILABLE), let running ones finish.
  void BeginShutdown();
  /// Mesh calls whose engine run has not returned yet.
  int active_jobs() const { return active_jobs_.load(); }
  int queued_jobs() const { return limiter_.queued(); }
  /// Mesh calls holding or waiting for a job slot (drained before shutdown).
  int busy_jobs() const { return limiter_.running() + limiter_.queued(); }
  /// Ends the idle workers and starts no more (after the drain).
  void StopWorkers() { pool_.Close(); }
  /// Starts the first workers; an error when none can be started.
  Status StartWorkers();

 private:
  /// The request's log, with its id (the client's x-request-id, or a new one), which is also
  /// sent back as x-request-id initial metadata. `quiet` logs the call at debug level.
  RequestLog StartRequest(grpc::ServerContext* context, const char* method,
                          bool quiet = false) const;
  /// UNAUTHENTICATED unless the call carries the bearer token (when one is configured).
  grpc::Status Authorize(grpc::ServerContext* context, const RequestLog& log) const;
  /// The model a ModelRef names, parsing inline bytes or a server-side file on a worker.
  Result<std::shared_ptr<const StoredModel>> Resolve(grpc::ServerContext* context,
                                                     const ::rdmesh::v1::ModelRef& ref,
                                                     const RequestLog& log, bool* cached);
  /// Indexes the model these bytes hold, parsing them on a worker unless already indexed.
  Result<std::shared_ptr<const StoredModel>> Accept(grpc::ServerContext* context,
                                                    const std::string& bytes,
                                                    const std::string& name, ModelFormat format,
                                                    const RequestLog& log, bool* cached);
  /// A worker whose call has ended: back to the pool, holding `model_id`, when it is fine;
  /// discarded (and replaced) when it died or was killed.
  void ReturnWorker(std::unique_ptr<WorkerProcess> worker, const CallEnd& end,
                    const std::string& model_id);

  /// What a Mesh request asks for, checked.
  struct MeshPlan {
    MeshOptions options;         ///< validated; threads resolved against the server's
    std::vector<double> levels;  ///< levels of detail, coarsest first; empty = one mesh
  };
  /// Mesh, validate: the request's options and levels of detail, by the engine's rules and
  /// the server's limits.
  Result<MeshPlan> PlanMesh(const ::rdmesh::v1::MeshRequest& request) const;
  /// Mesh, admit: OK once the call holds a job slot (the caller then owns it); otherwise the
  /// queue is full, the call was cancelled while queued, or the server is shutting down.
  grpc::Status Admit(const std::function<bool()>& cancelled);
  /// Mesh, relay: the Started event the worker's Ready becomes. `loaded` is the worker's
  /// description of its load (cached, load_seconds, from_store). Logs what is meshed.
  ::rdmesh::v1::MeshEvent StartedEvent(const MeshPlan& plan, const StoredModel& model,
                                       const ::rdmesh::v1::ModelInfo& loaded, double queue_seconds,
                                       pid_t worker, const RequestLog& log) const;

  const ServiceConfig config_;
  const int resolved_threads_;
  ModelIndex index_;
  WorkerPool pool_;
  JobLimiter limiter_;
  std::atomic<int> active_jobs_{0};
  std::atomic<int> active_parses_{0};
  std::atomic<int64_t> jobs_completed_{0};
  std::atomic<bool> shutting_down_{false};
  const std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
};

}  // namespace rdmesh::server
