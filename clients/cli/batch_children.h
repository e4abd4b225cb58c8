#pragma once
// The child processes of `rdmesh batch`, one per file: each in a process group of its own (so a
// kill reaches whatever it started, and the terminal's Ctrl-C reaches only the batch), with an
// address-space cap, a deadline enforced with SIGKILL, its stdout and stderr captured, and
// killed by the kernel should the batch itself die (PR_SET_PDEATHSIG).

#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <cstdint>
#include <string>
#include <vector>

#include "rdmesh/status.h"

namespace rdmesh::cli {

/// How one child ended.
struct ChildResult {
  int id = 0;              ///< the id given to Start()
  int exit_code = -1;      ///< its exit code when it exited, else -1
  int signal = 0;          ///< the signal that ended it, else 0
  bool timed_out = false;  ///< the pool killed it at its deadline
  bool stopped = false;    ///< KillAll() killed it
  std::string out;         ///< its whole stdout
  std::string err;         ///< the end of its stderr (the last 16 KiB or more)
  double seconds = 0.0;    ///< wall time from Start() to its end
};

/// Runs children and waits for them. Blocks SIGCHLD, SIGINT, SIGTERM and SIGHUP in this process
/// while it lives, and reads them in Wait(); for single-threaded processes.
class ChildPool {
 public:
  ChildPool();
  /// Kills the children left (SIGKILL to their groups) and restores the signal mask.
  ~ChildPool();
  ChildPool(const ChildPool&) = delete;
  ChildPool& operator=(const ChildPool&) = delete;

  /// The program run in the forked child instead of executing argv[0]: this program's own
  /// main, which then costs no dynamic loading per child. Only for a process with no other
  /// thread, as the pool's is.
  using Entry = int (*)(int argc, char** argv);

  /// Starts `argv` (argv[0] an absolute path) with exactly the environment `env` ("NAME=value").
  /// `timeout_seconds` > 0: its group is killed with SIGKILL that long after the start.
  /// `memory_limit` > 0: its RLIMIT_AS, in bytes. kInternal when fork or pipe fail; a program
  /// that cannot be executed ends with exit code 127 and the reason on its stderr.
  /// With `entry`, the child runs entry(argv) in the forked copy of this process (argv[0] is
  /// then only its name) and exits with its result.
  Status Start(int id, const std::vector<std::string>& argv, const std::vector<std::string>& env,
               double timeout_seconds, uint64_t memory_limit, Entry entry = nullptr);

  int running() const { return static_cast<int>(children_.size()); }

  /// Waits until a child ends, a signal arrives or `max_seconds` pass, enforcing the deadlines
  /// meanwhile; returns the children that ended. `*signal` is SIGINT, SIGTERM or SIGHUP when one
  /// arrived, else 0.
  std::vector<ChildResult> Wait(double max_seconds, int* signal);

  /// Kills every running child's group and returns them, each with `stopped`.
  std::vector<ChildResult> KillAll();

 private:
  struct Child {
    ChildResult result;
    pid_t pid = 0;
    int out_fd = -1;
    int err_fd = -1;
    std::chrono::steady_clock::time_point start;
    std::chrono::steady_clock::time_point deadline;
    bool has_deadline = false;
  };

  // Reads what `child`'s pipes hold now; closes a pipe at its end.
  static void Drain(Child* child);
  // Reaps `child`, which has ended or been killed: kills what is left of its group first.
  static ChildResult Reap(Child* child);

  std::vector<Child> children_;
  int signal_fd_ = -1;
  sigset_t saved_mask_;
};

}  // namespace rdmesh::cli
