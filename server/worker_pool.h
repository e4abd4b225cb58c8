#pragma once
// rdmeshd's worker processes: starting them, lending them to calls, and driving one call on a
// worker while watching for its death, the client's cancellation and the deadline. See
// docs/SERVICE.md, "Crash isolation".

#include <sys/types.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "frame.h"
#include "log.h"
#include "rdmesh/internal/worker.pb.h"
#include "rdmesh/status.h"

namespace rdmesh::server {

/// What every worker process gets (rdmeshd's --worker-* flags).
struct WorkerSettings {
  std::string executable;              ///< rdmeshd itself; started with --worker-fd
  uint64_t memory_bytes = 8ull << 30;  ///< RLIMIT_AS per worker; 0 = none
  double cpu_seconds = 300.0;          ///< CPU time one call may use; 0 = no limit
  uint64_t cache_bytes = 1ull << 30;   ///< parsed models kept per worker, in model file bytes
  uint64_t max_model_bytes = 256ull << 20;
  std::string store_dir;               ///< the persistent model store (--cache-dir); "" = none
  uint64_t store_bytes = 10ull << 30;  ///< its size limit (--cache-dir-bytes); 0 = none
  std::string log_format = "text";
  std::string log_level = "info";
};

/// One worker process. Owned by the pool while idle, by one call while lent.
class WorkerProcess {
 public:
  /// Starts `settings.executable --worker-fd 3 ...` with a socket to it on fd 3, in a process
  /// group of its own (a Ctrl-C on the daemon's terminal is the daemon's to handle).
  static Result<std::unique_ptr<WorkerProcess>> Start(const WorkerSettings& settings);
  ~WorkerProcess();  ///< kills and reaps a process still running
  WorkerProcess(const WorkerProcess&) = delete;
  WorkerProcess& operator=(const WorkerProcess&) = delete;

  pid_t pid() const { return pid_; }
  int fd() const { return fd_; }
  /// The buffered reader of fd(): every frame from the worker goes through it.
  FrameReader& reader() { return reader_; }

  /// Whether the worker has parsed this model (as far as the daemon knows: the worker's own
  /// cache may have evicted it since, and then parses it again).
  bool Holds(const std::string& model_id) const;
  void Remember(const std::string& model_id);

  /// Lets the process use `seconds` more CPU time from now (RLIMIT_CPU; passing it kills the
  /// process with SIGXCPU). False when the limit cannot be set.
  bool LimitCpu(double seconds);
  /// CPU seconds the process has used (user + system, all threads); -1 when unknown.
  double CpuSeconds() const;
  /// Resident memory, bytes; 0 when unknown.
  uint64_t RssBytes() const;

  /// True when the process has ended (it is then reaped).
  bool Exited();
  /// Waits up to `grace` for the process to end by itself, then kills it (SIGKILL); reaps it and
  /// returns its wait status.
  int Reap(std::chrono::milliseconds grace);
  /// Whether the pool killed the process (after Reap).
  bool killed() const { return killed_; }

 private:
  WorkerProcess(pid_t pid, int fd) : pid_(pid), fd_(fd), reader_(fd) {}

  pid_t pid_;
  int fd_;
  FrameReader reader_;
  bool reaped_ = false;
  bool killed_ = false;
  int wait_status_ = 0;
  std::deque<std::string> models_;  // most recent last, at most kRememberedModels
};

/// "SIGSEGV", "exit code 3", ...: how a process ended, from its wait status.
std::string DescribeExit(int wait_status);

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

/// What happened when a worker call ended.
struct CallEnd {
  Status status;
  /// False when the worker died or was killed: Discard it, never Release it.
  bool worker_ok = true;
  /// The worker died on its own (a crash, a limit): not a stop the daemon asked for.
  bool crashed = false;
  /// "load" or "mesh": where the call was when it ended.
  std::string phase = "load";
};

/// Runs `call` on `worker`: sends it, hands every reply but Done to `on_reply` (returning false
/// from it stops the call, e.g. when the client is gone), and returns how it ended. `cancelled`
/// is polled every 20 ms; when it turns true or the deadline passes, the worker is asked to stop
/// and, if it has not answered Done within a second, killed. A worker that dies answers the call
/// with the cause: a reader crash (`what` names the reader, e.g. "the STEP reader") is
/// kParseError, a crash while meshing kInvalidArgument, a CPU or memory limit
/// kResourceExhausted.
CallEnd CallWorker(WorkerProcess* worker, const WorkerSettings& settings,
                   const ::rdmesh::internal::ToWorker& call, const std::string& what,
                   const std::function<bool(const ::rdmesh::internal::FromWorker&)>& on_reply,
                   const std::function<bool()>& cancelled,
                   std::optional<std::chrono::steady_clock::time_point> deadline,
                   const RequestLog& log);

}  // namespace rdmesh::server
