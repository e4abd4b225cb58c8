#include "worker/worker.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <exception>
#include <mutex>
#include <new>
#include <string>
#include <thread>
#include <utility>

#include "common/log.h"
#include "common/read_file.h"
#include "rdmesh/internal/worker.pb.h"
#include "wire/convert.h"
#include "wire/frame.h"
#include "worker/mesh_job.h"
#include "worker/model_cache.h"

namespace rdmesh::server {
namespace {

namespace pb = ::rdmesh::v1;
namespace wire = ::rdmesh::internal;

/// Calls from the daemon, read by a thread of their own so that Cancel reaches a running call.
class Inbox {
 public:
  explicit Inbox(int fd) : fd_(fd), reader_([this] { Read(); }) {}
  ~Inbox() { reader_.detach(); }

  /// The next call; false once the daemon has gone.
  bool Next(wire::ToWorker* call) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [&] { return !calls_.empty() || closed_; });
    if (calls_.empty()) return false;
    *call = std::move(calls_.front());
    calls_.pop_front();
    cancelled_ = false;
    return true;
  }

  /// True once the daemon asked to stop the current call (or went away).
  bool cancelled() const { return cancelled_.load(); }

 private:
  void Read() {
    wire::ToWorker call;
    while (ReadFrame(fd_, &call, -1) == FrameRead::kMessage) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (call.has_cancel()) {
        cancelled_ = true;
      } else {
        calls_.push_back(std::move(call));
        ready_.notify_one();
      }
    }
    // The daemon is gone (or spoke garbage): nobody waits for this process any more.
    std::_Exit(0);
  }

  const int fd_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<wire::ToWorker> calls_;
  bool closed_ = false;
  std::atomic<bool> cancelled_{false};
  std::thread reader_;
};

pb::ModelInfo Describe(const CachedModel& entry, bool cached) {
  pb::ModelInfo info = ToProto(entry.info);
  info.set_model_id(entry.id);
  info.set_file_bytes(entry.file_bytes);
  info.set_cached(cached);
  info.set_load_seconds(cached ? 0.0 : entry.load_seconds);
  info.set_from_store(!cached && entry.from_store);
  return info;
}

