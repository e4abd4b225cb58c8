#pragma once
// Runs a command in a child process, so that a crash of OCCT (a segfault in a reader or the
// mesher, which OCC_CATCH_SIGNALS cannot always catch) becomes an exit code and a message instead
// of a dead process. The child tells the parent which phase it is in through a pipe.
//
// RDMESH_NO_FORK=1 in the environment runs the command in the process itself (for debuggers).

#include <functional>
#include <string>

namespace rdmesh::cli {

/// What the run is doing, for the message when it dies.
enum class Phase : char {
  kLoading = 'L',
  kMeshing = 'M',
  kWriting = 'W',
};

/// Records that the run has entered `phase` and tells the parent process, when isolated.
/// Async-signal-safe (an atomic store and one write(2) of one byte).
void EnterPhase(Phase phase);

/// The phase last entered (kLoading before any); any thread may ask.
Phase CurrentPhase();

/// How the child died.
struct ChildDeath {
  Phase phase;       ///< the last phase the child entered (kLoading before any)
  int signal;        ///< the signal that ended it
  bool interrupted;  ///< this process had passed on SIGINT, SIGTERM or SIGHUP to it
};

/// Runs `run` in a forked child and returns its exit code; when the child dies by a signal,
/// returns on_death(how). SIGINT, SIGTERM and SIGHUP sent to this process are passed on to the
/// child (a second one kills it). Call it before any thread exists. In the child, and when
/// RDMESH_NO_FORK is set to anything but "" or "0" or the fork fails, it returns run() itself.
int RunIsolated(const std::function<int()>& run,
                const std::function<int(const ChildDeath&)>& on_death);

/// "SIGSEGV" for SIGSEGV, "signal 40" for a signal without a name.
std::string SignalName(int signal);

}  // namespace rdmesh::cli
