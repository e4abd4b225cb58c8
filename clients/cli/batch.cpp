#include "batch.h"

#include <fcntl.h>
#include <sched.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "batch_children.h"
#include "batch_inputs.h"
#include "batch_manifest.h"
#include "exit_codes.h"
#include "isolation.h"
#include "rdmesh/engine.h"
#include "rdmesh/sha256.h"

extern char** environ;

namespace rdmesh::cli {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

namespace {

// A child that has not stopped by itself this long after its --timeout is killed (SIGKILL).
constexpr double kKillGrace = 0.5;
// Options that do not change the mesh: a file done with other values is not done again.
const std::set<std::string> kNotCompared = {"--threads", "--timeout", "--cache-dir",
                                            "--cache-dir-bytes"};
// How many files the summary names as the slowest and the worst.
constexpr size_t kSummaryFiles = 5;

const char* const kStatuses[] = {"ok", "failed", "crashed", "timed_out", "unreadable"};

int CpuCount() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1L, sysconf(_SC_NPROCESSORS_ONLN));
}

uint64_t PhysicalMemory() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<uint64_t>(pages) * static_cast<uint64_t>(page) : 0;
}

std::string Bytes(uint64_t bytes) {
  char text[32];
  if (bytes >= (uint64_t{1} << 30))
    std::snprintf(text, sizeof(text), "%.1f GiB", static_cast<double>(bytes) / (1 << 30));
  else
    std::snprintf(text, sizeof(text), "%.0f MiB", static_cast<double>(bytes) / (1 << 20));
  return text;
}

std::string Duration(double seconds) {
  char text[32];
  const long s = std::lround(seconds);
  if (s >= 3600)
    std::snprintf(text, sizeof(text), "%ldh%02ldm", s / 3600, (s / 60) % 60);
  else if (s >= 60)
    std::snprintf(text, sizeof(text), "%ldm%02lds", s / 60, s % 60);
  else
    std::snprintf(text, sizeof(text), "%lds", s);
  return text;
}

std::string Number(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

// The last non-empty line of `text`, trimmed to `limit` characters.
std::string LastLine(const std::string& text, size_t limit = 300) {
  size_t end = text.find_last_not_of(" \t\r\n");
  if (end == std::string::npos) return "";
  size_t start = text.rfind('\n', end);
  start = start == std::string::npos ? 0 : start + 1;
  std::string line = text.substr(start, end - start + 1);
  if (line.size() > limit) line = line.substr(0, limit) + "...";
  return line;
}

// The child's report or error: its last stdout line as a JSON object; null when there is none.
Json ChildJson(const std::string& out) {
  Json json = Json::parse(LastLine(out, std::string::npos), nullptr, false);
  return json.is_object() ? json : Json();
}

std::string ErrorMessage(const Json& json) {
  if (json.contains("error") && json["error"].is_object() && json["error"].contains("message") &&
      json["error"]["message"].is_string())
    return json["error"]["message"];
  return "";
}

int64_t IntField(const Json& json, const char* name) {
  return json.contains(name) && json[name].is_number() ? json[name].get<int64_t>() : 0;
}

// The faces of a report that failed or were meshed over the criteria, as "face 5 (bspline):
// reason", the first one named.
std::string FaceReasons(const Json& report, const char* status, int64_t count,
                        const std::string& what) {
  std::string first;
  if (report.contains("faces") && report["faces"].is_array())
    for (const Json& face : report["faces"])
      if (face.value("status", "") == status &&
          (std::string(status) != "ok" || !face.value("reason", std::string()).empty())) {
        first = "face " + std::to_string(face.value("id", 0)) + " (" +
                face.value("surface_type", std::string("?")) +
                "): " + face.value("reason", std::string("no reason given"));
        break;
      }
  return std::to_string(count) + " of " +
         std::to_string(IntField(report, "faces_ok") + IntField(report, "faces_failed") +
                        IntField(report, "faces_skipped")) +
         " faces " + what + (first.empty() ? "" : "; " + first);
}

// Whether the child's stderr or message says it ran out of memory.
bool OutOfMemory(const std::string& text) {
  for (const char* sign : {"Out of memory", "out of memory", "bad_alloc", "Cannot allocate memory",
                           "failed to map segment", "cannot allocate memory", "OutOfMemory"})
    if (text.find(sign) != std::string::npos) return true;
  return false;
}

// OUTDIR, absolute, without a trailing separator.
fs::path OutputFolder(const std::string& output_dir) {
  fs::path path = fs::absolute(output_dir).lexically_normal();
  return path.has_filename() || path == path.root_path() ? path : path.parent_path();
}

// An exclusive lock on OUTDIR for this run: two runs would write one manifest.
class OutputLock {
 public:
  Status Take(const std::string& output_dir) {
    const std::string path = (fs::path(output_dir) / ".rdmesh-batch.lock").string();
    fd_ = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0)
      return Status(StatusCode::kIoError, "cannot write '" + path + "': " + strerror(errno));
    if (flock(fd_, LOCK_EX | LOCK_NB) != 0)
      return Status(StatusCode::kInvalidArgument,
                    "another rdmesh batch is writing '" + output_dir + "'");
    return Status::Ok();
  }
  ~OutputLock() {
    if (fd_ >= 0) close(fd_);
  }

 private:
  int fd_ = -1;
};

