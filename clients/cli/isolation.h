#pragma once
// Runs a command in a child process, so that a crash of OCCT (a segfault in a reader or the
// mesher, which OCC_CATCH_SIGNALS cannot always catch) becomes an exit code and a message instead
// of a dead process. The child tells the parent which phase it is in through a pipe.
//
// `rdmesh` is a launcher (launcher.cpp) that starts this program, rdmesh-local, as that child and
// hands it the pipe (kPhaseFdVariable); run by hand, rdmesh-local forks a child of its own.
// RDMESH_NO_FORK=1 in the environment runs the command in the process itself (for debuggers).

#include <functional>
#include <string>

#include "supervise.h"

namespace rdmesh::cli {

/// Records that the run has entered `phase` and tells the parent process, when isolated.
/// Async-signal-safe (an atomic store and one write(2) of one byte).
void EnterPhase(Phase phase);

/// The phase last entered (kLoading before any); any thread may ask.
Phase CurrentPhase();

/// Runs `run` in a child process and returns its exit code; when the child dies by a signal,
/// returns on_death(how). SIGINT, SIGTERM and SIGHUP sent to this process are passed on to the
/// child (a second one kills it). Call it before any thread exists.
/// - Started by the launcher (kPhaseFdVariable set): this process is the child; returns run().
/// - Run again by the launcher after the child died (kDeathVariable set): returns on_death(how).
/// - Otherwise it forks. In the child, and when RDMESH_NO_FORK is set to anything but "" or "0"
///   or the fork fails, it returns run() itself.
int RunIsolated(const std::function<int()>& run,
                const std::function<int(const ChildDeath&)>& on_death);

/// "SIGSEGV" for SIGSEGV, "signal 40" for a signal without a name.
std::string SignalName(int signal);

}  // namespace rdmesh::cli
