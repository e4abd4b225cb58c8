#pragma once
// One call on a worker process, driven from the daemon: the call is sent, the worker's replies are
// relayed, and the worker's death, the client's cancellation and the deadline are watched for.
// See docs/SERVICE.md, "Crash isolation".

#include <chrono>
#include <functional>
#include <optional>
#include <string>

#include "common/log.h"
#include "rdmesh/internal/worker.pb.h"
#include "rdmesh/status.h"
#include "worker/worker_process.h"

namespace rdmesh::server {

/// What happened when a worker call ended.
struct CallEnd {
  Status status;
  /// False when the worker died or was killed: Discard it, never Release it.
  bool worker_ok = true;
  /// The worker died on its own (a crash, a limit): not a stop the daemon asked for.
  bool crashed = false;
  /// "load" or "mesh": where the call was when it ended.
  std::string phase = "load";
};

/// Runs `call` on `worker`: sends it, hands every reply but Done to `on_reply` (returning false
/// from it stops the call, e.g. when the client is gone), and returns how it ended. `cancelled`
/// is polled every 20 ms; when it turns true or the deadline passes, the worker is asked to stop
/// and, if it has not answered Done within a second, killed. A worker that dies answers the call
/// with the cause: a reader crash (`what` names the reader, e.g. "the STEP reader") is
/// kParseError, a crash while meshing kInvalidArgument, a CPU or memory limit
/// kResourceExhausted.
CallEnd CallWorker(WorkerProcess* worker, const WorkerSettings& settings,
                   const ::rdmesh::internal::ToWorker& call, const std::string& what,
                   const std::function<bool(const ::rdmesh::internal::FromWorker&)>& on_reply,
                   const std::function<bool()>& cancelled,
                   std::optional<std::chrono::steady_clock::time_point> deadline,
                   const RequestLog& log);

}  // namespace rdmesh::server