// The one-line progress display and the lines about files that were not ok.
class Display {
 public:
  Display(bool quiet, size_t total)
      : quiet_(quiet), terminal_(!quiet && isatty(STDERR_FILENO) == 1), total_(total) {}

  void Problem(const std::string& line) {
    if (quiet_) return;
    Erase();
    std::fprintf(stderr, "rdmesh batch: %s\n", line.c_str());
    std::fflush(stderr);
  }

  void Message(const std::string& line) { Problem(line); }

  // done: files finished or skipped; processed: finished by a child or the hash (not skipped).
  void Update(size_t done, size_t processed, size_t failures, double seconds, bool force) {
    if (!terminal_) return;
    auto now = std::chrono::steady_clock::now();
    if (!force && shown_ && now - last_ < std::chrono::milliseconds(250)) return;
    last_ = now;
    shown_ = true;
    std::string line = "rdmesh batch: " + std::to_string(done) + "/" + std::to_string(total_) +
                       " done, " + std::to_string(failures) + " not ok";
    if (processed > 0 && seconds > 0) {
      const double rate = static_cast<double>(processed) / seconds;
      line += ", " + Number("%.1f", 60.0 * rate) + " files/min, ETA " +
              Duration(static_cast<double>(total_ - done) / rate);
    }
    std::fprintf(stderr, "\r\033[K%s", line.c_str());
    std::fflush(stderr);
  }

  void Erase() {
    if (!shown_) return;
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
    shown_ = false;
  }

 private:
  bool quiet_;
  bool terminal_;
  size_t total_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point last_;
};

// One run of the batch.
class Batch {
 public:
  Batch(const BatchFlags& flags, std::vector<BatchInput> inputs, std::vector<double> levels,
        ChildPool::Entry main)
      : main_(main),
        flags_(flags),
        inputs_(std::move(inputs)),
        levels_(std::move(levels)),
        out_(OutputFolder(flags.output_dir)),
        extension_("." + flags.format),
        manifest_((out_ / "manifest.jsonl").string()),
        display_(flags.quiet, inputs_.size()) {}

  int Run();

 private:
  struct Running {
    size_t input;
    std::string sha256;
    int64_t bytes;
  };

  Status Prepare();
  void SweepPartials();
  std::vector<std::string> ChildArgs(const BatchInput& input) const;
  std::vector<std::string> ChildEnv() const;
  std::string Partial(const BatchInput& input) const;
  // The outputs of a run of `input` written at `base` (one, or one per level).
  std::vector<fs::path> Outputs(const fs::path& base) const;
  // Starts the next input, or records it (unreadable, or skipped when already done).
  void StartOrSkip(size_t index);
  void Finish(const ChildResult& result);
  void Record(size_t index, Json entry);
  Json NewEntry(size_t index, const std::string& sha256, int64_t bytes) const;
  void Summarize(double seconds, bool interrupted);
  void RemoveEmptyFolders();

