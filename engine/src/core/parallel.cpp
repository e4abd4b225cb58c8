#include "core/parallel.h"

#include <memory>

#if defined(__SANITIZE_THREAD__)
#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>
#else
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>
#endif

namespace rdmesh {

#if defined(__SANITIZE_THREAD__)

struct ParallelRunner::Impl {
  int threads;
};

ParallelRunner::ParallelRunner(int threads)
    : impl_(std::make_unique<Impl>(
          Impl{threads > 0 ? threads
                           : std::max(1, static_cast<int>(std::thread::hardware_concurrency()))})) {
}

ParallelRunner::~ParallelRunner() = default;

void ParallelRunner::For(int begin, int end, const std::function<void(int)>& body,
                         Partition) const {
  if (begin >= end) return;
  std::atomic<int> next{begin};
  auto run = [&] {
    for (int i = next++; i < end; i = next++) body(i);
  };
  std::vector<std::thread> helpers;
  const int extra = std::min(impl_->threads, end - begin) - 1;
  for (int t = 0; t < extra; ++t) helpers.emplace_back(run);
  run();
  for (std::thread& helper : helpers) helper.join();
}

#else

struct ParallelRunner::Impl {
  explicit Impl(int threads) : arena(threads > 0 ? threads : tbb::task_arena::automatic) {}
  tbb::task_arena arena;
};

ParallelRunner::ParallelRunner(int threads) : impl_(std::make_unique<Impl>(threads)) {}

ParallelRunner::~ParallelRunner() = default;

void ParallelRunner::For(int begin, int end, const std::function<void(int)>& body,
                         Partition partition) const {
  impl_->arena.execute([&] {
    if (partition == Partition::kOnePerTask) {
      tbb::parallel_for(begin, end, body, tbb::simple_partitioner());
    } else {
      tbb::parallel_for(begin, end, body);
    }
  });
}

#endif

}  // namespace rdmesh
