// rdmesh: the command line front end of the engine.
//   rdmesh mesh MODEL -o OUT [options] [--json] [--quiet]
//   rdmesh info MODEL [--json]
//   rdmesh batch INPUT... -o OUTDIR [options] (batch.h)

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "batch.h"
#include "exit_codes.h"
#include "isolation.h"
#include "mesh_flags.h"
#include "progress.h"
#include "rdmesh/engine.h"
#include "rdmesh/format_names.h"
#include "rdmesh/model_store.h"
#include "report.h"
#ifdef RDMESH_WITH_REMOTE
#include "remote_client.h"
#endif
#include "watchdog.h"

namespace rdmesh::cli {

namespace {

// Seconds past --timeout after which the watchdog ends a run that did not stop by itself.
constexpr double kWatchdogGrace = 2.0;

// The context of the current run, for the SIGINT handler (Cancel() is one atomic store).
Context* g_interrupt_context = nullptr;

void OnInterrupt(int) {
  if (g_interrupt_context != nullptr) g_interrupt_context->Cancel();
}

// CPU seconds (user + system, all threads) this process has used so far.
double ProcessCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct CommonFlags {
  std::string model;
  bool json = false;
  bool quiet = false;
  std::string cache_dir;                   ///< the persistent model store; "" = none
  uint64_t cache_dir_bytes = 10ull << 30;  ///< its size limit
};

// Prints the error on stderr and, with --json, as the last stdout line; returns `code`.
int Fail(const CommonFlags& flags, int code, const Status& status) {
  std::cerr << "rdmesh: error: " << status.message() << "\n";
  if (flags.json) {
    nlohmann::ordered_json error = {
        {"error", {{"code", StatusCodeName(status.code())}, {"message", status.message()}}},
        {"exit_code", code}};
    // Through C stdio: while OCCT reads, std::cout is muted (model_readers.cpp), and the watchdog
    // may fail the run then.
    std::string line = error.dump() + "\n";
    std::fputs(line.c_str(), stdout);
    std::fflush(stdout);
  }
  return code;
}

// The exit code for a failed load or meshing run that was stopped (timeout, Ctrl-C).
Status StopMessage(const Status& status, double timeout_seconds, const std::string& what) {
  if (status.code() == StatusCode::kDeadlineExceeded) {
    char seconds[32];
    std::snprintf(seconds, sizeof(seconds), "%g", timeout_seconds);
    return Status(status.code(),
                  std::string("timed out after ") + seconds + " s (--timeout) while " + what);
  }
  return Status(status.code(), "interrupted while " + what);
}

bool IsStop(const Status& status) {
  return status.code() == StatusCode::kCancelled || status.code() == StatusCode::kDeadlineExceeded;
}

// Loads the model, through the store when there is a --cache-dir; fills the load fields of `run`.
Result<std::shared_ptr<const Model>> Load(const CommonFlags& flags, Context* context,
                                          RunInfo* run) {
  auto start = std::chrono::steady_clock::now();
  Result<std::shared_ptr<const Model>> model = Status(StatusCode::kInternal, "");
  if (flags.cache_dir.empty()) {
    model = LoadModel(flags.model, context);
  } else {
    StoreOutcome outcome;
    model =
        ModelStore(flags.cache_dir, flags.cache_dir_bytes).LoadFile(flags.model, context, &outcome);
    run->store_used = true;
    run->from_store = outcome.from_store;
    run->store_problem = outcome.problem;
    if (!outcome.problem.empty() && !flags.quiet)
      std::cerr << "rdmesh: warning: " << outcome.problem << "\n";
  }
  run->load_seconds = SecondsSince(start);
  if (model.ok()) {
    const ModelInfo& info = GetModelInfo(**model);
    run->load_stages = info.load_stages;
    run->reader = info.reader;
    run->reader_note = info.reader_note;
  }
  return model;
}

int RunInfoCommand(const CommonFlags& flags) {
  RunInfo run;
  Context context;
  g_interrupt_context = &context;
  auto model = Load(flags, &context, &run);
  if (!model.ok()) {
    if (IsStop(model.status()))
      return Fail(flags, kExitStopped,
                  StopMessage(model.status(), 0, "loading '" + flags.model + "'"));
    return Fail(flags, kExitBadModel, model.status());
  }
  ModelInfo info = GetModelInfo(**model);
  if (flags.json) {
    nlohmann::ordered_json json = ModelInfoJson(info);
    json["load_seconds"] = run.load_seconds;
    json["load_stages"] = LoadStagesJson(run);
    AddStoreJson(run, &json);
    std::cout << json.dump() << std::endl;
  } else if (!flags.quiet) {
    PrintModelInfo(info, std::cout);
  }
  return kExitOk;
}

int RunMeshCommand(const CommonFlags& flags, const MeshFlags& mesh_flags, const std::string& output,
                   bool strict, const std::string& remote) {
  Result<MeshOptions> options = BuildMeshOptions(mesh_flags);
  if (!options.ok()) return Fail(flags, kExitUsage, options.status());
  Result<std::vector<double>> levels = BuildLevels(mesh_flags, *options);
  if (!levels.ok()) return Fail(flags, kExitUsage, levels.status());
  std::string extension = std::filesystem::path(output).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  bool known = false;
  std::string formats;
  for (const std::string& format : SupportedOutputFormats()) {
    known = known || format == extension;
    formats += " " + format;
  }
  if (!known)
    return Fail(
        flags, kExitUsage,
        Status(StatusCode::kInvalidArgument,
               "cannot write '" + output + "': unknown output format (use one of" + formats + ")"));
  if (mesh_flags.write.compress && extension != ".glb")
    return Fail(flags, kExitUsage,
                Status(StatusCode::kInvalidArgument,
                       "--compress writes .glb only (the output is '" + output + "')"));

  Context context;
  g_interrupt_context = &context;
  context.SetTimeout(options->timeout_seconds);
  // Only these writers and the store carry names and colours: without them a plain STEP file
  // loads without OCCT's document framework (rdmesh_occt_xcaf.so stays unloaded).
  context.set_keep_document(extension == ".glb" || extension == ".obj" || !flags.cache_dir.empty());
  // The engine stops itself at the deadline; should a stage miss it, end the process anyway.
  Watchdog watchdog(options->timeout_seconds > 0 ? options->timeout_seconds + kWatchdogGrace : 0,
                    [&flags, &options] {
                      const char* doing =
                          CurrentPhase() == Phase::kLoading ? "loading '" : "meshing '";
                      Fail(flags, kExitStopped,
                           StopMessage(Status(StatusCode::kDeadlineExceeded, ""),
                                       options->timeout_seconds, doing + flags.model + "'"));
                      std::_Exit(kExitStopped);
                    });
  RunInfo run;
  run.model_path = flags.model;
  run.output_path = output;
  run.off_surface = options->off_surface;
  auto model = Load(flags, &context, &run);
  if (!model.ok()) {
    if (IsStop(model.status()))
      return Fail(
          flags, kExitStopped,
          StopMessage(model.status(), options->timeout_seconds, "loading '" + flags.model + "'"));
    return Fail(flags, kExitBadModel, model.status());
  }
  ModelInfo info = GetModelInfo(**model);
  EnterPhase(Phase::kMeshing);
  for (int id : options->face_ids)
    if (id > info.faces)
      return Fail(flags, kExitUsage,
                  Status(StatusCode::kInvalidArgument,
                         "--faces: face " + std::to_string(id) + " does not exist ('" +
                             flags.model + "' has faces 1-" + std::to_string(info.faces) + ")"));

  TerminalProgress progress(!flags.quiet);
  context.set_progress_callback([&progress](const Progress& p) { progress.Update(p); });
  // One result, or one per level of detail (coarsest first).
  std::vector<MeshResult> results;
  Status meshed = Status::Ok();
  const double cpu_start = ProcessCpuSeconds();
  if (levels->empty()) {
#ifdef RDMESH_WITH_REMOTE
    Result<MeshResult> result = remote.empty()
                                    ? MeshModel(**model, *options, &context)
                                    : MeshRemote(remote, flags.model, *options, &context);
#else
    Result<MeshResult> result = MeshModel(**model, *options, &context);
#endif
    if (result.ok())
      results.push_back(std::move(*result));
    else
      meshed = result.status();
  } else {
    LevelCallbacks callbacks;
    callbacks.done = [&results](int, MeshResult result) {
      results.push_back(std::move(result));
      return Status::Ok();
    };
#ifdef RDMESH_WITH_REMOTE
    if (!remote.empty()) {
      Result<std::vector<MeshResult>> remote_levels =
          MeshRemoteLevels(remote, flags.model, *options, *levels, &context);
      if (remote_levels.ok())
        results = std::move(*remote_levels);
      else
        meshed = remote_levels.status();
    } else {
      meshed = MeshModelLevels(**model, *options, *levels, &context, callbacks);
    }
#else
    meshed = MeshModelLevels(**model, *options, *levels, &context, callbacks);
#endif
  }
  run.mesh_cpu_seconds = ProcessCpuSeconds() - cpu_start;
  progress.Finish();
  watchdog.Disarm();  // writing is not bounded by --timeout
  if (!meshed.ok()) {
    if (IsStop(meshed))
      return Fail(flags, kExitStopped,
                  StopMessage(meshed, options->timeout_seconds, "meshing '" + flags.model + "'"));
    if (meshed.code() == StatusCode::kInvalidArgument) return Fail(flags, kExitUsage, meshed);
    return Fail(flags, kExitMeshFailed, meshed);
  }

  EnterPhase(Phase::kWriting);
  nlohmann::ordered_json level_reports = nlohmann::ordered_json::array();
  for (size_t i = 0; i < results.size(); ++i) {
    RunInfo level_run = run;
    if (!levels->empty()) level_run.output_path = LevelPath(output, static_cast<int>(i));
    auto write_start = std::chrono::steady_clock::now();
    Status written = WriteMesh(**model, results[i], level_run.output_path, mesh_flags.write);
    level_run.write_seconds = SecondsSince(write_start);
    if (!written.ok()) return Fail(flags, kExitWriteFailed, written);
    std::ostream& out = flags.json ? std::cerr : std::cout;
    if (!flags.quiet && !levels->empty())
      out << "level      " << i << " of " << levels->size() << ", max deviation rel "
          << (*levels)[i] << "\n";
    if (!flags.quiet) PrintMeshReport(info, results[i], level_run, out);
    nlohmann::ordered_json report = MeshReportJson(results[i], level_run);
    if (levels->empty()) {
      if (flags.json) std::cout << report.dump() << std::endl;
    } else {
      report["level"] = i;
      report["max_deviation_rel"] = (*levels)[i];
      level_reports.push_back(std::move(report));
    }
  }
  if (flags.json && !levels->empty()) {
    nlohmann::ordered_json json = {{"model", flags.model},
                                   {"load_seconds", run.load_seconds},
                                   {"load_stages", LoadStagesJson(run)},
                                   {"mesh_cpu_seconds", run.mesh_cpu_seconds},
                                   {"levels", std::move(level_reports)}};
    AddStoreJson(run, &json);
    std::cout << json.dump() << std::endl;
  }

  for (const MeshResult& result : results) {
    const MeshSummary& summary = result.summary;
    if (summary.faces_failed > 0 && (strict || summary.faces_ok == 0)) {
      std::cerr << "rdmesh: error: " << summary.faces_failed << " face"
                << (summary.faces_failed == 1 ? "" : "s") << " of '" << flags.model
                << "' failed to mesh" << (strict ? " (--strict)" : "") << "\n";
      return kExitMeshFailed;
    }
  }
  return kExitOk;
}

// The exit code and message for a run whose process died by a signal (see isolation.h).
int ReportDeath(const CommonFlags& flags, const std::string& output, const ChildDeath& death) {
  bool writing = death.phase == Phase::kWriting;
  const std::string& file = writing ? output : flags.model;
  if (death.interrupted) {
    const char* doing = death.phase == Phase::kLoading ? "loading"
                        : writing                      ? "writing"
                                                       : "meshing";
    return Fail(flags, kExitStopped,
                Status(StatusCode::kCancelled, std::string("interrupted while ") + doing + " '" +
                                                   file + "' (" + SignalName(death.signal) + ")"));
  }
  std::string how =
      (death.signal == SIGKILL ? " was killed (" : " crashed (") + SignalName(death.signal) + ")";
  switch (death.phase) {
    case Phase::kLoading:
      return Fail(flags, kExitBadModel,
                  Status(StatusCode::kParseError,
                         "cannot read '" + file + "': " + ReaderName(FormatFromExtension(file)) +
                             how + " on this model"));
    case Phase::kMeshing:
      return Fail(flags, kExitMeshFailed,
                  Status(StatusCode::kInternal, "the mesher" + how + " on '" + file + "'"));
    case Phase::kWriting:
      break;
  }
  return Fail(flags, kExitWriteFailed,
              Status(StatusCode::kInternal, "cannot write '" + file + "': the writer" + how));
}

void AddCommonFlags(CLI::App* command, CommonFlags* flags) {
  command->add_option("model", flags->model, "Model file: .step/.stp, .iges/.igs or .brep")
      ->required();
  command->add_flag("--json", flags->json,
                    "Print one JSON object on stdout as the last line (the human summary goes "
                    "to stderr)");
  command->add_flag("-q,--quiet", flags->quiet, "Print nothing but errors (and --json)");
  command
      ->add_option("--cache-dir", flags->cache_dir,
                   "Keep parsed models in this directory (OCCT binary, keyed by the file's "
                   "sha256) and read them from there instead of parsing again; off by default")
      ->envname("RDMESH_CACHE_DIR");
  command
      ->add_option("--cache-dir-bytes", flags->cache_dir_bytes,
                   "Size limit of --cache-dir; the least recently used models go first "
                   "(suffixes like 2GiB work)")
      ->envname("RDMESH_CACHE_DIR_BYTES")
      ->transform(CLI::AsSizeValue(false))
      ->capture_default_str();
}

#ifdef RDMESH_REMOTE_EXEC
// `--remote` runs in rdmesh-remote, the same command with the gRPC client, from this binary's
// folder: this one links no gRPC, so that a local run starts fast. Returns only when it cannot
// start it (kExitUsage, with the reason on stderr).
int ExecRemote(char** argv) {
  std::error_code error;
  std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  const std::string remote = (self.parent_path() / "rdmesh-remote").string();
  if (!error) ::execv(remote.c_str(), argv);
  std::cerr << "rdmesh: --remote needs " << remote << " (" << std::strerror(errno) << ")\n";
  return kExitUsage;
}
#endif

}  // namespace

int Main(int argc, char** argv) {
#ifdef RDMESH_REMOTE_EXEC
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--remote" || arg.rfind("--remote=", 0) == 0) return ExecRemote(argv);
  }
#endif
  CLI::App app{
      "rdmesh: watertight surface meshes of CAD models (STEP, IGES, BREP).\n"
      "Exit codes: 0 ok, 1 meshing failed (or --strict and a face failed), 2 bad "
      "usage, 3 cannot read the model, 4 timeout or interrupted, 5 cannot write the "
      "output."};
  app.footer(
      "Each run happens in a child process, so that a crash inside OCCT is reported with exit "
      "code 3 (reading), 1 (meshing) or 5 (writing); RDMESH_NO_FORK=1 runs in one process "
      "(for debuggers).");
  app.require_subcommand(1);