  ChildPool::Entry main_;  // this program's main, run by each child; null: exec mesher_
  const BatchFlags& flags_;
  std::vector<BatchInput> inputs_;
  std::vector<double> levels_;
  fs::path out_;
  std::string extension_;
  Manifest manifest_;
  Display display_;
  OutputLock lock_;
  ChildPool pool_;
  Json options_;  ///< the mesh options given, but those that do not change the mesh
  std::vector<std::string> base_args_;
  std::string mesher_;
  double timeout_ = 0.0;
  int jobs_ = 1;
  uint64_t memory_limit_ = 0;
  std::map<int, Running> running_;
  size_t skipped_ = 0;
  size_t processed_ = 0;
  std::map<std::string, size_t> counts_;
  std::vector<size_t> recorded_;  ///< inputs recorded by this run, in order
  std::vector<Json> entries_;     ///< per input: its entry of this run (or null)
  Status manifest_status_ = Status::Ok();
};

Status Batch::Prepare() {
  jobs_ = flags_.jobs > 0 ? flags_.jobs : CpuCount();
  timeout_ = flags_.mesh.options.timeout_seconds;
  if (flags_.memory_limit >= 0) {
    memory_limit_ = static_cast<uint64_t>(flags_.memory_limit);
  } else {
    memory_limit_ = PhysicalMemory() / static_cast<uint64_t>(jobs_);
  }
  // RDMESH_BATCH_MESHER: another program in the mesher's place (the tests' stand-ins).
  const char* mesher = std::getenv("RDMESH_BATCH_MESHER");
  std::error_code error;
  if (mesher != nullptr && mesher[0] != '\0') {
    mesher_ = mesher;
    main_ = nullptr;
  } else {
    mesher_ = fs::read_symlink("/proc/self/exe", error).string();
  }
  if (mesher_.empty())
    return Status(StatusCode::kInternal, "cannot find the rdmesh binary: " + error.message());

  bool threads_given = false;
  for (const CLI::Option* option : flags_.passed_on) {
    if (option->count() == 0) continue;
    const std::string name = "--" + option->get_lnames().front();
    threads_given = threads_given || name == "--threads";
    for (const std::string& value : option->results()) base_args_.push_back(name + "=" + value);
    if (kNotCompared.count(name) == 0) options_[name] = option->results().back();
  }
  // One process per core by default: a file's own threads would only compete with the others.
  if (!threads_given)
    base_args_.push_back("--threads=" + std::to_string(std::max(1, CpuCount() / jobs_)));
  if (options_.is_null()) options_ = Json::object();

  fs::create_directories(out_, error);
  if (error)
    return Status(StatusCode::kIoError,
                  "cannot create '" + out_.string() + "': " + error.message());
  // Before anything in OUTDIR is read or removed.
  Status locked = lock_.Take(out_.string());
  if (!locked.ok()) return locked;
  int torn = 0;
  Status loaded = manifest_.Load(&torn);
  if (!loaded.ok()) return loaded;
  if (torn > 0)
    display_.Message("skipped " + std::to_string(torn) +
                     " unreadable line(s) of the manifest (a run killed while writing it)");
  // An earlier input whose output a new input takes is no longer in the tree.
  std::map<std::string, std::string> owners;
  for (const BatchInput& input : inputs_)
    owners[Outputs(input.output).back().generic_string()] = input.path;
  std::vector<std::string> stale;
  for (const auto& [path, entry] : manifest_.entries()) {
    if (!entry.contains("output") || !entry["output"].is_string()) continue;
    auto owner = owners.find(entry["output"].get<std::string>());
    if (owner != owners.end() && owner->second != path) stale.push_back(path);
  }
  for (const std::string& path : stale) manifest_.Forget(path);
  SweepPartials();
  entries_.assign(inputs_.size(), Json());
  return Status::Ok();
}

// A killed run leaves its children's partial files (hidden, ".NAME.partial.EXT"): remove them.
void Batch::SweepPartials() {
  // The name Partial() gives, with the level a --lod run adds; compiled on first use, not at
  // every start-up of the CLI.
  static const std::regex kPartialName(R"(\..+\.partial(\.lod\d+)?\.[A-Za-z0-9]+)");
  std::error_code error;
  std::vector<fs::path> partials;
  for (fs::recursive_directory_iterator it(out_, error), end; !error && it != end;
       it.increment(error)) {
    if (std::regex_match(it->path().filename().string(), kPartialName) &&
        it->is_regular_file(error))
      partials.push_back(it->path());
  }
  for (const fs::path& path : partials) fs::remove(path, error);
}

