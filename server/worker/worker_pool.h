#pragma once
// rdmeshd's pool of worker processes: starting them, and lending them to calls one at a time.
// See docs/SERVICE.md, "Crash isolation".

#include <sys/types.h>

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "rdmesh/status.h"
#include "worker/worker_process.h"

namespace rdmesh::server {

/// The workers. At most `max_workers` processes live at once; each serves one call at a time.
/// Thread-safe.
class WorkerPool {
 public:
  WorkerPool(WorkerSettings settings, int max_workers);
  ~WorkerPool();  ///< ends every idle worker
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  /// Starts `count` workers ahead of the first calls (and keeps that many after losses).
  Status Prestart(int count);

  /// An idle worker, preferably one that holds `model_id`; starts one when none is idle and
  /// fewer than max_workers live; otherwise waits for one. Null when `stop()` turns true
  /// (polled every 20 ms) or when a process cannot be started (`*error` then says why).
  std::unique_ptr<WorkerProcess> Acquire(const std::string& model_id,
                                         const std::function<bool()>& stop, Status* error);
  /// A worker whose call ended cleanly goes back to the idle ones.
  void Release(std::unique_ptr<WorkerProcess> worker);
  /// A worker that died, or was killed: reaped and counted; a replacement is started.
  void Discard(std::unique_ptr<WorkerProcess> worker);
  /// Ends every idle worker and refuses to start more (shutdown).
  void Close();

  const WorkerSettings& settings() const { return settings_; }
  int max_workers() const { return max_workers_; }
  int live() const;
  int idle() const;
  /// Workers that died or were killed since the start.
  int64_t lost() const;
  /// RSS of the idle workers and of every worker's pid (for status and the soak).
  std::vector<pid_t> pids() const;

 private:
  const WorkerSettings settings_;
  const int max_workers_;
  mutable std::mutex mutex_;
  std::condition_variable returned_;
  std::vector<std::unique_ptr<WorkerProcess>> idle_;
  std::vector<pid_t> pids_;  // every live worker
  int live_ = 0;
  int keep_ = 0;  // workers kept started (Prestart)
  int64_t lost_ = 0;
  bool closed_ = false;
};

}  // namespace rdmesh::server
