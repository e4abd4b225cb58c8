#include "daemon/rdmesh_service.h"

#include <algorithm>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "common/read_file.h"
#include "daemon/access.h"
#include "rdmesh/sha256.h"
#include "wire/convert.h"
#include "wire/status_map.h"

namespace rdmesh::server {
namespace {

namespace pb = ::rdmesh::v1;
namespace wire = ::rdmesh::internal;
using Clock = std::chrono::steady_clock;

/// Whether the client set a deadline (gRPC reports "none" as a time in the far future).
bool HasDeadline(const grpc::ServerContext& context) {
  return context.deadline() <
         std::chrono::system_clock::time_point::max() - std::chrono::hours(24 * 365);
}

/// The call's deadline on the steady clock; none when the client set none.
std::optional<Clock::time_point> DeadlineOf(const grpc::ServerContext& context) {
  if (!HasDeadline(context)) return std::nullopt;
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(
                            context.deadline() - std::chrono::system_clock::now());
}

/// A Mesh call's deadline: the client's, or `timeout_seconds` after `start` when that is earlier.
std::optional<Clock::time_point> MeshDeadline(const grpc::ServerContext& context,
                                              Clock::time_point start, double timeout_seconds) {
  std::optional<Clock::time_point> deadline = DeadlineOf(context);
  if (timeout_seconds > 0) {
    const Clock::time_point timeout = start + std::chrono::duration_cast<Clock::duration>(
                                                  std::chrono::duration<double>(timeout_seconds));
    if (!deadline || timeout < *deadline) deadline = timeout;
  }
  return deadline;
}

void FillModelFile(const StoredModel& model, wire::ModelFile* out) {
  out->set_model_id(model.id);
  out->set_path(model.path);
  out->set_name(model.name);
  out->set_format(ToProto(model.format));
}

/// The model's description for a reply: `cached` = not parsed by this call.
pb::ModelInfo Describe(const StoredModel& model, bool cached) {
  pb::ModelInfo info = model.info;
  info.set_model_id(model.id);
  info.set_file_bytes(model.file_bytes);
  info.set_cached(cached);
  info.set_load_seconds(cached ? 0.0 : model.load_seconds);
  if (cached) info.set_from_store(false);
  return info;
}

std::string Metadata(const grpc::ServerContext& context, const std::string& key) {
  const auto& metadata = context.client_metadata();
  auto it = metadata.find(key);
  if (it == metadata.end()) return "";
  return std::string(it->second.data(), it->second.size());
}

/// Logs the outcome of a call and returns its status.
grpc::Status Finish(const RequestLog& log, const grpc::Status& status, Clock::time_point start) {
  if (status.ok()) {
    log.Info("ok in {:.3f} s", SecondsSince(start));
  } else {
    log.Info("failed in {:.3f} s: code {} {}", SecondsSince(start),
             static_cast<int>(status.error_code()), status.error_message());
  }
  return status;
}

/// Counts a Mesh call as completed when it leaves scope, however it ends after admission.
class CountOnExit {
 public:
  explicit CountOnExit(std::atomic<int64_t>* counter) : counter_(counter) {}
  ~CountOnExit() { counter_->fetch_add(1); }
  CountOnExit(const CountOnExit&) = delete;
  CountOnExit& operator=(const CountOnExit&) = delete;

 private:
  std::atomic<int64_t>* counter_;
};

/// The worker's Mesh call: the model, the options, what to return, the server's triangle limit,
/// the levels, the client's deadline and the time the call has taken so far.
wire::ToWorker MeshCall(const MeshOptions& options, const std::vector<double>& levels,
                        const StoredModel& model, const pb::MeshRequest& request,
                        const grpc::ServerContext& context, int64_t max_triangles,
                        Clock::time_point start, const std::string& request_id) {
  wire::ToWorker call;
  call.set_request_id(request_id);
  wire::MeshCall* mesh = call.mutable_mesh();
  FillModelFile(model, mesh->mutable_model());
  *mesh->mutable_options() = ToProto(options);
  *mesh->mutable_return_fields() = request.return_fields();
  mesh->set_max_triangles(max_triangles);
  for (double level : levels) mesh->add_lod_deviation_rel(level);
  if (HasDeadline(context)) {
    mesh->set_deadline_unix_ms(
        std::chrono::duration_cast<std::chrono::milliseconds>(context.deadline().time_since_epoch())
            .count());
  }
  mesh->set_elapsed_seconds(SecondsSince(start));
  return call;
}

}  // namespace

RdmeshService::RdmeshService(ServiceConfig config)
    : config_(std::move(config)),
      resolved_threads_(config_.threads > 0
                            ? config_.threads
                            : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))),
      index_(config_.spool_dir, config_.cache_bytes),
      pool_(config_.worker, config_.max_workers > 0 ? config_.max_workers : config_.max_jobs + 2),
      limiter_(config_.max_jobs, config_.max_queue) {}