std::string Batch::Partial(const BatchInput& input) const {
  const fs::path final_path = out_ / input.output;
  return (final_path.parent_path() /
          ("." + final_path.filename().string() + ".partial" + extension_))
      .string();
}

std::vector<fs::path> Batch::Outputs(const fs::path& base) const {
  if (levels_.empty()) return {base};
  std::vector<fs::path> outputs;
  for (size_t i = 0; i < levels_.size(); ++i)
    outputs.push_back(LevelPath(base.string(), static_cast<int>(i)));
  return outputs;
}

std::vector<std::string> Batch::ChildArgs(const BatchInput& input) const {
  std::vector<std::string> args = {mesher_,        "mesh",   input.path, "-o",
                                   Partial(input), "--json", "--quiet"};
  args.insert(args.end(), base_args_.begin(), base_args_.end());
  return args;
}

std::vector<std::string> Batch::ChildEnv() const {
  std::vector<std::string> env;
  for (char** var = environ; *var != nullptr; ++var)
    if (std::strncmp(*var, "RDMESH_NO_FORK=", 15) != 0) env.emplace_back(*var);
  // The batch is the child's supervisor: no second process of its own.
  env.emplace_back("RDMESH_NO_FORK=1");
  return env;
}

Json Batch::NewEntry(size_t index, const std::string& sha256, int64_t bytes) const {
  const BatchInput& input = inputs_[index];
  return Json{{"path", input.path},
              {"sha256", sha256.empty() ? Json() : Json(sha256)},
              {"bytes", bytes >= 0 ? Json(bytes) : Json()},
              {"status", ""},
              {"reason", ""},
              {"faces", Json()},
              {"faces_failed", Json()},
              {"triangles", Json()},
              {"requested_deviation", Json()},
              {"estimated_deviation", Json()},
              {"seconds", 0.0},
              {"output", Json()},
              {"reader", Json()},
              {"exit_code", Json()},
              {"signal", Json()},
              {"options", options_}};
}

void Batch::Record(size_t index, Json entry) {
  const std::string status = entry["status"];
  ++counts_[status];
  if (status != "ok")
    display_.Problem(status + ": " + inputs_[index].path + ": " +
                     entry["reason"].get<std::string>());
  Status appended = manifest_.Append(entry);
  if (!appended.ok() && manifest_status_.ok()) manifest_status_ = appended;
  entries_[index] = std::move(entry);
  recorded_.push_back(index);
}

void Batch::StartOrSkip(size_t index) {
  const BatchInput& input = inputs_[index];
  std::error_code error;
  const fs::file_status type = fs::status(input.path, error);
  std::string problem;
  std::string bytes;
  if (!fs::exists(type)) {
    problem = "no such file";
  } else if (!fs::is_regular_file(type)) {
    problem = "not a regular file";
  } else {
    std::ifstream in(input.path, std::ios::binary);
    if (!in.is_open()) {
      problem = std::string("cannot open it: ") + strerror(errno);
    } else {
      std::ostringstream text;
      text << in.rdbuf();
      if (in.bad()) problem = std::string("cannot read it: ") + strerror(errno);
      bytes = text.str();
    }
  }
  if (!problem.empty()) {
    Json entry = NewEntry(index, "", -1);
    entry["status"] = "unreadable";
    entry["reason"] = problem;
    ++processed_;
    Record(index, std::move(entry));
    return;
  }
  const std::string sha256 = Sha256Hex(bytes);
  const int64_t size = static_cast<int64_t>(bytes.size());
  bytes.clear();
  bytes.shrink_to_fit();

  // Done before: ok, same bytes, same output, same options, and the output still there.
  if (const Json* old = manifest_.Find(input.path);
      old != nullptr && old->value("status", "") == "ok" &&
      old->value("sha256", Json()) == sha256 &&
      old->value("output", Json()) == Outputs(input.output).back().generic_string() &&
      old->value("options", Json()) == options_) {
    bool present = true;
    for (const fs::path& output : Outputs(out_ / input.output))
      present = present && fs::is_regular_file(output, error);
    if (present) {
      ++skipped_;
      ++counts_["ok"];
      entries_[index] = *old;
      return;
    }
  }

  fs::create_directories((out_ / input.output).parent_path(), error);
  const double limit = timeout_ > 0 ? timeout_ + kKillGrace : 0.0;
  Status started = pool_.Start(static_cast<int>(index), ChildArgs(input), ChildEnv(), limit,
                               memory_limit_, main_);
  if (!started.ok()) {
    Json entry = NewEntry(index, sha256, size);
    entry["status"] = "crashed";
    entry["reason"] = "cannot start a process for it: " + started.message();
    ++processed_;
    Record(index, std::move(entry));
    return;
  }
  running_[static_cast<int>(index)] = {index, sha256, size};
}

