#include "worker_pool.h"

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
#include <utility>

#include "frame.h"

extern char** environ;

namespace rdmesh::server {
namespace {

namespace wire = ::rdmesh::internal;
using Clock = std::chrono::steady_clock;

constexpr std::size_t kRememberedModels = 64;
constexpr int kPollMs = 20;
/// How long a worker asked to stop may take before it is killed.
constexpr std::chrono::milliseconds kStopGrace(1000);
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

// --- WorkerProcess ----------------------------------------------------------------------------

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

// --- WorkerPool -------------------------------------------------------------------------------

WorkerPool::WorkerPool(WorkerSettings settings, int max_workers)
    : settings_(std::move(settings)), max_workers_(std::max(1, max_workers)) {}

WorkerPool::~WorkerPool() { Close(); }

Status WorkerPool::Prestart(int count) {
  std::lock_guard<std::mutex> lock(mutex_);
  keep_ = std::min(count, max_workers_);
  while (live_ < keep_) {
    Result<std::unique_ptr<WorkerProcess>> worker = WorkerProcess::Start(settings_);
    if (!worker.ok()) return worker.status();
    pids_.push_back((*worker)->pid());
    idle_.push_back(std::move(*worker));
    ++live_;
  }
  return Status::Ok();
}

std::unique_ptr<WorkerProcess> WorkerPool::Acquire(const std::string& model_id,
                                                   const std::function<bool()>& stop,
                                                   Status* error) {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    if (closed_) {
      *error = Status(StatusCode::kCancelled, "the server is shutting down");
      return nullptr;
    }
    // Idle workers that died while idle (killed from outside) are dropped.
    for (std::size_t i = 0; i < idle_.size();) {
      if (idle_[i]->Exited()) {
        pids_.erase(std::remove(pids_.begin(), pids_.end(), idle_[i]->pid()), pids_.end());
        idle_.erase(idle_.begin() + static_cast<std::ptrdiff_t>(i));
        --live_;
        ++lost_;
      } else {
        ++i;
      }
    }
    if (!idle_.empty()) {
      std::size_t pick = idle_.size() - 1;  // the most recently returned
      for (std::size_t i = 0; i < idle_.size(); ++i) {
        if (idle_[i]->Holds(model_id)) pick = i;
      }
      std::unique_ptr<WorkerProcess> worker = std::move(idle_[pick]);
      idle_.erase(idle_.begin() + static_cast<std::ptrdiff_t>(pick));
      return worker;
    }
    if (live_ < max_workers_) {
      Result<std::unique_ptr<WorkerProcess>> worker = WorkerProcess::Start(settings_);
      if (!worker.ok()) {
        *error = worker.status();
        return nullptr;
      }
      pids_.push_back((*worker)->pid());
      ++live_;
      return std::move(*worker);
    }
    returned_.wait_for(lock, std::chrono::milliseconds(kPollMs));
    if (stop()) {
      *error = Status(StatusCode::kCancelled, "cancelled while waiting for a worker");
      return nullptr;
    }
  }
}

void WorkerPool::Release(std::unique_ptr<WorkerProcess> worker) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (closed_) {
    pids_.erase(std::remove(pids_.begin(), pids_.end(), worker->pid()), pids_.end());
    --live_;
    worker.reset();  // kills it
    return;
  }
  idle_.push_back(std::move(worker));
  returned_.notify_one();
}

void WorkerPool::Discard(std::unique_ptr<WorkerProcess> worker) {
  worker->Reap(std::chrono::milliseconds(0));
  std::lock_guard<std::mutex> lock(mutex_);
  pids_.erase(std::remove(pids_.begin(), pids_.end(), worker->pid()), pids_.end());
  worker.reset();
  --live_;
  ++lost_;
  if (!closed_ && live_ < keep_) {
    Result<std::unique_ptr<WorkerProcess>> replacement = WorkerProcess::Start(settings_);
    if (replacement.ok()) {
      pids_.push_back((*replacement)->pid());
      idle_.push_back(std::move(*replacement));
      ++live_;
    }
  }
  returned_.notify_one();
}

void WorkerPool::Close() {
  std::vector<std::unique_ptr<WorkerProcess>> idle;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    idle.swap(idle_);
    for (const auto& worker : idle) {
      pids_.erase(std::remove(pids_.begin(), pids_.end(), worker->pid()), pids_.end());
    }
    live_ -= static_cast<int>(idle.size());
  }
  idle.clear();  // kills and reaps them
}

int WorkerPool::live() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return live_;
}

int WorkerPool::idle() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(idle_.size());
}

int64_t WorkerPool::lost() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return lost_;
}

std::vector<pid_t> WorkerPool::pids() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pids_;
}

// --- CallWorker -------------------------------------------------------------------------------