Status RdmeshService::StartWorkers() { return pool_.Prestart(config_.max_jobs); }

void RdmeshService::BeginShutdown() {
  shutting_down_ = true;
  limiter_.Close();
}

RequestLog RdmeshService::StartRequest(grpc::ServerContext* context, const char* method,
                                       bool quiet) const {
  RequestLog log(RequestIdFrom(Metadata(*context, "x-request-id")));
  context->AddInitialMetadata("x-request-id", log.id());
  if (quiet) {
    log.Debug("{} from {}", method, context->peer());
  } else {
    log.Info("{} from {}", method, context->peer());
  }
  return log;
}

grpc::Status RdmeshService::Authorize(grpc::ServerContext* context, const RequestLog& log) const {
  if (config_.token.empty()) return grpc::Status::OK;
  if (BearerTokenMatches(Metadata(*context, "authorization"), config_.token)) {
    return grpc::Status::OK;
  }
  log.Warn("refused: missing or wrong bearer token");
  return Unauthenticated("this server needs an 'authorization: Bearer <token>' header");
}

Result<std::shared_ptr<const StoredModel>> RdmeshService::Accept(
    grpc::ServerContext* context, const std::string& bytes, const std::string& name,
    ModelFormat format, const RequestLog& log, bool* cached) {
  const auto parse = [&](const StoredModel& spooled, bool* refuse) -> Result<pb::ModelInfo> {
    Status error = Status::Ok();
    std::unique_ptr<WorkerProcess> worker = pool_.Acquire(
        spooled.id, [context] { return context->IsCancelled(); }, &error);
    if (!worker) return error;
    wire::ToWorker call;
    call.set_request_id(log.id());
    FillModelFile(spooled, call.mutable_load()->mutable_model());
    std::optional<pb::ModelInfo> info;
    active_parses_.fetch_add(1);
    const CallEnd end = CallWorker(
        worker.get(), pool_.settings(), call, ReaderName(spooled.format),
        [&info](const wire::FromWorker& reply) {
          if (reply.has_ready()) info = reply.ready().model();
          return true;
        },
        [context] { return context->IsCancelled(); }, DeadlineOf(*context), log);
    active_parses_.fetch_sub(1);
    ReturnWorker(std::move(worker), end, spooled.id);
    *refuse = end.crashed && end.phase == "load" && end.status.code() == StatusCode::kParseError;
    if (!end.status.ok()) return end.status;
    if (!info) return Status(StatusCode::kInternal, "the worker described no model");
    if (info->faces() == 0) {
      return Status(StatusCode::kEmptyModel, "the model '" + name + "' holds no faces");
    }
    info->set_name(info->name().empty() ? name : info->name());
    return *info;
  };
  Result<std::shared_ptr<const StoredModel>> entry =
      index_.GetOrParse(bytes, name, format, parse, cached);
  if (!entry.ok()) {
    return Status(entry.status().code(),
                  "cannot use model '" + name + "': " + entry.status().message());
  }
  if (*cached) {
    log.Info("model {} '{}' already indexed", (*entry)->id.substr(0, 12), name);
  } else {
    log.Info("model {} '{}' parsed: {} bytes, {} faces in {:.3f} s", (*entry)->id.substr(0, 12),
             name, (*entry)->file_bytes, (*entry)->info.faces(), (*entry)->load_seconds);
  }
  return entry;
}

