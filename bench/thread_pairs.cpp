// thread_pairs: one thread against two within one process, in pairs a fraction of a second apart
// (issue 13's thread bar: "2 threads give >= 1.8x the speed of 1 thread, and the mesh stays
// byte-identical").
//
//   build/bin/thread_pairs MODEL [--tolerances 1e-3,1e-4] [--pairs 15] [--warmup 2]
//   build/bin/thread_pairs MODEL --only THREADS [--pairs N] [--tolerances T]   (under perf)
//
// The model is loaded once. Per tolerance: `--warmup` meshes at each thread count that are not
// reported, then `--pairs` pairs of MeshModel runs, one with options.threads = 1 and one with 2,
// the order flipping every pair. The two runs of a pair are a fraction of a second apart, so a
// change of the machine's speed (this VM's moves by up to 40% in spells of about a minute) falls
// on both; separate processes (bench/performance/thread_speedup.py) are seconds apart and see
// the model's first mesh in a process. This is the warm rdmeshd's case: one process meshing a
// loaded model again and again.
//
// Timed: MeshSummary::seconds (edge grids, faces and assembly; what `rdmesh mesh --json` reports
// as `seconds`) and the process's CPU seconds over the run. Every mesh is compared with the first
// one-thread mesh of its tolerance (nodes, triangles, face ids, node kinds and parameters, bit for
// bit). One JSON object per tolerance on stdout:
//   {"model", "tolerance", "pairs", "triangles", "identical", "one_thread_seconds" (median),
//    "two_thread_seconds" (median), "speedup_of_medians", "speedup_median_of_pairs",
//    "speedup_of_fastest", "one_thread_wall" and "two_thread_wall" (medians of the whole
//    MeshModel call, edge lines included), "wall_speedup_median_of_pairs", "one_thread_cpu" and
//    "two_thread_cpu" (medians)}
// Exits 1 when a mesh differs, 2 on a load or mesh error.

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "rdmesh/engine.h"

