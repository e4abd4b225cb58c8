#include "rdmesh_service.h"

#include <algorithm>
#include <string>
#include <thread>
#include <utility>

#include "access.h"
#include "convert.h"
#include "mesh_job.h"
#include "sha256.h"
#include "status_map.h"

namespace rdmesh::server {
namespace {

namespace pb = ::rdmesh::v1;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
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

}  // namespace

RdmeshService::RdmeshService(ServiceConfig config)
    : config_(std::move(config)),
      resolved_threads_(config_.threads > 0
                            ? config_.threads
                            : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))),
      cache_(config_.cache_bytes),
      limiter_(config_.max_jobs, config_.max_queue) {}

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

pb::ModelInfo RdmeshService::Describe(const CachedModel& entry, bool cached) const {
  pb::ModelInfo info = ToProto(entry.info);
  info.set_model_id(entry.id);
  info.set_file_bytes(entry.file_bytes);
  info.set_cached(cached);
  info.set_load_seconds(cached ? 0.0 : entry.load_seconds);
  return info;
}

Result<std::shared_ptr<const CachedModel>> RdmeshService::Resolve(const pb::ModelRef& ref,
                                                                  const RequestLog& log,
                                                                  bool* cached) {
  *cached = false;
  std::string bytes;
  std::string name;
  ModelFormat format = ModelFormat::kAuto;
  switch (ref.source_case()) {
    case pb::ModelRef::kModelId: {
      if (!IsSha256Hex(ref.model_id())) {
        return Status(StatusCode::kInvalidArgument,
                      "model_id must be 64 lower-case hex digits (the id UploadModel returned)");
      }
      std::shared_ptr<const CachedModel> entry = cache_.Find(ref.model_id());
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
      bytes = model.data();
      name = model.name().empty() ? "inline" : model.name();
      format = FromProto(model.format());
      break;
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
      bytes = std::move(*content);
      name = ref.server_path();
      break;
    }
    case pb::ModelRef::SOURCE_NOT_SET:
      return Status(StatusCode::kInvalidArgument,
                    "the request names no model: set model_id, inline_model or server_path");
  }
  Result<std::shared_ptr<const CachedModel>> entry = cache_.GetOrLoad(bytes, name, format, cached);
  if (!entry.ok()) {
    return Status(entry.status().code(),
                  "cannot use model '" + name + "': " + entry.status().message());
  }
  if (*cached) {
    log.Info("model {} '{}' from the cache", (*entry)->id.substr(0, 12), name);
  } else {
    log.Info("model {} '{}' parsed: {} bytes, {} faces in {:.3f} s", (*entry)->id.substr(0, 12),
             name, (*entry)->file_bytes, (*entry)->info.faces, (*entry)->load_seconds);
  }
  return entry;
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
  Result<std::shared_ptr<const CachedModel>> entry = cache_.GetOrLoad(bytes, name, format, &cached);
  if (!entry.ok()) {
    return Finish(log,
                  ToGrpcStatus(Status(entry.status().code(), "cannot use model '" + name +
                                                                 "': " + entry.status().message())),
                  start);
  }
  log.Info("model {} '{}': {} bytes, {} faces, {}", (*entry)->id.substr(0, 12), name, bytes.size(),
           (*entry)->info.faces, cached ? "already cached" : "parsed");
  *response = Describe(**entry, cached);
  return Finish(log, grpc::Status::OK, start);
}

grpc::Status RdmeshService::GetModelInfo(grpc::ServerContext* context, const pb::ModelRef* request,
                                         pb::ModelInfo* response) {
  const Clock::time_point start = Clock::now();
  const RequestLog log = StartRequest(context, "GetModelInfo");
  if (grpc::Status auth = Authorize(context, log); !auth.ok()) return auth;
  bool cached = false;
  Result<std::shared_ptr<const CachedModel>> entry = Resolve(*request, log, &cached);
  if (!entry.ok()) return Finish(log, ToGrpcStatus(entry.status()), start);
  *response = Describe(**entry, cached);
  return Finish(log, grpc::Status::OK, start);
}

