#pragma once
// The parent's side of a run in a child process: it follows the phase the child reports and
// passes on signals until the child ends. Plain C library calls only, so that the launcher
// (launcher.cpp) links it without the C++ library: every library loaded is start-up time on
// every run.

#include <signal.h>
#include <sys/types.h>

namespace rdmesh::cli {

/// What the run is doing, for the message when it dies.
enum class Phase : char {
  kLoading = 'L',
  kMeshing = 'M',
  kWriting = 'W',
};

/// How the child died.
struct ChildDeath {
  Phase phase;       ///< the last phase the child entered (kLoading before any)
  int signal;        ///< the signal that ended it
  bool interrupted;  ///< this process had passed on SIGINT, SIGTERM or SIGHUP to it
};

/// The launcher hands rdmesh-local the write end of the phase pipe in this variable (a file
/// descriptor number): rdmesh-local then runs in its own process and reports its phases there.
inline constexpr char kPhaseFdVariable[] = "RDMESH_PHASE_FD";
/// When the child died by a signal, the launcher runs rdmesh-local again with the same arguments
/// and this variable ("PHASE:SIGNAL:INTERRUPTED", FormatDeath) to print the message and exit.
inline constexpr char kDeathVariable[] = "RDMESH_CHILD_DEATH";

/// RDMESH_NO_FORK is set to anything but "" or "0": the run stays in one process.
bool ForkDisabled();

/// Blocks SIGINT, SIGTERM and SIGHUP until Supervise has its handlers in place, so that a
/// signal that comes during the start of the child is passed on, not lost; returns the old mask.
sigset_t BlockForwardedSignals();

/// Reads the phase bytes `child` writes to `phase_fd` (the pipe's read end; closed here) until
/// it exits, passing on SIGINT, SIGTERM and SIGHUP sent to this process (a second one kills it),
/// and reaps it; restores `saved_mask` once the handlers are in place. Returns true with
/// *exit_code when the child exited, false with *death when a signal ended it.
bool Supervise(pid_t child, int phase_fd, const sigset_t& saved_mask, int* exit_code,
               ChildDeath* death);

/// Writes "PHASE:SIGNAL:INTERRUPTED" into `out` (at least 32 bytes) for kDeathVariable.
void FormatDeath(const ChildDeath& death, char* out, int size);

/// Reads FormatDeath's text; false when it is not one.
bool ParseDeath(const char* text, ChildDeath* death);

}  // namespace rdmesh::cli
