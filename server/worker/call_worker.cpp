#include "worker/call_worker.h"

#include <signal.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>
#include <utility>

#include "wire/frame.h"
#include "worker/worker.h"

namespace rdmesh::server {
namespace {

namespace wire = ::rdmesh::internal;
using Clock = std::chrono::steady_clock;

/// How often the call looks at its worker's socket, the cancellation and the deadline.
constexpr int kPollMs = 20;
/// How long a worker asked to stop may take before it is killed.
constexpr std::chrono::milliseconds kStopGrace(1000);

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
  if (WIFEXITED(wait_status) && WEXITSTATUS(wait_status) == kWorkerOutOfMemoryExit) {
    return Status(StatusCode::kResourceExhausted, "the worker reached its memory limit of " +
                                                      std::to_string(settings.memory_bytes >> 20) +
                                                      " MiB (--worker-memory) while " + doing);
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