void Batch::Finish(const ChildResult& result) {
  auto it = running_.find(result.id);
  if (it == running_.end()) return;
  const Running run = it->second;
  running_.erase(it);
  const BatchInput& input = inputs_[run.input];
  const std::vector<fs::path> partials = Outputs(Partial(input));
  const std::vector<fs::path> finals = Outputs(out_ / input.output);
  std::error_code error;
  if (result.stopped) {  // interrupted: not done, the next run does it
    for (const fs::path& partial : partials) fs::remove(partial, error);
    return;
  }

  Json entry = NewEntry(run.input, run.sha256, run.bytes);
  entry["seconds"] = result.seconds;
  if (result.exit_code >= 0) entry["exit_code"] = result.exit_code;
  if (result.signal != 0) entry["signal"] = SignalName(result.signal);
  const Json json = ChildJson(result.out);
  // The finest level's report carries the counts; with --lod, every level is listed.
  Json report = json;
  if (json.contains("levels") && json["levels"].is_array() && !json["levels"].empty())
    report = json["levels"].back();
  const bool has_report = report.is_object() && report.contains("triangles");
  const std::string message = ErrorMessage(json);
  std::string status, reason;
  bool keep_output = false;
  if (result.exit_code < 0) {
    if (result.timed_out) {
      status = "timed_out";
      reason = "killed after " + Number("%g", timeout_ + kKillGrace) +
               " s: no result within --timeout " + Number("%g", timeout_) + " s";
    } else {
      status = "crashed";
      reason = "the process died by " + SignalName(result.signal);
      const std::string last = LastLine(result.err);
      if (!last.empty()) reason += ": " + last;
    }
  } else if (result.exit_code == kExitOk || (result.exit_code == kExitMeshFailed && has_report)) {
    if (!has_report) {
      status = "failed";
      reason = "the mesher printed no report";
    } else if (IntField(report, "faces_failed") > 0 || result.exit_code != kExitOk) {
      status = "failed";
      reason = FaceReasons(report, "failed", IntField(report, "faces_failed"), "failed");
      keep_output = true;
    } else {
      status = "ok";
      const int64_t over = IntField(report, "faces_over_criteria");
      if (over > 0) reason = FaceReasons(report, "ok", over, "meshed over the criteria");
      keep_output = true;
    }
  } else {
    switch (result.exit_code) {
      case kExitBadModel:
        status = "unreadable";
        break;
      case kExitStopped:
        status = "timed_out";
        break;
      case kExitMeshFailed:
      case kExitUsage:
      case kExitWriteFailed:
        status = "failed";
        break;
      default:
        status = "crashed";
    }
    reason = !message.empty() ? message : LastLine(result.err);
    if (reason.empty()) reason = "exited with code " + std::to_string(result.exit_code);
    if (status == "crashed" && !message.empty())
      reason = "exited with code " + std::to_string(result.exit_code) + ": " + reason;
  }
  // Out of memory says nothing of the file: whatever the exit, the process gave out.
  if (status != "ok" && (OutOfMemory(result.err) || OutOfMemory(message))) {
    status = "crashed";
    const std::string limit =
        memory_limit_ > 0 ? "the limit is --memory-limit " + Bytes(memory_limit_) : "";
    if (OutOfMemory(reason))
      reason += limit.empty() ? "" : " (" + limit + ")";
    else
      reason += limit.empty() ? " (out of memory)" : " (out of memory: " + limit + ")";
  }

  if (has_report) {
    entry["faces"] = IntField(report, "faces_ok") + IntField(report, "faces_failed") +
                     IntField(report, "faces_skipped");
    entry["faces_failed"] = IntField(report, "faces_failed");
    entry["triangles"] = report.value("triangles", Json());
    entry["requested_deviation"] = report.value("requested_deviation", Json());
    entry["estimated_deviation"] = report.value("estimated_deviation", Json());
  }
  if (json.contains("reader") && json["reader"].is_string() && json["reader"] != "")
    entry["reader"] = json["reader"];
  else if (report.contains("reader") && report["reader"].is_string() && report["reader"] != "")
    entry["reader"] = report["reader"];
  // The partial files become the outputs; without a mesh, an older output of this path goes.
  if (keep_output) {
    for (size_t i = 0; i < partials.size() && keep_output; ++i) {
      fs::rename(partials[i], finals[i], error);
      if (error) {
        status = "failed";
        reason = "cannot move the mesh to '" + finals[i].string() + "': " + error.message();
        keep_output = false;
      }
    }
  }
  if (!keep_output) {
    for (const fs::path& path : partials) fs::remove(path, error);
    for (const fs::path& path : finals) fs::remove(path, error);
  } else {
    entry["output"] = input.output;
    if (!levels_.empty()) {
      Json levels = Json::array();
      for (size_t i = 0; i < finals.size(); ++i) {
        const Json level =
            json.contains("levels") && json["levels"].is_array() && json["levels"].size() > i
                ? json["levels"][i]
                : Json::object();
        levels.push_back({{"output", finals[i].lexically_relative(out_).generic_string()},
                          {"max_deviation_rel", levels_[i]},
                          {"triangles", level.value("triangles", Json())},
                          {"estimated_deviation", level.value("estimated_deviation", Json())}});
      }
      entry["output"] = levels.back()["output"];
      entry["levels"] = std::move(levels);
    }
  }
  entry["status"] = status;
  entry["reason"] = reason;
  ++processed_;
  Record(run.input, std::move(entry));
}