grpc::Status RdmeshService::Mesh(grpc::ServerContext* context, const pb::MeshRequest* request,
                                 grpc::ServerWriter<pb::MeshEvent>* writer) {
  const Clock::time_point start = Clock::now();
  const RequestLog log = StartRequest(context, "Mesh");
  if (grpc::Status auth = Authorize(context, log); !auth.ok()) return auth;
  if (shutting_down_) {
    return Finish(log, Unavailable("the server is shutting down"), start);
  }

  Result<MeshOptions> options = FromProto(request->options());
  if (!options.ok()) return Finish(log, ToGrpcStatus(options.status()), start);
  if (Status valid = ValidateOptions(*options); !valid.ok()) {
    return Finish(log, ToGrpcStatus(valid), start);
  }
  if (config_.max_triangles > 0 && options->max_triangles > config_.max_triangles) {
    return Finish(log,
                  ToGrpcStatus(Status(StatusCode::kInvalidArgument,
                                      "max_triangles " + std::to_string(options->max_triangles) +
                                          " is more than the server's limit of " +
                                          std::to_string(config_.max_triangles))),
                  start);
  }
  options->threads =
      options->threads > 0 ? std::min(options->threads, resolved_threads_) : resolved_threads_;

  bool cached = false;
  Result<std::shared_ptr<const CachedModel>> entry = Resolve(request->model(), log, &cached);
  if (!entry.ok()) return Finish(log, ToGrpcStatus(entry.status()), start);
  const CachedModel& model = **entry;
  for (int id : options->face_ids) {
    if (id > model.info.faces) {
      return Finish(
          log,
          ToGrpcStatus(Status(StatusCode::kInvalidArgument,
                              "face id " + std::to_string(id) + " is out of range: the model " +
                                  "has faces 1.." + std::to_string(model.info.faces))),
          start);
    }
  }

  const Clock::time_point queued = Clock::now();
  switch (limiter_.Acquire([context] { return context->IsCancelled(); })) {
    case JobLimiter::Admission::kAdmitted:
      break;
    case JobLimiter::Admission::kQueueFull:
      return Finish(
          log,
          ToGrpcStatus(Status(StatusCode::kResourceExhausted,
                              "the job queue is full (" + std::to_string(limiter_.max_jobs()) +
                                  " running, " + std::to_string(limiter_.max_queue()) +
                                  " waiting); retry later")),
          start);
    case JobLimiter::Admission::kStopped:
      return Finish(log, ToGrpcStatus(Status(StatusCode::kCancelled, "cancelled while queued")),
                    start);
    case JobLimiter::Admission::kClosed:
      return Finish(log, Unavailable("the server is shutting down"), start);
  }
  JobSlot slot(&limiter_);
  struct CountCompleted {
    std::atomic<int64_t>* counter;
    ~CountCompleted() { counter->fetch_add(1); }
  } count_completed{&jobs_completed_};

  pb::MeshEvent started_event;
  pb::Started* started = started_event.mutable_started();
  started->set_job_id(log.id());
  *started->mutable_model() = Describe(model, cached);
  pb::ResolvedOptions* resolved = started->mutable_options();
  *resolved->mutable_options() = ToProto(*options);
  resolved->set_max_deviation_abs(options->max_deviation > 0
                                      ? options->max_deviation
                                      : options->max_deviation_rel * model.info.diagonal);
  resolved->set_threads(options->threads);
  resolved->set_server_max_triangles(config_.max_triangles);
  started->set_faces_requested(
      options->face_ids.empty() ? model.info.faces : static_cast<int>(options->face_ids.size()));
  started->set_queue_seconds(SecondsSince(queued));
  log.Info("meshing {} faces on {} threads: max_deviation {} (abs {}), rd {}, budget {}",
           started->faces_requested(), options->threads, options->max_deviation,
           resolved->max_deviation_abs(), options->rd_tolerance, options->max_triangles);
  if (!writer->Write(started_event)) {
    return Finish(log, ToGrpcStatus(Status(StatusCode::kCancelled, "client went away")), start);
  }

  MeshJob::Params params;
  params.model = *entry;
  params.options = std::move(*options);
  params.with_uv = request->return_fields().uv();
  params.with_normals = request->return_fields().normals();
  params.with_topology = request->return_fields().node_topology();
  params.max_triangles = config_.max_triangles;
  params.deadline = context->deadline();
  params.start = start;
  MeshJob job(std::move(params), &log, &active_jobs_);
  const Status status =
      job.Run([writer](const pb::MeshEvent& event) { return writer->Write(event); },
              [context] { return context->IsCancelled(); });
  if (status.ok()) {
    log.Info("{} triangles, {} nodes, {} faces ok, {} failed; deviation {:.4g}; {} face messages",
             job.summary().triangles, job.summary().nodes, job.summary().faces_ok,
             job.summary().faces_failed, job.summary().estimated_deviation, job.face_messages());
  }
  return Finish(log, ToGrpcStatus(status), start);
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
  response->set_cached_models(cache_.size());
  response->set_cache_bytes(cache_.bytes());
  response->set_cache_limit_bytes(cache_.limit_bytes());
  response->set_max_model_bytes(config_.max_model_bytes);
  response->set_max_triangles(config_.max_triangles);
  response->set_jobs_completed(jobs_completed_.load());
  response->set_uptime_seconds(SecondsSince(started_));
  return grpc::Status::OK;
}

}  // namespace rdmesh::server
