// part21_bench: the speed of our Part 21 text parser (engine/src/model/step/part21) against OCCT's
// own text read, STEPControl_Reader::ReadFile, on the same files. Single thread.
//
//   part21_bench [--repeat N] [--no-occt] FILE.step...
//
// For each file: the bytes are read into memory once; Parse runs N times (default 5) on a fresh
// copy each time (the copy is not timed) and the fastest run counts (--repeat 1: the first, cold
// parse of the process). ReadFile runs once, from the file (in the page cache after our read);
// --no-occt skips it (a whole library, at OCCT's few MB/s, takes long). Wall and thread CPU
// times both: on a shared machine the CPU time is the figure that does not depend on the load.
// Prints one line per file and a total:
//   file MB instances ms cpu_ms MB/s cpu_MB/s entities/s occt_ms occt_cpu_ms occt_entities
//   cpu_speedup (occt_cpu_ms / cpu_ms)
// occt_entities (OCCT's model's NbEntities) is a cross-check of our instance count.

#include <IFSelect_ReturnStatus.hxx>
#include <Interface_InterfaceModel.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <STEPControl_Reader.hxx>
#include <XSControl_WorkSession.hxx>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "model/step/part21.h"

namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

// CPU seconds of the calling thread.
double CpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 5;
  bool occt_too = true;
  std::vector<const char*> paths;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) {
      repeat = std::max(1, std::atoi(argv[++i]));
    } else if (std::strcmp(argv[i], "--no-occt") == 0) {
      occt_too = false;
    } else {
      paths.push_back(argv[i]);
    }
  }
  if (paths.empty()) {
    std::fprintf(stderr, "usage: %s [--repeat N] [--no-occt] FILE.step...\n", argv[0]);
    return 2;
  }
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer));
  std::printf("%-36s %7s %9s %8s %8s %7s %8s %11s %9s %11s %13s %11s\n", "file", "MB", "instances",
              "ms", "cpu_ms", "MB/s", "cpu_MB/s", "entities/s", "occt_ms", "occt_cpu_ms",
              "occt_entities", "cpu_speedup");
  double total_mb = 0, total_wall = 0, total_cpu = 0, total_occt = 0, total_occt_cpu = 0;
  size_t total_instances = 0;
  int failures = 0;
  for (const char* path : paths) {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.is_open() || in.bad()) {
      std::fprintf(stderr, "%s: cannot read\n", path);
      ++failures;
      continue;
    }
    double wall = 1e30, cpu = 1e30;
    size_t instances = 0;
    bool ok = true;
    for (int r = 0; r < repeat && ok; ++r) {
      std::string copy = bytes;
      const double cpu_start = CpuSeconds();
      const Clock::time_point start = Clock::now();
      rdmesh::Result<rdmesh::step::File> file = rdmesh::step::Parse(std::move(copy));
      const Clock::time_point stop = Clock::now();
      const double cpu_stop = CpuSeconds();
      if (!file.ok()) {
        std::fprintf(stderr, "%s: %s\n", path, file.status().ToString().c_str());
        ok = false;
        break;
      }
      wall = std::min(wall, Seconds(start, stop));
      cpu = std::min(cpu, cpu_stop - cpu_start);
      instances = file->instances.size();
    }
    if (!ok) {
      ++failures;
      continue;
    }
    double occt = 0, occt_cpu = 0;
    int occt_entities = -1;
    if (occt_too) {
      STEPControl_Reader reader;
      const double cpu_start = CpuSeconds();
      const Clock::time_point start = Clock::now();
      const IFSelect_ReturnStatus status = reader.ReadFile(path);
      occt = Seconds(start, Clock::now());
      occt_cpu = CpuSeconds() - cpu_start;
      if (status == IFSelect_RetDone) occt_entities = reader.WS()->Model()->NbEntities();
    }
    const double mb = static_cast<double>(bytes.size()) / 1e6;
    std::string name = path;
    name = name.substr(name.find_last_of('/') + 1);
    std::printf("%-36.36s %7.2f %9zu %8.2f %8.2f %7.1f %8.1f %11.0f %9.1f %11.1f %13d %10.1fx\n",
                name.c_str(), mb, instances, wall * 1e3, cpu * 1e3, mb / wall, mb / cpu,
                static_cast<double>(instances) / wall, occt * 1e3, occt_cpu * 1e3, occt_entities,
                occt_cpu / cpu);
    total_mb += mb;
    total_wall += wall;
    total_cpu += cpu;
    total_occt += occt;
    total_occt_cpu += occt_cpu;
    total_instances += instances;
  }
  if (total_wall > 0) {
    std::printf("%-36s %7.2f %9zu %8.2f %8.2f %7.1f %8.1f %11.0f %9.1f %11.1f %13s %10.1fx\n",
                "total", total_mb, total_instances, total_wall * 1e3, total_cpu * 1e3,
                total_mb / total_wall, total_mb / total_cpu,
                static_cast<double>(total_instances) / total_wall, total_occt * 1e3,
                total_occt_cpu * 1e3, "", total_occt_cpu / total_cpu);
  }
  return failures == 0 ? 0 : 1;
}
