// step_equivalence: rdmesh's own STEP reader (step::Parse + step::TranslateStep) against the
// engine's OCCT read (STEPCAFControl_Reader, model_readers.cpp, forced with
// RDMESH_STEP_READER=occt) on many files (issue 34).
//
//   step_equivalence [--threads N] [--timeout S] [--area-rel R] FILE_OR_DIR...
//
// Directories are searched for *.step / *.stp (recursively, sorted). Each file is read in a
// child process (a crash or hang there costs one file): both reads, alternating which goes
// first, then the comparison of step/equivalence.h. One JSON line per file:
//   {"file": ..., "bytes": N, "faces": F, "supported": bool, "unsupported": "...",
//    "equivalent": bool, "difference": "...", "worst_area_rel": x, "worst_box_rel": x,
//    "ours_seconds": parse + translate, "parse_seconds": s, "translate_seconds": s,
//    "occt_seconds": s, "occt_error": "...", "ours_error": "..."}
// and a last line {"summary": ...}: files, supported and equivalent fractions, the geometric mean
// of ours/OCCT seconds over equivalent files and their total seconds.
// OCC_CATCH_SIGNALS below turns a fault inside OCCT into an exception, as in the engine's reads
// (model_readers' ScopedOcctFaultHandlers); it has to be defined before any OCCT header.
#define OCC_CONVERT_SIGNALS 1

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <OSD.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "model/model_readers.h"
#include "model/step/equivalence.h"
#include "model/step/part21.h"
#include "model/step/translate.h"

namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string Json(const std::string& text) {
  std::string out = "\"";
  for (unsigned char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
      out += buffer;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

struct Options {
  int threads = 0;
  double timeout = 600;
  double area_rel = 1e-9;
  bool isolate = true;     ///< --no-fork runs each file in this process (for debuggers)
  bool ours_only = false;  ///< --ours-only: our read alone, no OCCT read or comparison (profiles)
};

// Reads and compares one file; returns its JSON line. Runs in the child.
std::string RunOne(const std::string& path, const Options& options, bool ours_first) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string name = std::filesystem::path(path).filename().string();
  double parse_s = 0, translate_s = 0, occt_s = 0;
  rdmesh::Result<rdmesh::ReadShape> occt = rdmesh::Status(rdmesh::StatusCode::kInternal, "");
  rdmesh::Result<rdmesh::step::Translated> ours = rdmesh::Status(rdmesh::StatusCode::kInternal, "");
  std::string ours_error;
  auto run_occt = [&] {
    auto start = Clock::now();
    occt = rdmesh::ReadModelBytes(bytes, rdmesh::ModelFormat::kStep, path, name, nullptr);
    occt_s = Since(start);
    if (occt.ok() && occt->reader != "occt")
      occt = rdmesh::Status(rdmesh::StatusCode::kInternal, "the engine's read was not OCCT's");
  };
  auto run_ours = [&] {
    auto start = Clock::now();
    rdmesh::Result<rdmesh::step::File> file = rdmesh::step::Parse(bytes, nullptr);
    parse_s = Since(start);
    if (!file.ok()) {
      ours_error = file.status().message();
      return;
    }
    start = Clock::now();
    rdmesh::step::TranslateOptions translate_options;
    translate_options.threads = options.threads;
    try {
      OCC_CATCH_SIGNALS
      ours = rdmesh::step::TranslateStep(*file, translate_options, nullptr);
    } catch (const Standard_Failure& failure) {
      ours = rdmesh::Status(rdmesh::StatusCode::kInternal,
                            std::string("OCCT failure: ") + failure.DynamicType()->Name());
    }
    translate_s = Since(start);
    if (!ours.ok()) ours_error = ours.status().message();
  };
  if (options.ours_only) {
    run_ours();
  } else if (ours_first) {
    run_ours();
    run_occt();
  } else {
    run_occt();
    run_ours();
  }
  std::string line = "{\"file\": " + Json(path) + ", \"bytes\": " + std::to_string(bytes.size());
  const bool supported = ours.ok() && ours->supported;
  line += ", \"supported\": " + std::string(supported ? "true" : "false");
  if (ours.ok() && !ours->supported) line += ", \"unsupported\": " + Json(ours->unsupported);
  if (!ours_error.empty()) line += ", \"ours_error\": " + Json(ours_error);
  if (!occt.ok()) line += ", \"occt_error\": " + Json(occt.status().message());
  char numbers[256];
  std::snprintf(numbers, sizeof(numbers),
                ", \"parse_seconds\": %.6f, \"translate_seconds\": %.6f, \"ours_seconds\": %.6f, "
                "\"occt_seconds\": %.6f",
                parse_s, translate_s, parse_s + translate_s, occt_s);
  line += numbers;
  bool equivalent = false;
  if (supported && occt.ok() && !options.ours_only) {
    rdmesh::step::ShapeSummary a = rdmesh::step::Summarize(ours->read, options.threads);
    rdmesh::step::ShapeSummary b = rdmesh::step::Summarize(*occt, options.threads);
    rdmesh::step::Comparison comparison = rdmesh::step::Compare(a, b, options.area_rel);
    equivalent = comparison.equivalent;
    std::snprintf(numbers, sizeof(numbers),
                  ", \"faces\": %d, \"worst_area_rel\": %.3g, \"worst_box_rel\": %.3g", b.faces,
                  comparison.worst_area_rel, comparison.worst_box_rel);
    line += numbers;
    if (!equivalent) line += ", \"difference\": " + Json(comparison.difference);
    if (!comparison.numbering_difference.empty())
      line += ", \"numbering\": " + Json(comparison.numbering_difference);
    if (!comparison.tolerance_difference.empty())
      line += ", \"tolerances\": " + Json(comparison.tolerance_difference);
    if (!comparison.name_line_break_difference.empty())
      line += ", \"name_line_breaks\": " + Json(comparison.name_line_break_difference);
    if (ours->read.length_unit != occt->length_unit ||
        ours->read.unit_scale_mm != occt->unit_scale_mm) {
      equivalent = false;
      line += ", \"unit\": " + Json(ours->read.length_unit + " vs " + occt->length_unit);
    }
  }
  line += ", \"equivalent\": " + std::string(equivalent ? "true" : "false");
  if (supported) {
    line += ", \"items\": " + std::to_string(ours->items) +
            ", \"items_healed_by_face\": " + std::to_string(ours->items_healed_by_face) +
            ", \"items_in_order\": " + std::to_string(ours->items_in_order) +
            ", \"faces_fixed_again\": " + std::to_string(ours->faces_fixed_again);
    if (!ours->heal_note.empty()) line += ", \"heal_note\": " + Json(ours->heal_note);
    line += ", \"stages\": {";
    bool first = true;
    for (const auto& [stage, seconds] : ours->stage_seconds) {
      std::snprintf(numbers, sizeof(numbers), "%s\"%s\": %.6f", first ? "" : ", ", stage.c_str(),
                    seconds);
      line += numbers;
      first = false;
    }
    line += "}";
  }
  return line + "}";
}

// Runs RunOne in a child process with a timeout; a crash or hang gives an error line.
std::string RunIsolated(const std::string& path, const Options& options, bool ours_first) {
  int fds[2];
  if (pipe(fds) != 0) return "{\"file\": " + Json(path) + ", \"error\": \"pipe\"}";
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    std::string line = RunOne(path, options, ours_first);
    const char* data = line.data();
    size_t left = line.size();
    while (left > 0) {
      ssize_t n = write(fds[1], data, left);
      if (n <= 0) break;
      data += n;
      left -= static_cast<size_t>(n);
    }
    _exit(0);
  }
  close(fds[1]);
  std::string output;
  const auto start = Clock::now();
  bool timed_out = false;
  char buffer[4096];
  while (true) {
    const double left = options.timeout - Since(start);
    if (left <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = poll(&p, 1, static_cast<int>(std::min(left, 1.0) * 1000));
    if (ready < 0) break;
    if (ready == 0) continue;
    const ssize_t n = read(fds[0], buffer, sizeof(buffer));
    if (n <= 0) break;
    output.append(buffer, static_cast<size_t>(n));
  }
  if (timed_out) kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  close(fds[0]);
  if (timed_out) return "{\"file\": " + Json(path) + ", \"error\": \"timeout\"}";
  if (output.empty()) {
    std::string why = WIFSIGNALED(status) ? "signal " + std::to_string(WTERMSIG(status))
                                          : "exit " + std::to_string(WEXITSTATUS(status));
    return "{\"file\": " + Json(path) + ", \"error\": " + Json("child died: " + why) + "}";
  }
  return output;
}

bool IsStep(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  return ext == ".step" || ext == ".stp";
}

// The number after "key": in a JSON line, or NaN.
double Number(const std::string& line, const std::string& key) {
  const size_t at = line.find("\"" + key + "\": ");
  if (at == std::string::npos) return std::nan("");
  return std::strtod(line.c_str() + at + key.size() + 4, nullptr);
}

bool Flag(const std::string& line, const std::string& key) {
  return line.find("\"" + key + "\": true") != std::string::npos;
}

}  // namespace