Result<std::shared_ptr<const StoredModel>> RdmeshService::Resolve(grpc::ServerContext* context,
                                                                  const pb::ModelRef& ref,
                                                                  const RequestLog& log,
                                                                  bool* cached) {
  *cached = false;
  switch (ref.source_case()) {
    case pb::ModelRef::kModelId: {
      if (!IsSha256Hex(ref.model_id())) {
        return Status(StatusCode::kInvalidArgument,
                      "model_id must be 64 lower-case hex digits (the id UploadModel returned)");
      }
      std::shared_ptr<const StoredModel> entry = index_.Find(ref.model_id());
      if (!entry) {
        return Status(StatusCode::kNotFound, "model " + ref.model_id() +
                                                 " is not in the cache (never uploaded, or "
                                                 "evicted): upload it again");
      }
      *cached = true;
      return entry;
    }
    case pb::ModelRef::kInlineModel: {
      const pb::InlineModel& model = ref.inline_model();
      if (model.data().size() > config_.max_model_bytes) {
        return Status(StatusCode::kResourceExhausted,
                      "the inline model is " + std::to_string(model.data().size()) +
                          " bytes, more than the server's --max-model-bytes of " +
                          std::to_string(config_.max_model_bytes));
      }
      return Accept(context, model.data(), model.name().empty() ? "inline" : model.name(),
                    FromProto(model.format()), log, cached);
    }
    case pb::ModelRef::kServerPath: {
      if (config_.data_root.empty()) {
        return Status(StatusCode::kPermissionDenied,
                      "server-side file reads are off; start rdmeshd with --data-root DIR");
      }
      Result<std::string> path = ResolveUnderRoot(config_.data_root, ref.server_path());
      if (!path.ok()) return path.status();
      Result<std::string> content = ReadFileLimited(*path, config_.max_model_bytes);
      if (!content.ok()) return content.status();
      return Accept(context, *content, ref.server_path(), ModelFormat::kAuto, log, cached);
    }
    case pb::ModelRef::SOURCE_NOT_SET:
      break;
  }
  return Status(StatusCode::kInvalidArgument,
                "the request names no model: set model_id, inline_model or server_path");
}

grpc::Status RdmeshService::UploadModel(grpc::ServerContext* context,
                                        grpc::ServerReader<pb::ModelChunk>* reader,
                                        pb::ModelInfo* response) {
  const Clock::time_point start = Clock::now();
  const RequestLog log = StartRequest(context, "UploadModel");
  if (grpc::Status auth = Authorize(context, log); !auth.ok()) return auth;
  std::string bytes;
  std::string name;
  ModelFormat format = ModelFormat::kAuto;
  pb::ModelChunk chunk;
  bool first = true;
  while (reader->Read(&chunk)) {
    if (first) {
      name = chunk.name();
      format = FromProto(chunk.format());
      if (chunk.total_bytes() > config_.max_model_bytes) {
        return Finish(
            log,
            ToGrpcStatus(Status(StatusCode::kResourceExhausted,
                                "the model is " + std::to_string(chunk.total_bytes()) +
                                    " bytes, more than the server's --max-model-bytes of " +
                                    std::to_string(config_.max_model_bytes))),
            start);
      }
      if (chunk.total_bytes() > 0) bytes.reserve(chunk.total_bytes());
      first = false;
    }
    if (bytes.size() + chunk.data().size() > config_.max_model_bytes) {
      return Finish(log,
                    ToGrpcStatus(Status(StatusCode::kResourceExhausted,
                                        "the model passes the server's --max-model-bytes of " +
                                            std::to_string(config_.max_model_bytes) + " bytes")),
                    start);
    }
    bytes += chunk.data();
  }
  if (context->IsCancelled()) {
    return Finish(log, ToGrpcStatus(Status(StatusCode::kCancelled, "upload cancelled")), start);
  }
  if (bytes.empty()) {
    return Finish(log,
                  ToGrpcStatus(Status(StatusCode::kInvalidArgument, "the upload holds no bytes")),
                  start);
  }
  if (name.empty()) name = "upload";
  bool cached = false;
  Result<std::shared_ptr<const StoredModel>> entry =
      Accept(context, bytes, name, format, log, &cached);
  if (!entry.ok()) return Finish(log, ToGrpcStatus(entry.status()), start);
  *response = Describe(**entry, cached);
  return Finish(log, grpc::Status::OK, start);
}

grpc::Status RdmeshService::GetModelInfo(grpc::ServerContext* context, const pb::ModelRef* request,
                                         pb::ModelInfo* response) {
  const Clock::time_point start = Clock::now();
  const RequestLog log = StartRequest(context, "GetModelInfo");
  if (grpc::Status auth = Authorize(context, log); !auth.ok()) return auth;
  bool cached = false;
  Result<std::shared_ptr<const StoredModel>> entry = Resolve(context, *request, log, &cached);
  if (!entry.ok()) return Finish(log, ToGrpcStatus(entry.status()), start);
  *response = Describe(**entry, cached);
  return Finish(log, grpc::Status::OK, start);
}

