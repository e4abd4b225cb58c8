// rdmeshd: the rdmesh gRPC daemon. Every flag can also be set through an environment variable
// (flags win). See docs/SERVICE.md.

#include <grpc/support/log.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "common/log.h"
#include "common/read_file.h"
#include "daemon/access.h"
#include "daemon/rdmesh_service.h"
#include "grpc/health/v1/health.pb.h"
#include "worker/worker.h"

#ifndef RDMESH_VERSION
#define RDMESH_VERSION "dev"
#endif

namespace {

using rdmesh::server::LogLine;

struct Flags {
  std::string listen = "127.0.0.1:50051";
  rdmesh::server::ServiceConfig service;
  std::string log_format = "text";
  std::string log_level = "info";
  std::string tls_cert;
  std::string tls_key;
  std::string token_file;
  double grace_seconds = 10.0;
};

/// `rdmeshd --worker-fd N ...`: a worker process started by the daemon (not for people).
int WorkerMain(int argc, char** argv) {
  rdmesh::server::WorkerConfig config;
  std::string log_format = "text";
  std::string log_level = "info";
  CLI::App app{"rdmeshd worker process (started by rdmeshd)"};
  app.add_option("--worker-fd", config.fd)->required();
  app.add_option("--worker-memory", config.memory_bytes);
  app.add_option("--cache-bytes", config.cache_bytes);
  app.add_option("--max-model-bytes", config.max_model_bytes);
  app.add_option("--cache-dir", config.store_dir);
  app.add_option("--cache-dir-bytes", config.store_bytes);
  app.add_option("--log-format", log_format);
  app.add_option("--log-level", log_level);
  CLI11_PARSE(app, argc, argv);
  rdmesh::server::InitLogging(
      log_format == "json" ? rdmesh::server::LogFormat::kJson : rdmesh::server::LogFormat::kText,
      log_level);
  rlimit no_core{0, 0};  // a crashing worker writes no core file
  setrlimit(RLIMIT_CORE, &no_core);
  return rdmesh::server::RunWorker(config);
}

/// This program, to start workers from: /proc/self/exe is the very binary the daemon runs, even
/// after an upgrade replaced the file on disk, so workers never run another version.
std::string SelfPath() { return "/proc/self/exe"; }

void LogFromGrpc(gpr_log_func_args* args) {
  spdlog::level::level_enum level = spdlog::level::info;
  if (args->severity == GPR_LOG_SEVERITY_DEBUG) level = spdlog::level::debug;
  if (args->severity == GPR_LOG_SEVERITY_ERROR) level = spdlog::level::err;
  LogLine(level, "grpc", args->message);
}

bool IsLoopback(const std::string& address) {
  return address.rfind("127.", 0) == 0 || address.rfind("localhost:", 0) == 0 ||
         address.rfind("[::1]:", 0) == 0 || address.rfind("unix:", 0) == 0;
}

/// Reads a whole file into `out`; false when it cannot be read.
bool ReadText(const std::string& path, std::string* out) {
  auto bytes = rdmesh::server::ReadFileLimited(path, 1u << 20);
  if (!bytes.ok()) return false;
  *out = std::move(*bytes);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--worker-fd") return WorkerMain(argc, argv);
  }
  // SIGTERM/SIGINT are taken by a thread of their own (sigwait): block them first, before gRPC
  // or anything else starts a thread, so that every thread inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  Flags flags;
  flags.service.version = RDMESH_VERSION;
  CLI::App app{"rdmeshd: the rdmesh meshing service (gRPC)"};
  app.set_version_flag("--version", RDMESH_VERSION);
  app.add_option("--listen", flags.listen, "Address to listen on, host:port (port 0 = any free)")
      ->envname("RDMESH_LISTEN")
      ->capture_default_str();
  app.add_option("--threads", flags.service.threads, "Engine threads per job (0 = all cores)")
      ->envname("RDMESH_THREADS")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--max-jobs", flags.service.max_jobs, "Meshing jobs running at once")
      ->envname("RDMESH_MAX_JOBS")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--max-queue", flags.service.max_queue,
                 "Jobs waiting for a slot; more are refused with RESOURCE_EXHAUSTED")
      ->envname("RDMESH_MAX_QUEUE")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--max-model-bytes", flags.service.max_model_bytes,
                 "Largest model file accepted (bytes; suffixes like 256MiB work)")
      ->envname("RDMESH_MAX_MODEL_BYTES")
      ->transform(CLI::AsSizeValue(false))
      ->capture_default_str();
  app.add_option("--max-triangles", flags.service.max_triangles,
                 "Largest mesh a job may produce (0 = no limit)")
      ->envname("RDMESH_MAX_TRIANGLES")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--cache-bytes", flags.service.cache_bytes,
                 "Model cache size, in model file bytes (suffixes like 1GiB work)")
      ->envname("RDMESH_CACHE_BYTES")
      ->transform(CLI::AsSizeValue(false))
      ->capture_default_str();
  app.add_option("--cache-dir", flags.service.worker.store_dir,
                 "Persistent store of parsed models, shared by the workers and by replicas on "
                 "the same volume: a model parsed once is read from here after a restart or on "
                 "another replica (off if unset; see docs/SCALE.md)")
      ->envname("RDMESH_CACHE_DIR");
  app.add_option("--cache-dir-bytes", flags.service.worker.store_bytes,
                 "Size limit of --cache-dir; the least recently used models go first (suffixes "
                 "like 20GiB work)")
      ->envname("RDMESH_CACHE_DIR_BYTES")
      ->transform(CLI::AsSizeValue(false))
      ->capture_default_str();
  app.add_option("--workers", flags.service.max_workers,
                 "Worker processes that read and mesh models (0 = max-jobs + 2)")
      ->envname("RDMESH_WORKERS")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--worker-memory", flags.service.worker.memory_bytes,
                 "Address-space limit of each worker process (0 = none; suffixes like 8GiB work)")
      ->envname("RDMESH_WORKER_MEMORY")
      ->transform(CLI::AsSizeValue(false))
      ->capture_default_str();
  app.add_option("--worker-cpu-seconds", flags.service.worker.cpu_seconds,
                 "CPU time one call may use in its worker before it is stopped (0 = no limit)")
      ->envname("RDMESH_WORKER_CPU_SECONDS")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--spool-dir", flags.service.spool_dir,
                 "Where uploaded model files are kept for the workers (default: a new "
                 "temporary directory, removed at exit)")
      ->envname("RDMESH_SPOOL_DIR")
      ->check(CLI::ExistingDirectory);
  app.add_option("--log-format", flags.log_format, "Log lines as text or json")
      ->envname("RDMESH_LOG_FORMAT")
      ->check(CLI::IsMember({"text", "json"}))
      ->capture_default_str();
  app.add_option("--log-level", flags.log_level, "trace, debug, info, warn, error or off")
      ->envname("RDMESH_LOG_LEVEL")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}))
      ->capture_default_str();
  auto* cert = app.add_option("--tls-cert", flags.tls_cert, "TLS certificate chain (PEM)")
                   ->envname("RDMESH_TLS_CERT")
                   ->check(CLI::ExistingFile);
  auto* key = app.add_option("--tls-key", flags.tls_key, "TLS private key (PEM)")
                  ->envname("RDMESH_TLS_KEY")
                  ->check(CLI::ExistingFile);
  cert->needs(key);
  key->needs(cert);
  app.add_option("--token-file", flags.token_file,
                 "File holding a bearer token that every call must present")
      ->envname("RDMESH_TOKEN_FILE")
      ->check(CLI::ExistingFile);
  app.add_option("--data-root", flags.service.data_root,
                 "Allow ModelRef.server_path reads of files under this directory (off if unset)")
      ->envname("RDMESH_DATA_ROOT")
      ->check(CLI::ExistingDirectory);
  app.add_option("--grace-seconds", flags.grace_seconds,
                 "On SIGTERM/SIGINT, let running jobs finish for this long, then cancel them")
      ->envname("RDMESH_GRACE_SECONDS")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  if (!rdmesh::server::InitLogging(flags.log_format == "json" ? rdmesh::server::LogFormat::kJson
                                                              : rdmesh::server::LogFormat::kText,
                                   flags.log_level)) {
    return 2;
  }
  gpr_set_log_function(LogFromGrpc);
  gpr_set_log_verbosity(GPR_LOG_SEVERITY_ERROR);

  if (!flags.token_file.empty()) {
    auto token = rdmesh::server::ReadTokenFile(flags.token_file);
    if (!token.ok()) {
      LogLine(spdlog::level::critical, "-", token.status().message());
      return 2;
    }
    flags.service.token = *token;
  }
  std::shared_ptr<grpc::ServerCredentials> credentials = grpc::InsecureServerCredentials();
  if (!flags.tls_cert.empty()) {
    grpc::SslServerCredentialsOptions tls;
    grpc::SslServerCredentialsOptions::PemKeyCertPair pair;
    if (!ReadText(flags.tls_key, &pair.private_key) ||
        !ReadText(flags.tls_cert, &pair.cert_chain)) {
      LogLine(spdlog::level::critical, "-", "cannot read --tls-cert or --tls-key");
      return 2;
    }
    tls.pem_key_cert_pairs.push_back(std::move(pair));
    credentials = grpc::SslServerCredentials(tls);
  }
  if (!IsLoopback(flags.listen) && flags.tls_cert.empty()) {
    LogLine(spdlog::level::warn, "-",
            "listening on " + flags.listen + " without TLS: traffic (and any token) is plain text");
  }

  // Register grpc.health.v1's descriptors so that reflection can describe the health service.
  (void)grpc::health::v1::HealthCheckRequest::descriptor();
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();

  std::string temporary_spool;
  if (flags.service.spool_dir.empty()) {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern =
        std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/rdmeshd-spool-XXXXXX";
    if (mkdtemp(pattern.data()) == nullptr) {
      LogLine(spdlog::level::critical, "-", "cannot create a spool directory " + pattern);
      return 1;
    }
    temporary_spool = pattern;
    flags.service.spool_dir = pattern;
  }
  flags.service.worker.executable = SelfPath();
  flags.service.worker.log_format = flags.log_format;
  flags.service.worker.log_level = flags.log_level;
  flags.service.worker.max_model_bytes = flags.service.max_model_bytes;
  const int max_workers =
      flags.service.max_workers > 0 ? flags.service.max_workers : flags.service.max_jobs + 2;
  flags.service.worker.cache_bytes = flags.service.cache_bytes / static_cast<uint64_t>(max_workers);

  rdmesh::server::RdmeshService service(flags.service);
  if (rdmesh::Status started = service.StartWorkers(); !started.ok()) {
    LogLine(spdlog::level::critical, "-", started.message());
    return 1;
  }
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(flags.listen, credentials, &port);
  builder.RegisterService(&service);
  builder.SetMaxReceiveMessageSize(32 << 20);  // inline models; uploads come in ~1 MiB chunks
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) {
    LogLine(spdlog::level::critical, "-", "cannot listen on " + flags.listen);
    return 1;
  }
  grpc::HealthCheckServiceInterface* health = server->GetHealthCheckService();
  health->SetServingStatus(true);
  health->SetServingStatus("rdmesh.v1.Rdmesh", true);
  const std::string host = flags.listen.substr(0, flags.listen.rfind(':'));
  LogLine(
      spdlog::level::info, "-",
      fmt::format("rdmeshd {} listening on {}:{} ({}, {}) threads/job {} max-jobs {} "
                  "max-queue {} workers {} data-root {} cache-dir {}",
                  RDMESH_VERSION, host, port, flags.tls_cert.empty() ? "plain" : "tls",
                  flags.service.token.empty() ? "no token" : "token", flags.service.threads,
                  flags.service.max_jobs, flags.service.max_queue, max_workers,
                  flags.service.data_root.empty() ? "off" : flags.service.data_root,
                  flags.service.worker.store_dir.empty() ? "off" : flags.service.worker.store_dir));

  std::mutex mutex;
  std::condition_variable stop_requested;
  int stop_signal = 0;
  std::thread signal_thread([&] {
    int received = 0;
    sigwait(&signals, &received);
    {
      std::lock_guard<std::mutex> lock(mutex);
      stop_signal = received;
    }
    stop_requested.notify_all();
    sigwait(&signals, &received);  // a second signal: stop at once
    LogLine(spdlog::level::warn, "-", "second signal: exiting without draining");
    std::_Exit(130);
  });
  signal_thread.detach();

  {
    std::unique_lock<std::mutex> lock(mutex);
    stop_requested.wait(lock, [&] { return stop_signal != 0; });
  }
  LogLine(
      spdlog::level::info, "-",
      fmt::format("signal {}: NOT_SERVING, draining {} running and {} queued jobs for up to "
                  "{} s",
                  stop_signal, service.active_jobs(), service.queued_jobs(), flags.grace_seconds));
  // Health turns NOT_SERVING and new jobs are refused (UNAVAILABLE) while the server still
  // answers calls; running and queued jobs get the grace period to finish, then whatever is left
  // is cancelled by Shutdown's deadline (which stops the engine within a second).
  health->SetServingStatus(false);
  service.BeginShutdown();
  const auto grace_end =
      std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::milliseconds>(
                                             std::chrono::duration<double>(flags.grace_seconds));
  while (service.busy_jobs() > 0 && std::chrono::steady_clock::now() < grace_end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (service.busy_jobs() > 0) {
    LogLine(spdlog::level::warn, "-",
            fmt::format("grace period over: cancelling {} jobs", service.busy_jobs()));
  }
  // Shutdown cancels what is left; the engine then stops within a second. Should it not, exit
  // anyway after a few seconds rather than hang (with a non-zero code: jobs were abandoned).
  std::atomic<bool> stopped{false};
  std::thread watchdog([&stopped] {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (!stopped && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (!stopped) {
      LogLine(spdlog::level::err, "-", "jobs did not stop 5 s after cancellation; exiting");
      std::_Exit(3);
    }
  });
  server->Shutdown(std::chrono::system_clock::now() + std::chrono::milliseconds(200));
  server->Wait();
  stopped = true;
  watchdog.join();
  service.StopWorkers();
  if (!temporary_spool.empty()) {
    std::error_code ignored;
    std::filesystem::remove_all(temporary_spool, ignored);
  }
  LogLine(spdlog::level::info, "-", "stopped");
  return 0;
}
