#include "worker/worker_process.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

extern char** environ;

namespace rdmesh::server {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kRememberedModels = 64;
/// The fd number of the daemon's socket in a worker.
constexpr int kWorkerFd = 3;

std::string SignalName(int signal) {
  switch (signal) {
    case SIGSEGV:
      return "SIGSEGV";
    case SIGBUS:
      return "SIGBUS";
    case SIGABRT:
      return "SIGABRT";
    case SIGFPE:
      return "SIGFPE";
    case SIGILL:
      return "SIGILL";
    case SIGKILL:
      return "SIGKILL";
    case SIGXCPU:
      return "SIGXCPU";
    case SIGTERM:
      return "SIGTERM";
    case SIGTRAP:
      return "SIGTRAP";
    default:
      return "signal " + std::to_string(signal);
  }
}

/// Fields 14 and 15 (utime, stime) of /proc/PID/stat, in seconds; -1 when unreadable.
double ProcCpuSeconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t paren = text.rfind(')');  // the command name may hold spaces
  if (paren == std::string::npos) return -1.0;
  std::istringstream fields(text.substr(paren + 2));
  std::string field;
  double ticks = 0.0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i == 14 || i == 15) ticks += std::strtod(field.c_str(), nullptr);
  }
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

}  // namespace

std::string DescribeExit(int wait_status) {
  if (WIFSIGNALED(wait_status)) return SignalName(WTERMSIG(wait_status));
  if (WIFEXITED(wait_status)) return "exit code " + std::to_string(WEXITSTATUS(wait_status));
  return "wait status " + std::to_string(wait_status);
}

Result<std::unique_ptr<WorkerProcess>> WorkerProcess::Start(const WorkerSettings& settings) {
  int sockets[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sockets) != 0) {
    return Status(StatusCode::kInternal,
                  std::string("cannot create a worker socket: ") + std::strerror(errno));
  }
  int child_end = sockets[1];
  if (child_end == kWorkerFd) {  // dup2 onto itself would keep close-on-exec
    child_end = fcntl(sockets[1], F_DUPFD_CLOEXEC, kWorkerFd + 1);
    close(sockets[1]);
  }
  std::vector<std::string> args = {settings.executable,
                                   "--worker-fd",
                                   std::to_string(kWorkerFd),
                                   "--worker-memory",
                                   std::to_string(settings.memory_bytes),
                                   "--cache-bytes",
                                   std::to_string(settings.cache_bytes),
                                   "--max-model-bytes",
                                   std::to_string(settings.max_model_bytes),
                                   "--log-format",
                                   settings.log_format,
                                   "--log-level",
                                   settings.log_level};
  if (!settings.store_dir.empty()) {
    args.insert(args.end(), {"--cache-dir", settings.store_dir, "--cache-dir-bytes",
                             std::to_string(settings.store_bytes)});
  }
  std::vector<char*> argv;
  for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, child_end, kWorkerFd);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attributes, &none);  // the daemon blocks SIGTERM/SIGINT
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGTERM);
  sigaddset(&defaults, SIGINT);
  sigaddset(&defaults, SIGPIPE);
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  posix_spawnattr_setpgroup(&attributes, 0);
  posix_spawnattr_setflags(&attributes,
                           POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETPGROUP);
  pid_t pid = 0;
  const int error =
      posix_spawn(&pid, settings.executable.c_str(), &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  close(child_end);
  if (error != 0) {
    close(sockets[0]);
    return Status(StatusCode::kInternal, "cannot start a worker process (" + settings.executable +
                                             "): " + std::strerror(error));
  }
  return std::unique_ptr<WorkerProcess>(new WorkerProcess(pid, sockets[0]));
}

WorkerProcess::~WorkerProcess() {
  if (!reaped_) Reap(std::chrono::milliseconds(0));
  close(fd_);
}

bool WorkerProcess::Holds(const std::string& model_id) const {
  return std::find(models_.begin(), models_.end(), model_id) != models_.end();
}

void WorkerProcess::Remember(const std::string& model_id) {
  auto it = std::find(models_.begin(), models_.end(), model_id);
  if (it != models_.end()) models_.erase(it);
  models_.push_back(model_id);
  if (models_.size() > kRememberedModels) models_.pop_front();
}

bool WorkerProcess::LimitCpu(double seconds) {
  if (seconds <= 0) return true;
  const double used = CpuSeconds();
  if (used < 0) return false;
  rlimit limit{};
  if (prlimit(pid_, RLIMIT_CPU, nullptr, &limit) != 0) return false;
  limit.rlim_cur = static_cast<rlim_t>(std::ceil(used + seconds));
  if (limit.rlim_max != RLIM_INFINITY && limit.rlim_cur > limit.rlim_max) {
    limit.rlim_cur = limit.rlim_max;
  }
  return prlimit(pid_, RLIMIT_CPU, &limit, nullptr) == 0;
}

double WorkerProcess::CpuSeconds() const { return ProcCpuSeconds(pid_); }

uint64_t WorkerProcess::RssBytes() const {
  std::ifstream in("/proc/" + std::to_string(pid_) + "/statm");
  uint64_t size = 0;
  uint64_t resident = 0;
  if (!(in >> size >> resident)) return 0;
  return resident * static_cast<uint64_t>(sysconf(_SC_PAGESIZE));
}

bool WorkerProcess::Exited() {
  if (reaped_) return true;
  int status = 0;
  if (waitpid(pid_, &status, WNOHANG) == pid_) {
    reaped_ = true;
    wait_status_ = status;
  }
  return reaped_;
}

int WorkerProcess::Reap(std::chrono::milliseconds grace) {
  if (reaped_) return wait_status_;
  const Clock::time_point give_up = Clock::now() + grace;
  while (!Exited() && Clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (!reaped_) {
    kill(pid_, SIGKILL);
    killed_ = true;
    int status = 0;
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    reaped_ = true;
    wait_status_ = status;
  }
  return wait_status_;
}

}  // namespace rdmesh::server