// The folders made for files that left no mesh, once nothing runs (a child may be writing there).
void Batch::RemoveEmptyFolders() {
  std::error_code error;
  for (const BatchInput& input : inputs_)
    for (fs::path folder = (out_ / input.output).parent_path();
         folder != out_ && folder.native().size() > out_.native().size();
         folder = folder.parent_path())
      if (!fs::is_empty(folder, error) || error || !fs::remove(folder, error)) break;
}

int Batch::Run() {
  Status prepared = Prepare();
  if (!prepared.ok()) {
    std::cerr << "rdmesh: error: " << prepared.message() << "\n";
    return kExitUsage;
  }
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  auto failures = [this] {
    size_t count = 0;
    for (const auto& [status, n] : counts_)
      if (status != "ok") count += n;
    return count;
  };
  size_t next = 0;
  bool stopping = false;
  bool interrupted = false;
  while (true) {
    while (!stopping && next < inputs_.size() && pool_.running() < jobs_) StartOrSkip(next++);
    if (pool_.running() == 0 && (stopping || next >= inputs_.size())) break;
    display_.Update(skipped_ + processed_, processed_, failures(), elapsed(), false);
    if (pool_.running() == 0) continue;
    int signal = 0;
    for (const ChildResult& result : pool_.Wait(0.25, &signal)) Finish(result);
    if (signal == SIGINT && !stopping) {
      stopping = interrupted = true;
      display_.Message("interrupted: finishing the " + std::to_string(pool_.running()) +
                       " running file(s); Ctrl-C again stops them now");
    } else if (signal != 0) {
      stopping = interrupted = true;
      if (pool_.running() > 0)
        display_.Message("stopping the " + std::to_string(pool_.running()) +
                         " running file(s) now (" + SignalName(signal) + ")");
      for (const ChildResult& result : pool_.KillAll()) Finish(result);
    }
  }
  display_.Erase();
  interrupted = interrupted && skipped_ + processed_ < inputs_.size();
  RemoveEmptyFolders();

  std::vector<std::string> order;
  for (const BatchInput& input : inputs_) order.push_back(input.path);
  Status rewritten = manifest_.Rewrite(order);
  if (!rewritten.ok() && manifest_status_.ok()) manifest_status_ = rewritten;
  Summarize(elapsed(), interrupted);
  if (!manifest_status_.ok()) {
    std::cerr << "rdmesh: error: " << manifest_status_.message() << "\n";
    return kExitWriteFailed;
  }
  if (interrupted) return kExitStopped;
  return counts_["ok"] == inputs_.size() ? kExitOk : kExitMeshFailed;
}

