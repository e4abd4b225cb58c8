// rdmesh: the command line's front. It loads none of the engine. `mesh` and `info` run in
// rdmesh-local, a child process beside this program, so that a crash inside OCCT on a model
// becomes an exit code and a message (isolation.h); every other command (`batch`, --help), and
// any run with RDMESH_NO_FORK=1, replaces this process with rdmesh-local, and `--remote` with
// rdmesh-remote.
//
// Why not fork the loaded program, as rdmesh-local run by hand does: the forked copy pays again,
// page by page, for every page of the parent it writes (copy on write), about 10 ms a run on a
// small model (docs/TUNING.md, "The launcher"). Plain C library calls only: each library loaded
// is start-up time on every run.

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "exit_codes.h"
#include "supervise.h"

extern char** environ;

namespace {

using rdmesh::cli::ChildDeath;

// `name` in this program's folder, in `path` (PATH_MAX bytes); false when /proc/self/exe cannot
// be read.
bool Beside(const char* name, char* path) {
  ssize_t length = readlink("/proc/self/exe", path, PATH_MAX - 1);
  if (length <= 0) return false;
  path[length] = '\0';
  char* slash = strrchr(path, '/');
  if (slash == nullptr) return false;
  return snprintf(slash + 1, PATH_MAX - (slash + 1 - path), "%s", name) <
         PATH_MAX - (slash + 1 - path);
}

// Replaces this process with `name` beside it; returns kExitUsage, with the reason on stderr,
// only when it cannot.
int ExecBeside(const char* name, char** argv, const char* why) {
  char path[PATH_MAX];
  if (!Beside(name, path)) snprintf(path, sizeof(path), "%s", name);
  execv(path, argv);
  fprintf(stderr, "rdmesh: %s needs %s (%s)\n", why, path, strerror(errno));
  return rdmesh::cli::kExitUsage;
}

bool IsRemote(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (strcmp(argv[i], "--remote") == 0 || strncmp(argv[i], "--remote=", 9) == 0) return true;
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  // mimalloc on transparent huge pages from its first segment on (engine/src/core/
  // malloc_options.cpp sets it too, but only after the libraries' static initialisers have
  // allocated the main thread's first segment); a value the caller set stays.
  setenv("MIMALLOC_LARGE_OS_PAGES", "1", 0);
  // rdmesh-remote links the gRPC client: a local run does not load it.
  if (IsRemote(argc, argv)) return ExecBeside("rdmesh-remote", argv, "--remote");
  const bool isolated = argc > 1 && !rdmesh::cli::ForkDisabled() &&
                        (strcmp(argv[1], "mesh") == 0 || strcmp(argv[1], "info") == 0);
  int pipe_fds[2];
  // Without a pipe the run goes on in this process, as RunIsolated does when it cannot fork.
  if (!isolated || pipe2(pipe_fds, O_CLOEXEC) != 0)
    return ExecBeside("rdmesh-local", argv, "a local run");

  char path[PATH_MAX];
  if (!Beside("rdmesh-local", path)) return ExecBeside("rdmesh-local", argv, "a local run");
  // The write end goes to the child (not closed on exec), which is told its number.
  fcntl(pipe_fds[1], F_SETFD, 0);
  char fd_text[16];
  snprintf(fd_text, sizeof(fd_text), "%d", pipe_fds[1]);
  setenv(rdmesh::cli::kPhaseFdVariable, fd_text, 1);
  const sigset_t saved_mask = rdmesh::cli::BlockForwardedSignals();
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setsigmask(&attributes, &saved_mask);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK);
  pid_t child = 0;
  const int error = posix_spawn(&child, path, nullptr, &attributes, argv, environ);
  posix_spawnattr_destroy(&attributes);
  close(pipe_fds[1]);
  unsetenv(rdmesh::cli::kPhaseFdVariable);
  if (error != 0) {
    sigprocmask(SIG_SETMASK, &saved_mask, nullptr);
    fprintf(stderr, "rdmesh: a local run needs %s (%s)\n", path, strerror(error));
    return rdmesh::cli::kExitUsage;
  }

  int code = 0;
  ChildDeath death;
  if (rdmesh::cli::Supervise(child, pipe_fds[0], saved_mask, &code, &death)) return code;
  // rdmesh-local words the message (it knows the flags: --json, the file, the phase's reader).
  char death_text[32];
  rdmesh::cli::FormatDeath(death, death_text, sizeof(death_text));
  setenv(rdmesh::cli::kDeathVariable, death_text, 1);
  execv(path, argv);
  fprintf(stderr, "rdmesh: error: the run ended by signal %d (and %s cannot be run: %s)\n",
          death.signal, path, strerror(errno));
  return rdmesh::cli::kExitMeshFailed;
}
