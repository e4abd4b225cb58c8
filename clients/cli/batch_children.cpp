#include "batch_children.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/signalfd.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>

namespace rdmesh::cli {

namespace {

constexpr int kWatched[] = {SIGCHLD, SIGINT, SIGTERM, SIGHUP};
// Kept of a child's stderr: the end, where the reason of a death is.
constexpr size_t kErrKeep = 16 << 10;
// A child that floods its stdout is cut off there (a report is well below).
constexpr size_t kOutKeep = size_t{256} << 20;

sigset_t WatchedSet() {
  sigset_t set;
  sigemptyset(&set);
  for (int signal : kWatched) sigaddset(&set, signal);
  return set;
}

double Seconds(std::chrono::steady_clock::duration duration) {
  return std::chrono::duration<double>(duration).count();
}

// Only async-signal-safe calls between fork and exec: the parent may hold locks. Without exec
// (`entry`), the child goes on as a copy of this single-threaded process: no lock is held.
[[noreturn]] void RunChild(pid_t parent, char** argv, char** envp, int out_fd, int err_fd,
                           uint64_t memory_limit, const sigset_t& mask, ChildPool::Entry entry) {
  setpgid(0, 0);
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) _exit(127);  // the batch died before prctl
  if (memory_limit > 0) {
    rlimit limit{memory_limit, memory_limit};
    setrlimit(RLIMIT_AS, &limit);
  }
  for (int signal : {SIGPIPE, SIGINT, SIGTERM, SIGHUP, SIGCHLD}) ::signal(signal, SIG_DFL);
  sigprocmask(SIG_SETMASK, &mask, nullptr);
  int null_fd = open("/dev/null", O_RDONLY);
  if (null_fd >= 0) dup2(null_fd, 0);
  dup2(out_fd, 1);
  dup2(err_fd, 2);
  if (entry != nullptr) {
    // Nothing of the batch's open files (other children's pipes, the manifest, its lock) stays
    // open in the child.
    close_range(3, ~0U, 0);
    environ = envp;
    int argc = 0;
    while (argv[argc] != nullptr) ++argc;
    const int code = entry(argc, argv);
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
    _exit(code);
  }
  execve(argv[0], argv, envp);
  const char* reason = strerror(errno);
  const char* parts[] = {"cannot run ", argv[0], ": ", reason, "\n"};
  for (const char* part : parts) {
    ssize_t written = write(2, part, strlen(part));
    (void)written;
  }
  _exit(127);
}

}  // namespace

ChildPool::ChildPool() {
  sigset_t watched = WatchedSet();
  sigprocmask(SIG_BLOCK, &watched, &saved_mask_);
  signal_fd_ = signalfd(-1, &watched, SFD_NONBLOCK | SFD_CLOEXEC);
}

ChildPool::~ChildPool() {
  KillAll();
  if (signal_fd_ >= 0) close(signal_fd_);
  sigprocmask(SIG_SETMASK, &saved_mask_, nullptr);
}

Status ChildPool::Start(int id, const std::vector<std::string>& argv,
                        const std::vector<std::string>& env, double timeout_seconds,
                        uint64_t memory_limit, Entry entry) {
  std::vector<char*> args, envp;
  for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  for (const std::string& var : env) envp.push_back(const_cast<char*>(var.c_str()));
  envp.push_back(nullptr);
  int out[2], err[2];
  if (pipe2(out, O_CLOEXEC) != 0) return Status(StatusCode::kInternal, strerror(errno));
  if (pipe2(err, O_CLOEXEC) != 0) {
    close(out[0]);
    close(out[1]);
    return Status(StatusCode::kInternal, strerror(errno));
  }
  const pid_t parent = getpid();
  Child child;
  child.start = std::chrono::steady_clock::now();
  // What this process has buffered must not be written a second time by the child.
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid == 0)
    RunChild(parent, args.data(), envp.data(), out[1], err[1], memory_limit, saved_mask_, entry);
  close(out[1]);
  close(err[1]);
  if (pid < 0) {
    const int error = errno;
    close(out[0]);
    close(err[0]);
    return Status(StatusCode::kInternal, std::string("cannot fork: ") + strerror(error));
  }
  setpgid(pid, pid);  // also here, so that a kill right away reaches the group
  fcntl(out[0], F_SETFL, O_NONBLOCK);
  fcntl(err[0], F_SETFL, O_NONBLOCK);
  child.result.id = id;
  child.pid = pid;
  child.out_fd = out[0];
  child.err_fd = err[0];
  if (timeout_seconds > 0) {
    child.has_deadline = true;
    child.deadline = child.start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                       std::chrono::duration<double>(timeout_seconds));
  }
  children_.push_back(std::move(child));
  return Status::Ok();
}

