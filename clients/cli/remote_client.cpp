#include "remote_client.h"

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>
#include <utility>

#include "rdmesh/sha256.h"
#include "rdmesh/v1/rdmesh.grpc.pb.h"
#include "wire/convert.h"
#include "wire/status_map.h"

namespace rdmesh::cli {
namespace {

namespace pb = ::rdmesh::v1;
constexpr std::size_t kChunkBytes = 1u << 20;
// The request header naming the model of a call (its sha256): a balancer routes on it
// (docs/ROUTING.md).
constexpr char kModelHeader[] = "x-rdmesh-model";

Result<std::string> ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status(StatusCode::kNotFound, "cannot open '" + path + "'");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

std::string Trim(std::string text) {
  const char* kSpace = " \t\r\n";
  const std::size_t begin = text.find_first_not_of(kSpace);
  if (begin == std::string::npos) return "";
  return text.substr(begin, text.find_last_not_of(kSpace) - begin + 1);
}

/// A channel with the credentials the environment asks for.
Result<std::shared_ptr<grpc::Channel>> Connect(const std::string& address) {
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (const char* ca = std::getenv("RDMESH_TLS_CA"); ca != nullptr && *ca != '\0') {
    Result<std::string> pem = ReadFile(ca);
    if (!pem.ok()) return Status(StatusCode::kIoError, "RDMESH_TLS_CA: " + pem.status().message());
    grpc::SslCredentialsOptions tls;
    tls.pem_root_certs = *pem;
    credentials = grpc::SslCredentials(tls);
  }
  grpc::ChannelArguments arguments;
  arguments.SetMaxReceiveMessageSize(64 << 20);
  return grpc::CreateCustomChannel(address, credentials, arguments);
}

/// Adds the bearer token from RDMESH_TOKEN / RDMESH_TOKEN_FILE, if any.
Status AddToken(grpc::ClientContext* call) {
  std::string token;
  if (const char* value = std::getenv("RDMESH_TOKEN"); value != nullptr) token = value;
  if (const char* file = std::getenv("RDMESH_TOKEN_FILE"); token.empty() && file != nullptr) {
    Result<std::string> content = ReadFile(file);
    if (!content.ok()) {
      return Status(StatusCode::kIoError, "RDMESH_TOKEN_FILE: " + content.status().message());
    }
    token = *content;
  }
  token = Trim(token);
  if (!token.empty()) call->AddMetadata("authorization", "Bearer " + token);
  return Status::Ok();
}

/// The metadata of every call about the model `model_id`: the token and the routing header.
Status PrepareCall(grpc::ClientContext* call, const std::string& model_id) {
  call->AddMetadata(kModelHeader, model_id);
  return AddToken(call);
}

/// Cancels `call` as soon as the context asks to stop, until destroyed.
class StopWatcher {
 public:
  StopWatcher(Context* context, grpc::ClientContext* call)
      : thread_([this, context, call] {
          while (!done_) {
            if (context->ShouldStop()) {
              call->TryCancel();
              return;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
          }
        }) {}
  ~StopWatcher() {
    done_ = true;
    thread_.join();
  }

 private:
  std::atomic<bool> done_{false};
  std::thread thread_;
};

/// The engine status for a failed call: the context's own stop, or the server's error.
Status CallFailed(const grpc::Status& status, Context* context, const std::string& address) {
  if (context->ShouldStop()) return context->StopStatus();
  if (status.error_code() == grpc::StatusCode::UNAVAILABLE) {
    return Status(StatusCode::kIoError,
                  "rdmeshd at " + address + " is unavailable: " + status.error_message());
  }
  return server::FromGrpcStatus(status);
}

/// Uploads `bytes` (in 1 MiB chunks; the server parses them once and caches the model).
Status Upload(pb::Rdmesh::Stub* stub, const std::string& address, const std::string& model_path,
              const std::string& bytes, const std::string& model_id, Context* context) {
  pb::ModelInfo uploaded;
  grpc::ClientContext call;
  if (Status prepared = PrepareCall(&call, model_id); !prepared.ok()) return prepared;
  StopWatcher watcher(context, &call);
  std::unique_ptr<grpc::ClientWriter<pb::ModelChunk>> writer = stub->UploadModel(&call, &uploaded);
  const std::string name = model_path.substr(model_path.find_last_of('/') + 1);
  for (std::size_t offset = 0; offset == 0 || offset < bytes.size(); offset += kChunkBytes) {
    pb::ModelChunk chunk;
    chunk.set_data(bytes.substr(offset, kChunkBytes));
    if (offset == 0) {
      chunk.set_name(name);
      chunk.set_total_bytes(bytes.size());
    }
    if (!writer->Write(chunk)) break;  // the server answered early; Finish says why
  }
  writer->WritesDone();
  grpc::Status status = writer->Finish();
  if (!status.ok()) return CallFailed(status, context, address);
  if (uploaded.model_id() != model_id) {
    return Status(StatusCode::kInternal, "rdmeshd named the model " + uploaded.model_id() +
                                             ", not its sha256 " + model_id);
  }
  return Status::Ok();
}

/// One Mesh call, rebuilding the result from the stream: one MeshResult, or one per level of
/// detail (each LevelStarted event starts the next). Sets `*not_found` when the server does not
/// hold the model (the call then returns the server's NOT_FOUND).
Result<std::vector<MeshResult>> StreamMesh(pb::Rdmesh::Stub* stub, const std::string& address,
                                           const pb::MeshRequest& request, Context* context,
                                           bool* not_found) {
  *not_found = false;
  grpc::ClientContext call;
  if (Status prepared = PrepareCall(&call, request.model().model_id()); !prepared.ok()) {
    return prepared;
  }
  std::vector<server::MeshResultBuilder> builders(1);
  pb::MeshEvent started;  // the Started event, given to every level's builder
  grpc::Status status;
  {
    StopWatcher watcher(context, &call);
    std::unique_ptr<grpc::ClientReader<pb::MeshEvent>> reader = stub->Mesh(&call, request);
    pb::MeshEvent event;
    Status added = Status::Ok();
    while (reader->Read(&event)) {
      if (event.has_progress()) {
        Progress progress;
        progress.stage = server::FromProto(event.progress().stage());
        progress.done = event.progress().done();
        progress.total = event.progress().total();
        context->ReportProgress(progress);
        continue;
      }
      if (event.has_started()) started = event;
      if (event.has_level_started() && added.ok()) {
        // Level 0 fills the first builder; each later level starts after the previous Summary.
        const int level = event.level_started().level();
        const bool first = level == 0 && builders.size() == 1 && !builders.back().has_summary();
        const bool next = level > 0 && level == static_cast<int>(builders.size()) &&
                          builders.back().has_summary();
        if (!first && !next) added = Status(StatusCode::kInvalidArgument, "levels out of order");
        if (next) {
          builders.emplace_back();
          added = builders.back().Add(started);
        }
        continue;
      }
      if (added.ok()) added = builders.back().Add(event);
      if (!added.ok()) call.TryCancel();
    }
    status = reader->Finish();
    if (!added.ok()) {
      return Status(StatusCode::kInternal, "unexpected stream from rdmeshd: " + added.message());
    }
  }
  if (!status.ok()) {
    *not_found =
        status.error_code() == grpc::StatusCode::NOT_FOUND && !builders.front().has_started();
    return CallFailed(status, context, address);
  }
  std::vector<MeshResult> results;
  for (server::MeshResultBuilder& builder : builders) {
    Result<MeshResult> result = builder.Finish();
    if (!result.ok()) return result.status();
    results.push_back(std::move(*result));
  }
  return results;
}

}  // namespace

Result<std::vector<MeshResult>> MeshRemoteLevels(const std::string& address,
                                                 const std::string& model_path,
                                                 const MeshOptions& options,
                                                 const std::vector<double>& levels_rel,
                                                 Context* context) {
  Context local;
  if (context == nullptr) context = &local;
  if (options.timeout_seconds > 0) context->SetTimeout(options.timeout_seconds);
  Result<std::shared_ptr<grpc::Channel>> channel = Connect(address);
  if (!channel.ok()) return channel.status();
  std::unique_ptr<pb::Rdmesh::Stub> stub = pb::Rdmesh::NewStub(*channel);
  Result<std::string> bytes = ReadFile(model_path);
  if (!bytes.ok()) return bytes.status();
  const std::string model_id = Sha256Hex(*bytes);

  // Mesh the model by its id; upload it only when the server does not hold it (a new model, an
  // evicted one, or one whose replica is gone), then mesh again.
  pb::MeshRequest request;
  request.mutable_model()->set_model_id(model_id);
  *request.mutable_options() = server::ToProto(options);
  request.mutable_return_fields()->set_uv(true);
  request.mutable_return_fields()->set_normals(true);
  request.mutable_return_fields()->set_node_topology(true);
  request.mutable_return_fields()->set_edges(true);  // the edge lines, as a local run has them
  request.mutable_return_fields()->set_triangle_deviation(true);  // VTU and PLY cell data
  if (!levels_rel.empty()) {
    // The levels replace the relative deviation, which ResolveLevels has left unset.
    for (double level : levels_rel) request.add_lod_deviation_rel(level);
  }
  bool not_found = false;
  Result<std::vector<MeshResult>> result =
      StreamMesh(stub.get(), address, request, context, &not_found);
  if (!not_found) return result;
  if (Status uploaded = Upload(stub.get(), address, model_path, *bytes, model_id, context);
      !uploaded.ok()) {
    return uploaded;
  }
  return StreamMesh(stub.get(), address, request, context, &not_found);
}

Result<MeshResult> MeshRemote(const std::string& address, const std::string& model_path,
                              const MeshOptions& options, Context* context) {
  Result<std::vector<MeshResult>> results =
      MeshRemoteLevels(address, model_path, options, {}, context);
  if (!results.ok()) return results.status();
  if (results->size() != 1)
    return Status(StatusCode::kInternal, "rdmeshd sent levels of detail that were not asked for");
  return std::move(results->front());
}

}  // namespace rdmesh::cli