int main(int argc, char** argv) {
  // The engine reads STEP with rdmesh's own reader by default; the comparison is against OCCT's.
  setenv("RDMESH_STEP_READER", "occt", 1);
  // Faults inside OCCT become exceptions, for our read as for the engine's (OCCT's healing can
  // fault on broken geometry; its own OCC_CATCH_SIGNALS blocks then recover).
  OSD::SetSignal(OSD_SignalMode_Set, /*theFloatingSignal=*/false);
  Options options;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--threads" && i + 1 < argc) {
      options.threads = std::atoi(argv[++i]);
    } else if (arg == "--timeout" && i + 1 < argc) {
      options.timeout = std::atof(argv[++i]);
    } else if (arg == "--ours-only") {
      options.ours_only = true;
    } else if (arg == "--no-fork") {
      options.isolate = false;
    } else if (arg == "--area-rel" && i + 1 < argc) {
      options.area_rel = std::atof(argv[++i]);
    } else if (std::filesystem::is_directory(arg)) {
      std::vector<std::string> found;
      for (const auto& entry : std::filesystem::recursive_directory_iterator(arg))
        if (entry.is_regular_file() && IsStep(entry.path())) found.push_back(entry.path());
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else if (std::filesystem::is_regular_file(arg)) {
      files.push_back(arg);
    } else {
      std::fprintf(stderr, "usage: %s [--threads N] [--timeout S] [--area-rel R] FILE_OR_DIR...\n",
                   argv[0]);
      return 2;
    }
  }
  // Warm the OCCT reader's static tables and the XCAF application up before forking, so the
  // children time steady reads; TBB stays uninitialised here (it must not be forked).
  if (!files.empty() && options.isolate) {
    std::ifstream in(files.front(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    (void)rdmesh::ReadModelBytes(bytes, rdmesh::ModelFormat::kStep, files.front(), "warm-up",
                                 nullptr);
    (void)rdmesh::step::Parse(bytes, nullptr);
  }
  int supported = 0, equivalent = 0, failed = 0, numbering = 0, tolerances = 0, line_breaks = 0;
  double log_ratio = 0, ours_total = 0, occt_total = 0, worst_area = 0;
  for (size_t i = 0; i < files.size(); ++i) {
    const std::string line = options.isolate ? RunIsolated(files[i], options, i % 2 == 0)
                                             : RunOne(files[i], options, i % 2 == 0);
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
    if (line.find("\"error\":") != std::string::npos) ++failed;
    if (line.find("\"numbering\":") != std::string::npos) ++numbering;
    if (line.find("\"tolerances\":") != std::string::npos) ++tolerances;
    if (line.find("\"name_line_breaks\":") != std::string::npos) ++line_breaks;
    if (Flag(line, "supported")) ++supported;
    if (!Flag(line, "equivalent")) continue;
    ++equivalent;
    const double ours = Number(line, "ours_seconds"), occt = Number(line, "occt_seconds");
    if (ours > 0 && occt > 0) log_ratio += std::log(ours / occt);
    ours_total += ours;
    occt_total += occt;
    worst_area = std::max(worst_area, Number(line, "worst_area_rel"));
  }
  const double n = static_cast<double>(files.size());
  std::printf(
      "{\"summary\": {\"files\": %zu, \"supported\": %d, \"equivalent\": %d, \"failed\": %d, "
      "\"supported_fraction\": %.4f, \"equivalent_fraction\": %.4f, "
      "\"time_ratio_geomean\": %.4f, \"ours_seconds\": %.3f, \"occt_seconds\": %.3f, "
      "\"worst_area_rel\": %.3g, \"numbering_differences\": %d, \"tolerance_differences\": %d, "
      "\"name_line_break_differences\": %d}}\n",
      files.size(), supported, equivalent, failed, n > 0 ? supported / n : 0.0,
      n > 0 ? equivalent / n : 0.0, equivalent > 0 ? std::exp(log_ratio / equivalent) : 0.0,
      ours_total, occt_total, worst_area, numbering, tolerances, line_breaks);
  return 0;
}
