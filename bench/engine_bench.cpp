// engine_bench: Google Benchmark timing of the meshing engine through its public API
// (LoadModel once, then MeshModel per iteration) on the yardstick's analytic models.
//
//   build-bench/bin/engine_bench [--benchmark_filter=Sphere] [--benchmark_repetitions=5]
//
// Each case reports the triangles of its mesh as a counter, so a speed change can be told apart
// from a change in the mesh. Model loading is not timed. The engine is run with one thread, so
// figures compare across machines with different core counts.

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <memory>
#include <string>

#include "rdmesh/engine.h"

namespace {

std::string ModelPath(const char* name) {
  const char* dir = std::getenv("RDMESH_BENCH_MODELS");
  return std::string(dir != nullptr ? dir : RDMESH_YARDSTICK_MODELS) + "/" + name;
}

// Loads each model once for the whole process.
std::shared_ptr<const rdmesh::Model> Load(const char* name) {
  auto model = rdmesh::LoadModel(ModelPath(name));
  return model.ok() ? *model : nullptr;
}

void MeshAtDeviation(benchmark::State& state, const char* name) {
  static std::shared_ptr<const rdmesh::Model> sphere = Load("sphere.step");
  static std::shared_ptr<const rdmesh::Model> cylinder = Load("cylinder.step");
  static std::shared_ptr<const rdmesh::Model> torus = Load("torus.step");
  const std::string model_name = name;
  const rdmesh::Model* model = model_name == "sphere.step"     ? sphere.get()
                               : model_name == "cylinder.step" ? cylinder.get()
                                                               : torus.get();
  if (model == nullptr) {
    state.SkipWithError(("cannot load " + ModelPath(name)).c_str());
    return;
  }
  rdmesh::MeshOptions options;
  options.max_deviation_rel = 1.0 / static_cast<double>(state.range(0));
  options.threads = 1;
  int64_t triangles = 0;
  for (auto _ : state) {
    auto result = rdmesh::MeshModel(*model, options);
    if (!result.ok()) {
      state.SkipWithError(result.status().message().c_str());
      return;
    }
    triangles = result->summary.triangles;
    benchmark::DoNotOptimize(triangles);
  }
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["tri_per_s"] = benchmark::Counter(static_cast<double>(triangles),
                                                   benchmark::Counter::kIsIterationInvariantRate);
}

// Argument: 1 / max_deviation_rel (1e3 and 1e4 are the benchmark's two targets).
BENCHMARK_CAPTURE(MeshAtDeviation, Sphere, "sphere.step")
    ->Arg(1000)
    ->Arg(10000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(MeshAtDeviation, Cylinder, "cylinder.step")
    ->Arg(1000)
    ->Arg(10000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(MeshAtDeviation, Torus, "torus.step")
    ->Arg(1000)
    ->Arg(10000)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
