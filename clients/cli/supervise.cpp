#include "supervise.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

namespace rdmesh::cli {

namespace {

// The child's pid while it runs, and how many signals were passed on to it.
volatile sig_atomic_t g_child = 0;
volatile sig_atomic_t g_forwarded = 0;

constexpr int kForwarded[] = {SIGINT, SIGTERM, SIGHUP};
constexpr int kForwardedCount = sizeof(kForwarded) / sizeof(kForwarded[0]);

void Forward(int signal) {
  pid_t child = g_child;
  if (child <= 0) return;
  kill(child, g_forwarded == 0 ? signal : SIGKILL);
  g_forwarded = g_forwarded + 1;
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

bool ForkDisabled() {
  const char* value = getenv("RDMESH_NO_FORK");
  return value != nullptr && value[0] != '\0' && strcmp(value, "0") != 0;
}

sigset_t BlockForwardedSignals() {
  sigset_t forwarded, saved;
  sigemptyset(&forwarded);
  for (int signal : kForwarded) sigaddset(&forwarded, signal);
  sigprocmask(SIG_BLOCK, &forwarded, &saved);
  return saved;
}

bool Supervise(pid_t child, int phase_fd, const sigset_t& saved_mask, int* exit_code,
               ChildDeath* death) {
  g_child = child;
  g_forwarded = 0;
  struct sigaction forward = {}, saved[kForwardedCount];
  forward.sa_handler = Forward;
  sigemptyset(&forward.sa_mask);
  for (int i = 0; i < kForwardedCount; ++i) sigaction(kForwarded[i], &forward, &saved[i]);
  sigprocmask(SIG_SETMASK, &saved_mask, nullptr);

  const Phase phase = FollowPhases(phase_fd);
  close(phase_fd);
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  g_child = 0;
  for (int i = 0; i < kForwardedCount; ++i) sigaction(kForwarded[i], &saved[i], nullptr);
  if (WIFEXITED(status)) {
    *exit_code = WEXITSTATUS(status);
    return true;
  }
  *death = ChildDeath{phase, WTERMSIG(status), g_forwarded > 0};
  return false;
}

void FormatDeath(const ChildDeath& death, char* out, int size) {
  snprintf(out, size, "%c:%d:%d", static_cast<char>(death.phase), death.signal,
           death.interrupted ? 1 : 0);
}

bool ParseDeath(const char* text, ChildDeath* death) {
  char phase = 0;
  int signal = 0, interrupted = 0;
  if (sscanf(text, "%c:%d:%d", &phase, &signal, &interrupted) != 3) return false;
  if (phase != 'L' && phase != 'M' && phase != 'W') return false;
  *death = ChildDeath{static_cast<Phase>(phase), signal, interrupted != 0};
  return true;
}

}  // namespace rdmesh::cli