namespace {

double CpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

bool SameMesh(const rdmesh::Mesh& a, const rdmesh::Mesh& b) {
  return a.xyz == b.xyz && a.triangles == b.triangles && a.triangle_face == b.triangle_face &&
         a.node_dim == b.node_dim && a.node_entity == b.node_entity && a.node_param == b.node_param;
}

struct Run {
  double seconds = 0.0;  // MeshSummary::seconds
  double wall = 0.0;     // the whole MeshModel call
  double cpu = 0.0;
};

// Meshes once; false (with a message) on an error.
bool MeshOnce(const rdmesh::Model& model, rdmesh::MeshOptions options, int threads,
              rdmesh::Mesh* mesh, Run* run) {
  options.threads = threads;
  const double cpu0 = CpuSeconds();
  const auto wall0 = std::chrono::steady_clock::now();
  auto result = rdmesh::MeshModel(model, options);
  run->wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  run->cpu = CpuSeconds() - cpu0;
  if (!result.ok()) {
    std::fprintf(stderr, "thread_pairs: %s\n", result.status().message().c_str());
    return false;
  }
  run->seconds = result->summary.seconds;
  *mesh = std::move(result->mesh);
  return true;
}

std::vector<double> ParseList(const std::string& text) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) values.push_back(std::strtod(item.c_str(), nullptr));
  return values;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path;
  std::vector<double> tolerances = {1e-3, 1e-4};
  int pairs = 15;
  int warmup = 2;
  int only = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--tolerances" && i + 1 < argc) {
      tolerances = ParseList(argv[++i]);
    } else if (arg == "--pairs" && i + 1 < argc) {
      pairs = std::max(1, std::atoi(argv[++i]));
    } else if (arg == "--warmup" && i + 1 < argc) {
      warmup = std::max(0, std::atoi(argv[++i]));
    } else if (arg == "--only" && i + 1 < argc) {
      only = std::max(1, std::atoi(argv[++i]));
    } else if (!arg.empty() && arg[0] != '-' && path.empty()) {
      path = arg;
    } else {
      std::fprintf(stderr,
                   "usage: thread_pairs MODEL [--tolerances 1e-3,1e-4] [--pairs 15] "
                   "[--warmup 2] [--only THREADS]\n");
      return 2;
    }
  }
  if (path.empty() || tolerances.empty()) {
    std::fprintf(stderr, "usage: thread_pairs MODEL [--tolerances 1e-3,1e-4] [--pairs 15]\n");
    return 2;
  }
  auto model = rdmesh::LoadModel(path);
  if (!model.ok()) {
    std::fprintf(stderr, "thread_pairs: %s\n", model.status().message().c_str());
    return 2;
  }
  const std::string name = path.substr(path.find_last_of('/') + 1);
  bool all_identical = true;
  for (double tolerance : tolerances) {
    rdmesh::MeshOptions options;
    options.max_deviation_rel = tolerance;
    rdmesh::Mesh reference;
    rdmesh::Mesh mesh;
    Run run;
    if (only > 0) {  // for a profiler: `--pairs` runs at one thread count, nothing reported
      for (int i = 0; i < pairs; ++i)
        if (!MeshOnce(**model, options, only, &mesh, &run)) return 2;
      continue;
    }
    if (!MeshOnce(**model, options, 1, &reference, &run)) return 2;
    bool identical = true;
    for (int i = 0; i < warmup; ++i) {
      for (int threads : {2, 1}) {
        if (!MeshOnce(**model, options, threads, &mesh, &run)) return 2;
        identical = identical && SameMesh(mesh, reference);
      }
    }
    std::vector<double> one, two, one_wall, two_wall, one_cpu, two_cpu, ratios, wall_ratios;
    for (int i = 0; i < pairs; ++i) {
      Run runs[2];  // [0] one thread, [1] two threads
      for (int k = 0; k < 2; ++k) {
        const int threads = (i % 2 == 0) == (k == 0) ? 1 : 2;
        if (!MeshOnce(**model, options, threads, &mesh, &runs[threads - 1])) return 2;
        identical = identical && SameMesh(mesh, reference);
      }
      one.push_back(runs[0].seconds);
      two.push_back(runs[1].seconds);
      one_wall.push_back(runs[0].wall);
      two_wall.push_back(runs[1].wall);
      wall_ratios.push_back(runs[0].wall / runs[1].wall);
      one_cpu.push_back(runs[0].cpu);
      two_cpu.push_back(runs[1].cpu);
      ratios.push_back(runs[0].seconds / runs[1].seconds);
    }
    all_identical = all_identical && identical;
    const double one_median = Median(one);
    const double two_median = Median(two);
    const double fastest =
        *std::min_element(one.begin(), one.end()) / *std::min_element(two.begin(), two.end());
    std::printf(
        "{\"model\": \"%s\", \"tolerance\": %g, \"pairs\": %d, \"triangles\": %lld, "
        "\"identical\": %s, \"one_thread_seconds\": %.6f, \"two_thread_seconds\": %.6f, "
        "\"speedup_of_medians\": %.4f, \"speedup_median_of_pairs\": %.4f, "
        "\"speedup_of_fastest\": %.4f, \"one_thread_wall\": %.6f, \"two_thread_wall\": %.6f, "
        "\"wall_speedup_median_of_pairs\": %.4f, \"one_thread_cpu\": %.6f, "
        "\"two_thread_cpu\": %.6f}\n",
        name.c_str(), tolerance, pairs, static_cast<long long>(reference.triangle_count()),
        identical ? "true" : "false", one_median, two_median, one_median / two_median,
        Median(ratios), fastest, Median(one_wall), Median(two_wall), Median(wall_ratios),
        Median(one_cpu), Median(two_cpu));
    std::fflush(stdout);
  }
  return all_identical ? 0 : 1;
}