/// The process's peak address-space size (VmPeak), bytes; 0 when unknown. Read into a stack
/// buffer: it is asked right after an allocation failed, when the heap may have nothing left
/// (an ifstream's buffer then throws std::bad_alloc outside any handler, and the worker aborts).
uint64_t PeakAddressSpace() {
  const int fd = open("/proc/self/status", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  char text[8192];  // the whole file: about 1.5 KiB
  const ssize_t size = read(fd, text, sizeof(text) - 1);
  close(fd);
  if (size <= 0) return 0;
  text[size] = '\0';
  const char* peak = std::strstr(text, "\nVmPeak:");
  return peak != nullptr ? std::strtoull(peak + 8, nullptr, 10) << 10 : 0;
}

Status OutOfMemory(uint64_t limit, const std::string& phase) {
  return Status(StatusCode::kResourceExhausted,
                "the worker reached its memory limit of " + std::to_string(limit >> 20) +
                    " MiB (--worker-memory) while " +
                    (phase == "load" ? "reading the model" : "meshing the model"));
}

class Worker {
 public:
  explicit Worker(const WorkerConfig& config)
      : config_(config),
        cache_(config.cache_bytes,
               config.store_dir.empty()
                   ? nullptr
                   : std::make_shared<const ModelStore>(config.store_dir, config.store_bytes)),
        inbox_(config.fd) {}

  int Run() {
    wire::ToWorker call;
    while (inbox_.Next(&call)) {
      const RequestLog log(call.request_id().empty() ? "-" : call.request_id());
      std::string phase = "load";
      Status status = Status::Ok();
      try {
        status = Serve(call, log, &phase);
      } catch (const std::bad_alloc&) {
        status = OutOfMemory(config_.memory_bytes, phase);
      } catch (const std::exception& e) {
        status = Status(StatusCode::kInternal, std::string("exception: ") + e.what());
      } catch (...) {
        status = Status(StatusCode::kInternal, "unknown exception");
      }
      // An allocation or a thread that failed under the address-space limit surfaces as some
      // engine error; when the process came near its limit, that is what it was. Such a worker
      // ends after answering (its state may be damaged); the daemon starts another.
      const bool out_of_memory = !status.ok() && config_.memory_bytes > 0 &&
                                 PeakAddressSpace() >= config_.memory_bytes / 10 * 9;
      if (out_of_memory) status = OutOfMemory(config_.memory_bytes, phase);
      wire::FromWorker reply;
      wire::Done* done = reply.mutable_done();
      done->set_code(static_cast<int>(status.code()));
      done->set_message(status.message());
      done->set_phase(phase);
      if (!WriteFrame(config_.fd, reply) || out_of_memory) return 0;
    }
    return 0;
  }

 private:
  Result<std::shared_ptr<const CachedModel>> Load(const wire::ModelFile& file, bool* cached) {
    *cached = false;
    if (std::shared_ptr<const CachedModel> held = cache_.Find(file.model_id())) {
      *cached = true;
      return held;
    }
    Result<std::string> bytes = ReadFileLimited(file.path(), config_.max_model_bytes);
    if (!bytes.ok()) {
      return Status(StatusCode::kNotFound,
                    "the model's bytes are gone from the server's spool (evicted): upload it "
                    "again");
    }
    Result<std::shared_ptr<const CachedModel>> entry =
        cache_.GetOrLoad(*bytes, file.name(), FromProto(file.format()), cached);
    if (entry.ok() && (*entry)->id != file.model_id()) {
      return Status(StatusCode::kInternal,
                    "the spooled bytes of model " + file.model_id() + " do not match their id");
    }
    return entry;
  }

  Status Ready(const CachedModel& entry, bool cached) {
    wire::FromWorker reply;
    *reply.mutable_ready()->mutable_model() = Describe(entry, cached);
    if (!WriteFrame(config_.fd, reply)) return Status(StatusCode::kCancelled, "daemon gone");
    return Status::Ok();
  }

  Status Serve(const wire::ToWorker& call, const RequestLog& log, std::string* phase) {
    const wire::ModelFile& file = call.has_load() ? call.load().model() : call.mesh().model();
    bool cached = false;
    Result<std::shared_ptr<const CachedModel>> entry = Load(file, &cached);
    if (!entry.ok()) return entry.status();
    if (!cached) {
      if (!(*entry)->store_problem.empty())
        log.Warn("worker {}: {}", getpid(), (*entry)->store_problem);
      log.Info("worker {}: model {} '{}' {} in {:.3f} s", getpid(), (*entry)->id.substr(0, 12),
               file.name(), (*entry)->from_store ? "read from the store" : "parsed",
               (*entry)->load_seconds);
    }
    if (Status ready = Ready(**entry, cached); !ready.ok()) return ready;
    if (call.has_load()) return Status::Ok();

    *phase = "mesh";
    const wire::MeshCall& mesh = call.mesh();
    MeshJob::Params params;
    params.model = *entry;
    params.options = FromProto(mesh.options());
    params.with_uv = mesh.return_fields().uv();
    params.with_normals = mesh.return_fields().normals();
    params.with_topology = mesh.return_fields().node_topology();
    params.with_edges = mesh.return_fields().edges();
    params.with_deviation = mesh.return_fields().triangle_deviation();
    params.max_triangles = mesh.max_triangles();
    params.levels.assign(mesh.lod_deviation_rel().begin(), mesh.lod_deviation_rel().end());
    if (mesh.deadline_unix_ms() > 0) {
      params.deadline =
          std::chrono::system_clock::time_point(std::chrono::milliseconds(mesh.deadline_unix_ms()));
    }
    params.start = std::chrono::steady_clock::now() -
                   std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                       std::chrono::duration<double>(mesh.elapsed_seconds()));
    std::atomic<int> active{0};
    MeshJob job(std::move(params), &log, &active);
    const int fd = config_.fd;
    return job.Run(
        [fd](const pb::MeshEvent& event) {
          wire::FromWorker reply;
          *reply.mutable_event() = event;
          return WriteFrame(fd, reply);
        },
        [this] { return inbox_.cancelled(); });
  }

  const WorkerConfig config_;
  ModelCache cache_;
  Inbox inbox_;
};

}  // namespace

namespace {

uint64_t g_memory_bytes = 0;  // the worker's RLIMIT_AS, for OnTerminate

// std::terminate near the address-space limit is an allocation or a thread that failed where no
// handler could see it (a library's own thread): that is the memory limit, so say so to the
// daemon by the exit code; any other terminate stays an abort (a crash).
[[noreturn]] void OnTerminate() {
  if (g_memory_bytes > 0 && PeakAddressSpace() >= g_memory_bytes / 10 * 9)
    _exit(kWorkerOutOfMemoryExit);
  std::abort();
}

}  // namespace

int RunWorker(const WorkerConfig& config) {
  // No PR_SET_PDEATHSIG: it fires when the daemon *thread* that started this process ends
  // (gRPC's handler threads come and go). The inbox's reader ends the process instead, as soon
  // as the daemon's end of the socket closes, whatever the main thread is doing.
  if (config.memory_bytes > 0) {
    rlimit limit{config.memory_bytes, config.memory_bytes};
    setrlimit(RLIMIT_AS, &limit);
    g_memory_bytes = config.memory_bytes;
    std::set_terminate(OnTerminate);
  }
  Worker worker(config);
  return worker.Run();
}

}  // namespace rdmesh::server