void RdmeshService::ReturnWorker(std::unique_ptr<WorkerProcess> worker, const CallEnd& end,
                                 const std::string& model_id) {
  if (end.worker_ok) {
    worker->Remember(model_id);
    pool_.Release(std::move(worker));
  } else {
    pool_.Discard(std::move(worker));
  }
}

Result<RdmeshService::MeshPlan> RdmeshService::PlanMesh(const pb::MeshRequest& request) const {
  MeshPlan plan;
  plan.options = FromProto(request.options());
  if (Status valid = ValidateOptions(plan.options); !valid.ok()) return valid;
  if (request.lod_deviation_rel_size() > 0) {
    // ResolveLevels refuses a set max_deviation_rel, as it does for `rdmesh mesh --lod`.
    Result<std::vector<double>> levels = ResolveLevels(
        {request.lod_deviation_rel().begin(), request.lod_deviation_rel().end()}, plan.options);
    if (!levels.ok()) return levels.status();
    plan.levels = std::move(*levels);
  }
  MeshOptions& options = plan.options;
  if (config_.max_triangles > 0 && options.max_triangles > config_.max_triangles) {
    return Status(StatusCode::kInvalidArgument, "max_triangles " +
                                                    std::to_string(options.max_triangles) +
                                                    " is more than the server's limit of " +
                                                    std::to_string(config_.max_triangles));
  }
  options.threads =
      options.threads > 0 ? std::min(options.threads, resolved_threads_) : resolved_threads_;
  return plan;
}

grpc::Status RdmeshService::Admit(const std::function<bool()>& cancelled) {
  switch (limiter_.Acquire(cancelled)) {
    case JobLimiter::Admission::kAdmitted:
      return grpc::Status::OK;
    case JobLimiter::Admission::kQueueFull:
      return ToGrpcStatus(Status(StatusCode::kResourceExhausted,
                                 "the job queue is full (" + std::to_string(limiter_.max_jobs()) +
                                     " running, " + std::to_string(limiter_.max_queue()) +
                                     " waiting); retry later"));
    case JobLimiter::Admission::kStopped:
      return ToGrpcStatus(Status(StatusCode::kCancelled, "cancelled while queued"));
    case JobLimiter::Admission::kClosed:
      break;
  }
  return Unavailable("the server is shutting down");
}

pb::MeshEvent RdmeshService::StartedEvent(const MeshPlan& plan, const StoredModel& model,
                                          const pb::ModelInfo& loaded, double queue_seconds,
                                          pid_t worker, const RequestLog& log) const {
  const MeshOptions& options = plan.options;
  pb::MeshEvent event;
  pb::Started* started = event.mutable_started();
  started->set_job_id(log.id());
  *started->mutable_model() = Describe(model, true);
  started->mutable_model()->set_cached(loaded.cached());
  started->mutable_model()->set_load_seconds(loaded.load_seconds());
  started->mutable_model()->set_from_store(loaded.from_store());
  // With levels of detail, the options of the finest level.
  const MeshOptions shown =
      plan.levels.empty() ? options : LevelOptions(options, plan.levels.back());
  pb::ResolvedOptions* resolved = started->mutable_options();
  *resolved->mutable_options() = ToProto(shown);
  resolved->mutable_options()->set_max_deviation_rel(MaxDeviationRel(shown));  // the one used
  resolved->set_max_deviation_abs(shown.max_deviation > 0
                                      ? shown.max_deviation
                                      : MaxDeviationRel(shown) * model.info.diagonal());
  resolved->set_threads(options.threads);
  resolved->set_server_max_triangles(config_.max_triangles);
  started->set_faces_requested(
      options.face_ids.empty() ? model.info.faces() : static_cast<int>(options.face_ids.size()));
  started->set_queue_seconds(queue_seconds);
  log.Info(
      "meshing {} faces on {} threads in worker {}{}: max_deviation {} (abs {}), rd {}, "
      "budget {}, levels {}",
      started->faces_requested(), options.threads, worker,
      loaded.cached() ? "" : " (parsed the model)", shown.max_deviation,
      resolved->max_deviation_abs(), options.rd_tolerance, options.max_triangles,
      plan.levels.size());
  return event;
}

