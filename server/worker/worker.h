#pragma once
// The worker process: the side of rdmeshd that runs OCCT on untrusted model bytes. The daemon
// starts it as `rdmeshd --worker-fd N ...` and talks to it over that socket
// (proto/rdmesh/internal/worker.proto). A crash, a hang or an out-of-memory in the worker costs
// the daemon one call and one process, never the service.

#include <cstdint>
#include <string>

namespace rdmesh::server {

struct WorkerConfig {
  int fd = -1;                ///< the socket to the daemon
  uint64_t cache_bytes = 0;   ///< parsed models kept, counted in model file bytes
  uint64_t memory_bytes = 0;  ///< RLIMIT_AS of this process; 0 = none
  uint64_t max_model_bytes = 256ull << 20;
  std::string store_dir;     ///< the persistent model store shared by all workers; "" = none
  uint64_t store_bytes = 0;  ///< its size limit; 0 = none
};

/// The exit code of a worker that ended near its memory limit through std::terminate (a thread
/// or an allocation failed where no exception can be caught, e.g. inside TBB's own threads):
/// the daemon reports it as the memory limit, not as a crash.
constexpr int kWorkerOutOfMemoryExit = 86;

/// Serves calls from the daemon, one at a time, until the socket closes. Parsed models stay in
/// the worker (a bounded LRU cache), so that meshing the same model again does not parse it again.
/// Also ends, at once, when the daemon dies (its end of the socket closes). Returns the process
/// exit code.
int RunWorker(const WorkerConfig& config);

}  // namespace rdmesh::server
