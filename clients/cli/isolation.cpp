#include "isolation.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>

namespace rdmesh::cli {

namespace {

// The write end of the phase pipe in the child; -1 elsewhere.
int g_phase_fd = -1;
std::atomic<Phase> g_phase{Phase::kLoading};

// The phase pipe the launcher handed over (kPhaseFdVariable), or -1. The variable is removed
// so that no process this one starts takes it for its own.
int InheritedPhaseFd() {
  const char* value = std::getenv(kPhaseFdVariable);
  if (value == nullptr) return -1;
  char* end = nullptr;
  long fd = std::strtol(value, &end, 10);
  unsetenv(kPhaseFdVariable);
  struct stat info;
  if (end == value || *end != '\0' || fd < 3 || fd > 1 << 20 || fstat(fd, &info) != 0 ||
      !S_ISFIFO(info.st_mode))
    return -1;
  fcntl(static_cast<int>(fd), F_SETFD, FD_CLOEXEC);
  return static_cast<int>(fd);
}

// Runs `run` with its phases going to `fd`, the write end of a pipe the parent reads.
int RunReporting(const std::function<int()>& run, int fd) {
  g_phase_fd = fd;
  int code = run();
  close(fd);
  g_phase_fd = -1;
  return code;
}

}  // namespace

void EnterPhase(Phase phase) {
  g_phase.store(phase);
  if (g_phase_fd < 0) return;
  char byte = static_cast<char>(phase);
  ssize_t written = write(g_phase_fd, &byte, 1);
  (void)written;  // a parent that went away cannot be told
}

Phase CurrentPhase() { return g_phase.load(); }

int RunIsolated(const std::function<int()>& run,
                const std::function<int(const ChildDeath&)>& on_death) {
  if (const char* text = std::getenv(kDeathVariable)) {
    ChildDeath death;
    const bool known = ParseDeath(text, &death);
    unsetenv(kDeathVariable);
    if (known) return on_death(death);
  }
  if (int fd = InheritedPhaseFd(); fd >= 0) return RunReporting(run, fd);
  if (ForkDisabled()) return run();
  int pipe_fds[2];
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) return run();
  const sigset_t saved_mask = BlockForwardedSignals();
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  pid_t child = fork();
  if (child <= 0) {
    sigprocmask(SIG_SETMASK, &saved_mask, nullptr);
    close(pipe_fds[0]);
    if (child < 0) {
      close(pipe_fds[1]);
      return run();
    }
    return RunReporting(run, pipe_fds[1]);
  }

  close(pipe_fds[1]);
  int code = 0;
  ChildDeath death;
  if (Supervise(child, pipe_fds[0], saved_mask, &code, &death)) return code;
  return on_death(death);
}

std::string SignalName(int signal) {
  const char* name = sigabbrev_np(signal);
  return name != nullptr ? std::string("SIG") + name : "signal " + std::to_string(signal);
}

}  // namespace rdmesh::cli