grpc::Status RdmeshService::Mesh(grpc::ServerContext* context, const pb::MeshRequest* request,
                                 grpc::ServerWriter<pb::MeshEvent>* writer) {
  const Clock::time_point start = Clock::now();
  const RequestLog log = StartRequest(context, "Mesh");
  if (grpc::Status auth = Authorize(context, log); !auth.ok()) return auth;
  if (shutting_down_) {
    return Finish(log, Unavailable("the server is shutting down"), start);
  }

  // 1. Validate: the options and levels, then the model (parsed on a worker unless indexed).
  // Face ids past the model's are the engine's to refuse, as in a local run.
  Result<MeshPlan> plan = PlanMesh(*request);
  if (!plan.ok()) return Finish(log, ToGrpcStatus(plan.status()), start);
  bool cached = false;
  Result<std::shared_ptr<const StoredModel>> entry =
      Resolve(context, request->model(), log, &cached);
  if (!entry.ok()) return Finish(log, ToGrpcStatus(entry.status()), start);
  const StoredModel& model = **entry;

  // 2. Admit: a job slot, then a worker (one that holds the model, when one is idle).
  const Clock::time_point queued = Clock::now();
  const auto cancelled = [context] { return context->IsCancelled(); };
  if (grpc::Status admitted = Admit(cancelled); !admitted.ok()) {
    return Finish(log, admitted, start);
  }
  JobSlot slot(&limiter_);
  CountOnExit count_completed(&jobs_completed_);
  Status error = Status::Ok();
  std::unique_ptr<WorkerProcess> worker = pool_.Acquire(model.id, cancelled, &error);
  if (!worker) return Finish(log, ToGrpcStatus(error), start);
  const double queue_seconds = SecondsSince(queued);

  // 3. Build the worker call.
  const wire::ToWorker call = MeshCall(plan->options, plan->levels, model, *request, *context,
                                       config_.max_triangles, start, log.id());

  // 4. Relay the worker's events to the client: its Ready as the Started event, then the rest.
  int64_t face_messages = 0;
  std::optional<pb::Summary> summary;
  active_jobs_.fetch_add(1);
  const CallEnd end = CallWorker(
      worker.get(), pool_.settings(), call, ReaderName(model.format),
      [&](const wire::FromWorker& reply) {
        if (reply.has_ready()) {
          return writer->Write(
              StartedEvent(*plan, model, reply.ready().model(), queue_seconds, worker->pid(), log));
        }
        if (!reply.has_event()) return true;
        if (reply.event().has_face()) ++face_messages;
        if (reply.event().has_summary()) summary = reply.event().summary();
        return writer->Write(reply.event());
      },
      cancelled, MeshDeadline(*context, start, plan->options.timeout_seconds), log);
  active_jobs_.fetch_sub(1);
  ReturnWorker(std::move(worker), end, model.id);
  if (end.status.ok() && summary) {
    log.Info("{} triangles, {} nodes, {} faces ok, {} failed; deviation {:.4g}; {} face messages",
             summary->triangles(), summary->nodes(), summary->faces_ok(), summary->faces_failed(),
             summary->estimated_deviation(), face_messages);
  }
  return Finish(log, ToGrpcStatus(end.status), start);
}

grpc::Status RdmeshService::GetServerStatus(grpc::ServerContext* context,
                                            const pb::GetServerStatusRequest* /*request*/,
                                            pb::ServerStatus* response) {
  const RequestLog log = StartRequest(context, "GetServerStatus", /*quiet=*/true);
  if (grpc::Status auth = Authorize(context, log); !auth.ok()) return auth;
  response->set_version(config_.version);
  response->set_serving(!shutting_down_);
  response->set_active_jobs(active_jobs_.load());
  response->set_queued_jobs(limiter_.queued());
  response->set_max_jobs(limiter_.max_jobs());
  response->set_max_queue(limiter_.max_queue());
  response->set_threads(resolved_threads_);
  response->set_cached_models(index_.size());
  response->set_cache_bytes(index_.bytes());
  response->set_cache_limit_bytes(index_.limit_bytes());
  response->set_workers(pool_.live());
  response->set_idle_workers(pool_.idle());
  response->set_max_workers(pool_.max_workers());
  response->set_workers_lost(pool_.lost());
  response->set_refused_models(index_.refused());
  response->set_active_parses(active_parses_.load());
  for (pid_t pid : pool_.pids()) response->add_worker_pids(static_cast<int64_t>(pid));
  response->set_max_model_bytes(config_.max_model_bytes);
  response->set_max_triangles(config_.max_triangles);
  response->set_jobs_completed(jobs_completed_.load());
  response->set_uptime_seconds(SecondsSince(started_));
  return grpc::Status::OK;
}

}  // namespace rdmesh::server