void ChildPool::Drain(Child* child) {
  char buffer[65536];
  for (int* fd : {&child->out_fd, &child->err_fd}) {
    std::string& text = fd == &child->out_fd ? child->result.out : child->result.err;
    while (*fd >= 0) {
      ssize_t count = read(*fd, buffer, sizeof(buffer));
      if (count < 0 && errno == EINTR) continue;
      if (count < 0) break;  // EAGAIN: nothing more for now
      if (count == 0) {
        close(*fd);
        *fd = -1;
        break;
      }
      if (fd == &child->out_fd) {
        if (text.size() < kOutKeep) text.append(buffer, static_cast<size_t>(count));
      } else {
        text.append(buffer, static_cast<size_t>(count));
        if (text.size() > 2 * kErrKeep) text.erase(0, text.size() - kErrKeep);
      }
    }
  }
}

ChildResult ChildPool::Reap(Child* child) {
  // The leader is a zombie until waitpid, so its group id cannot have been reused.
  kill(-child->pid, SIGKILL);
  int status = 0;
  while (waitpid(child->pid, &status, 0) < 0 && errno == EINTR) {
  }
  Drain(child);
  for (int fd : {child->out_fd, child->err_fd})
    if (fd >= 0) close(fd);
  child->out_fd = child->err_fd = -1;
  ChildResult result = std::move(child->result);
  result.seconds = Seconds(std::chrono::steady_clock::now() - child->start);
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  return result;
}

std::vector<ChildResult> ChildPool::Wait(double max_seconds, int* signal) {
  *signal = 0;
  auto now = std::chrono::steady_clock::now();
  double wait = std::max(0.0, max_seconds);
  for (const Child& child : children_)
    if (child.has_deadline && !child.result.timed_out)
      wait = std::min(wait, std::max(0.0, Seconds(child.deadline - now)));
  std::vector<pollfd> fds;
  if (signal_fd_ >= 0) fds.push_back({signal_fd_, POLLIN, 0});
  for (const Child& child : children_)
    for (int fd : {child.out_fd, child.err_fd})
      if (fd >= 0) fds.push_back({fd, POLLIN, 0});
  // Round up: a deadline a few microseconds away must not spin.
  poll(fds.data(), fds.size(), static_cast<int>(wait * 1000.0) + 1);

  signalfd_siginfo info;
  while (signal_fd_ >= 0 && read(signal_fd_, &info, sizeof(info)) == sizeof(info))
    if (info.ssi_signo != SIGCHLD) *signal = static_cast<int>(info.ssi_signo);

  std::vector<ChildResult> ended;
  now = std::chrono::steady_clock::now();
  for (size_t i = 0; i < children_.size();) {
    Child& child = children_[i];
    Drain(&child);
    if (child.has_deadline && !child.result.timed_out && now >= child.deadline) {
      kill(-child.pid, SIGKILL);
      child.result.timed_out = true;
    }
    siginfo_t state{};
    if (waitid(P_PID, child.pid, &state, WEXITED | WNOHANG | WNOWAIT) == 0 &&
        state.si_pid == child.pid) {
      ended.push_back(Reap(&child));
      children_.erase(children_.begin() + static_cast<std::ptrdiff_t>(i));
    } else {
      ++i;
    }
  }
  return ended;
}

std::vector<ChildResult> ChildPool::KillAll() {
  std::vector<ChildResult> ended;
  for (Child& child : children_) {
    child.result.stopped = true;
    ended.push_back(Reap(&child));
  }
  children_.clear();
  return ended;
}

}  // namespace rdmesh::cli