  CommonFlags mesh_common;
  MeshFlags mesh_flags;
  std::string output;
  bool strict = false;
  std::string remote;
  CLI::App* mesh = app.add_subcommand("mesh", "Mesh a model and write the mesh");
  AddCommonFlags(mesh, &mesh_common);
  std::string formats;
  for (const std::string& format : SupportedOutputFormats()) formats += " " + format;
  mesh->add_option("-o,--output", output, "Output file; the extension picks the format:" + formats)
      ->required();
  mesh->add_flag("--strict", strict, "Exit with code 1 when any face fails to mesh");
#if defined(RDMESH_WITH_REMOTE) || defined(RDMESH_REMOTE_EXEC)
  mesh->add_option("--remote", remote,
                   "Mesh on the rdmeshd server at HOST:PORT (same options, same output; see "
                   "docs/SERVICE.md)");
#endif
  AddMeshFlags(mesh, &mesh_flags);

  CommonFlags info_common;
  CLI::App* info = app.add_subcommand("info", "Print what a model holds");
  AddCommonFlags(info, &info_common);

  BatchFlags batch_flags;
  CLI::App* batch = AddBatchCommand(&app, &batch_flags);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }
  // The batch supervises a process per file itself.
  if (batch->parsed()) return RunBatch(batch_flags, &Main);

  const CommonFlags& common = mesh->parsed() ? mesh_common : info_common;
  return RunIsolated(
      [&] {
        std::signal(SIGINT, OnInterrupt);
        if (mesh->parsed()) return RunMeshCommand(mesh_common, mesh_flags, output, strict, remote);
        return RunInfoCommand(info_common);
      },
      [&](const ChildDeath& death) { return ReportDeath(common, output, death); });
}

}  // namespace rdmesh::cli

// Sanitizer builds exit normally: LeakSanitizer checks at exit.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define RDMESH_EXIT_NORMALLY 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define RDMESH_EXIT_NORMALLY 1
#endif
#endif

int main(int argc, char** argv) {
  const int code = rdmesh::cli::Main(argc, argv);
  // Every file is written and closed by now; what exit() would add is the static destructors and
  // finalisers of some 70 libraries (4 M instructions over the two processes of a run).
  std::cout.flush();
  std::fflush(nullptr);
#ifndef RDMESH_EXIT_NORMALLY
  std::_Exit(code);
#endif
  return code;
}