namespace {

/// The status of a call whose worker died on its own.
Status DeathStatus(int wait_status, const std::string& phase, const std::string& what,
                   const WorkerSettings& settings) {
  const std::string cause = DescribeExit(wait_status);
  const std::string doing = phase == "load" ? "reading the model" : "meshing the model";
  if (WIFSIGNALED(wait_status) && WTERMSIG(wait_status) == SIGXCPU) {
    char limit[32];
    std::snprintf(limit, sizeof(limit), "%g", settings.cpu_seconds);
    return Status(StatusCode::kResourceExhausted,
                  std::string("the worker passed its CPU time limit of ") + limit +
                      " s (--worker-cpu-seconds) while " + doing);
  }
  if (WIFSIGNALED(wait_status) && WTERMSIG(wait_status) == SIGKILL) {
    return Status(StatusCode::kResourceExhausted,
                  "the worker was killed (SIGKILL, most likely out of memory) while " + doing);
  }
  if (WIFSIGNALED(wait_status)) {
    if (phase == "load") {
      return Status(StatusCode::kParseError, what + " crashed (" + cause + ") on this model");
    }
    return Status(StatusCode::kInvalidArgument, "the mesher crashed (" + cause + ") on this model");
  }
  return Status(StatusCode::kInternal, "the worker ended (" + cause + ") while " + doing);
}

}  // namespace

CallEnd CallWorker(WorkerProcess* worker, const WorkerSettings& settings,
                   const wire::ToWorker& call, const std::string& what,
                   const std::function<bool(const wire::FromWorker&)>& on_reply,
                   const std::function<bool()>& cancelled,
                   std::optional<Clock::time_point> deadline, const RequestLog& log) {
  CallEnd end;
  if (!worker->LimitCpu(settings.cpu_seconds)) {
    log.Warn("cannot set the CPU time limit of worker {}", worker->pid());
  }
  if (!WriteFrame(worker->fd(), call)) {
    const int status = worker->Reap(std::chrono::milliseconds(200));
    end.worker_ok = false;
    end.crashed = true;
    end.status = DeathStatus(status, end.phase, what, settings);
    return end;
  }
  std::optional<Status> stop;  // why the daemon asked the worker to stop
  Clock::time_point stop_sent;
  const auto request_stop = [&](Status why) {
    if (stop) return;
    stop = std::move(why);
    stop_sent = Clock::now();
    wire::ToWorker cancel;
    cancel.set_request_id(call.request_id());
    cancel.mutable_cancel();
    WriteFrame(worker->fd(), cancel);
  };
  wire::FromWorker reply;
  while (true) {
    const FrameRead read = worker->reader().Read(&reply, kPollMs);
    if (read == FrameRead::kMessage) {
      if (reply.has_done()) {
        end.phase = reply.done().phase();
        end.status = Status(static_cast<StatusCode>(reply.done().code()), reply.done().message());
        if (stop && !end.status.ok() && end.status.code() != StatusCode::kDeadlineExceeded) {
          end.status = *stop;
        }
        return end;
      }
      if (reply.has_ready()) end.phase = call.has_mesh() ? "mesh" : "load";
      if (!stop && !on_reply(reply)) {
        request_stop(Status(StatusCode::kCancelled, "client went away"));
      }
    } else if (read != FrameRead::kTimeout) {  // the worker is gone, or spoke garbage
      const int status = worker->Reap(std::chrono::milliseconds(500));
      end.worker_ok = false;
      if (stop) {
        end.status = *stop;
      } else {
        end.crashed = true;
        end.status = DeathStatus(status, end.phase, what, settings);
        log.Warn("worker {} ended ({}) while {}", worker->pid(), DescribeExit(status),
                 end.phase == "load" ? "reading the model" : "meshing");
      }
      return end;
    }
    if (!stop && deadline && Clock::now() >= *deadline) {
      request_stop(Status(StatusCode::kDeadlineExceeded, "the deadline passed"));
    }
    if (!stop && cancelled()) {
      // gRPC cancels a call whose deadline passed: say so rather than "cancelled".
      const bool late = deadline && Clock::now() >= *deadline - std::chrono::milliseconds(200);
      request_stop(late ? Status(StatusCode::kDeadlineExceeded, "the deadline passed")
                        : Status(StatusCode::kCancelled, "cancelled"));
    }
    if (stop && Clock::now() - stop_sent >= kStopGrace) {
      worker->Reap(std::chrono::milliseconds(0));
      log.Warn("worker {} did not stop within {} ms of being asked; killed and replaced",
               worker->pid(), kStopGrace.count());
      end.worker_ok = false;
      end.status = *stop;
      return end;
    }
  }
}

}  // namespace rdmesh::server
