#include "isolation.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <iterator>

namespace rdmesh::cli {

namespace {

// The write end of the phase pipe in the child; -1 elsewhere.
int g_phase_fd = -1;
std::atomic<Phase> g_phase{Phase::kLoading};

// The child's pid in the parent while it runs, and how many signals were passed on to it.
volatile sig_atomic_t g_child = 0;
volatile sig_atomic_t g_forwarded = 0;

constexpr int kForwarded[] = {SIGINT, SIGTERM, SIGHUP};

void Forward(int signal) {
  pid_t child = g_child;
  if (child <= 0) return;
  kill(child, g_forwarded == 0 ? signal : SIGKILL);
  g_forwarded = g_forwarded + 1;
}

bool ForkDisabled() {
  const char* value = std::getenv("RDMESH_NO_FORK");
  return value != nullptr && value[0] != '\0' && std::strcmp(value, "0") != 0;
}

// Reads phase bytes until the child closes the pipe (it exits); returns the last one.
Phase FollowPhases(int fd) {
  Phase phase = Phase::kLoading;
  char bytes[64];
  for (;;) {
    ssize_t count = read(fd, bytes, sizeof(bytes));
    if (count > 0) {
      phase = static_cast<Phase>(bytes[count - 1]);
    } else if (count < 0 && errno == EINTR) {
      continue;
    } else {
      return phase;
    }
  }
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
  if (ForkDisabled()) return run();
  int pipe_fds[2];
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) return run();
  // Signals wait until the parent's forwarding handlers are in place; nothing is buffered twice.
  sigset_t forwarded, saved_mask;
  sigemptyset(&forwarded);
  for (int signal : kForwarded) sigaddset(&forwarded, signal);
  sigprocmask(SIG_BLOCK, &forwarded, &saved_mask);
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
    g_phase_fd = pipe_fds[1];
    int code = run();
    close(pipe_fds[1]);
    g_phase_fd = -1;
    return code;
  }

  close(pipe_fds[1]);
  g_child = child;
  struct sigaction forward = {}, saved[std::size(kForwarded)];
  forward.sa_handler = Forward;
  sigemptyset(&forward.sa_mask);
  for (size_t i = 0; i < std::size(kForwarded); ++i) sigaction(kForwarded[i], &forward, &saved[i]);
  sigprocmask(SIG_SETMASK, &saved_mask, nullptr);

  ChildDeath death{FollowPhases(pipe_fds[0]), 0, false};
  close(pipe_fds[0]);
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  g_child = 0;
  for (size_t i = 0; i < std::size(kForwarded); ++i) sigaction(kForwarded[i], &saved[i], nullptr);
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  death.signal = WTERMSIG(status);
  death.interrupted = g_forwarded > 0;
  return on_death(death);
}

std::string SignalName(int signal) {
  const char* name = sigabbrev_np(signal);
  return name != nullptr ? std::string("SIG") + name : "signal " + std::to_string(signal);
}

}  // namespace rdmesh::cli
