#pragma once
// One rdmeshd worker process, as the daemon sees it: started with a socket on fd 3, in a process
// group of its own, and reaped or killed when done. See docs/SERVICE.md, "Crash isolation".

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>

#include "rdmesh/status.h"
#include "wire/frame.h"

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

}  // namespace rdmesh::server