void Batch::Summarize(double seconds, bool interrupted) {
  const double per_minute = seconds > 0 ? 60.0 * static_cast<double>(processed_) / seconds : 0.0;
  const size_t not_done = inputs_.size() - skipped_ - processed_;
  // The slowest files, and the worst: the most failed faces, then the estimate over the request.
  std::vector<size_t> slowest, worst;
  for (size_t index : recorded_) {
    slowest.push_back(index);
    const Json& entry = entries_[index];
    const double requested =
        entry["requested_deviation"].is_number() ? entry["requested_deviation"].get<double>() : 0.0;
    const double estimated =
        entry["estimated_deviation"].is_number() ? entry["estimated_deviation"].get<double>() : 0.0;
    if (entry["faces_failed"].is_number() &&
        (entry["faces_failed"].get<int64_t>() > 0 || (requested > 0 && estimated > requested)))
      worst.push_back(index);
  }
  auto seconds_of = [this](size_t i) { return entries_[i]["seconds"].get<double>(); };
  auto badness = [this](size_t i) {
    const Json& e = entries_[i];
    const double requested =
        e["requested_deviation"].is_number() ? e["requested_deviation"].get<double>() : 0.0;
    const double ratio = requested > 0 && e["estimated_deviation"].is_number()
                             ? e["estimated_deviation"].get<double>() / requested
                             : 0.0;
    return std::make_pair(e["faces_failed"].get<int64_t>(), ratio);
  };
  std::stable_sort(slowest.begin(), slowest.end(),
                   [&](size_t a, size_t b) { return seconds_of(a) > seconds_of(b); });
  std::stable_sort(worst.begin(), worst.end(),
                   [&](size_t a, size_t b) { return badness(a) > badness(b); });
  slowest.resize(std::min(slowest.size(), kSummaryFiles));
  worst.resize(std::min(worst.size(), kSummaryFiles));

  if (!flags_.quiet) {
    std::ostream& out = flags_.json ? std::cerr : std::cout;
    out << "rdmesh batch: " << inputs_.size() << " files, " << processed_ << " meshed in "
        << Duration(seconds) << " (" << Number("%.1f", per_minute) << " files/min, --jobs " << jobs_
        << "), " << skipped_ << " skipped (done before)";
    if (interrupted) out << ", " << not_done << " not done (interrupted)";
    out << "\n ";
    for (const char* status : kStatuses) out << " " << status << " " << counts_[status];
    out << "\n";
    if (!slowest.empty()) {
      out << "  slowest:\n";
      for (size_t i : slowest)
        out << "    " << Number("%7.2f s", seconds_of(i)) << "  " << inputs_[i].path << "\n";
    }
    if (!worst.empty()) {
      out << "  worst:\n";
      for (size_t i : worst) {
        const auto [failed, ratio] = badness(i);
        out << "    " << inputs_[i].path << ": ";
        if (failed > 0)
          out << failed << " of " << entries_[i]["faces"] << " faces failed";
        else
          out << "estimated deviation " << Number("%.2f", ratio) << "x the request";
        out << "\n";
      }
    }
    out << "  manifest: " << (out_ / "manifest.jsonl").string() << "\n";
  }
  if (flags_.json) {
    Json counts = Json::object();
    for (const char* status : kStatuses) counts[status] = counts_[status];
    Json names = Json::array(), bad = Json::array();
    for (size_t i : slowest) names.push_back(inputs_[i].path);
    for (size_t i : worst) bad.push_back(inputs_[i].path);
    Json summary = {{"files", inputs_.size()},
                    {"meshed", processed_},
                    {"skipped", skipped_},
                    {"not_done", not_done},
                    {"interrupted", interrupted},
                    {"counts", counts},
                    {"seconds", seconds},
                    {"files_per_minute", per_minute},
                    {"jobs", jobs_},
                    {"memory_limit", memory_limit_},
                    {"slowest", names},
                    {"worst", bad},
                    {"manifest", (out_ / "manifest.jsonl").string()}};
    std::cout << summary.dump() << std::endl;
  }
}

}  // namespace

CLI::App* AddBatchCommand(CLI::App* app, BatchFlags* flags) {
  CLI::App* batch = app->add_subcommand(
      "batch",
      "Mesh many models, each in a process of its own, into a mirrored tree with "
      "OUTDIR/manifest.jsonl; a second run skips what is done (docs/BATCH.md)");
  batch
      ->add_option("inputs", flags->inputs,
                   "Model files, folders (searched for .step .stp .iges .igs .brep) and @LIST "
                   "files (one path per line)")
      ->required();
  batch->add_option("-o,--output", flags->output_dir, "Output folder")->required();
  std::string formats;
  for (const std::string& format : SupportedOutputFormats()) formats += " " + format.substr(1);
  batch->add_option("--format", flags->format, "Output format:" + formats)->capture_default_str();
  batch->add_option("-j,--jobs", flags->jobs, "Files meshed at a time; 0 = all cores")
      ->capture_default_str();
  batch
      ->add_option("--memory-limit", flags->memory_limit,
                   "Address space of each file's process (RLIMIT_AS; suffixes like 4GiB work); "
                   "0 = none; default: the machine's memory / --jobs")
      ->transform(CLI::AsSizeValue(false));
  batch->add_flag("--json", flags->json, "Print the summary as one JSON object on stdout");
  batch->add_flag("-q,--quiet", flags->quiet, "Print nothing but errors (and --json)");
  const auto before = batch->get_options();
  AddMeshFlags(batch, &flags->mesh);
  batch->add_option("--cache-dir", "Keep parsed models in this directory (as rdmesh mesh)")
      ->envname("RDMESH_CACHE_DIR");
  batch->add_option("--cache-dir-bytes", "Size limit of --cache-dir (as rdmesh mesh)")
      ->envname("RDMESH_CACHE_DIR_BYTES");
  for (const CLI::Option* option : batch->get_options())
    if (std::find(before.begin(), before.end(), option) == before.end())
      flags->passed_on.push_back(option);
  batch->get_option("--threads")
      ->description("Threads of each file's process; 0 = all cores; default: cores / --jobs")
      ->default_str("");
  batch->get_option("--timeout")
      ->description(
          "Per file, in seconds: the file's process stops itself then, and is killed 0.5 s "
          "later (SIGKILL); 0 = no limit");
  return batch;
}

int RunBatch(const BatchFlags& flags, int (*main)(int argc, char** argv)) {
  auto usage = [](const std::string& message) {
    std::cerr << "rdmesh: error: " << message << "\n";
    return kExitUsage;
  };
  Result<MeshOptions> options = BuildMeshOptions(flags.mesh);
  if (!options.ok()) return usage(options.status().message());
  Result<std::vector<double>> levels = BuildLevels(flags.mesh, *options);
  if (!levels.ok()) return usage(levels.status().message());
  std::string format = flags.format;
  for (char& c : format) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const std::vector<std::string> formats = SupportedOutputFormats();
  if (std::find(formats.begin(), formats.end(), "." + format) == formats.end())
    return usage("--format " + flags.format + ": not an output format");
  // As `rdmesh mesh` refuses it: without a .glb it would only mesh finer.
  if (flags.mesh.write.compress && format != "glb")
    return usage("--compress writes .glb only (--format " + format + ")");
  if (flags.jobs < 0) return usage("--jobs must be 0 (all cores) or more");
  BatchFlags resolved = flags;
  resolved.format = format;
  Result<std::vector<BatchInput>> inputs =
      CollectInputs(flags.inputs, "." + format, flags.output_dir);
  if (!inputs.ok()) return usage(inputs.status().message());
  // Each child is forked from this process: loaded once here, the document framework (.glb and
  // .obj output, the store, assemblies) costs no child its 25-35 ms of loading. A failure is the
  // children's to report.
  (void)LoadDocumentFramework();
  return Batch(resolved, std::move(*inputs), std::move(*levels), main).Run();
}

}  // namespace rdmesh::cli
