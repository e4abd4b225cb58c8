// ParallelRunner: every index runs once, whatever the thread count and partition. Under TSan
// (build-tsan) it runs on std::threads, and these loops are also its race check.

#include "core/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace rdmesh {
namespace {

TEST(ParallelRunnerTest, EveryIndexRunsOnce) {
  for (int threads : {0, 1, 2}) {
    for (Partition partition : {Partition::kAuto, Partition::kOnePerTask}) {
      const ParallelRunner runner(threads);
      std::vector<std::atomic<int>> runs(1000);
      runner.For(
          7, 1000, [&](int i) { runs[i].fetch_add(1, std::memory_order_relaxed); }, partition);
      for (int i = 0; i < 1000; ++i) ASSERT_EQ(runs[i].load(), i >= 7 ? 1 : 0) << i;
    }
  }
}

TEST(ParallelRunnerTest, EmptyAndReversedRangesRunNothing) {
  const ParallelRunner runner(2);
  int calls = 0;
  runner.For(5, 5, [&](int) { ++calls; });
  runner.For(5, 3, [&](int) { ++calls; });
  EXPECT_EQ(calls, 0);
}

// Two threads asked for, on a machine with two cores or more: the first body waits (up to 10 s,
// for a loaded machine) until another body runs beside it.
TEST(ParallelRunnerTest, UsesTheThreadsItIsGiven) {
  if (std::thread::hardware_concurrency() < 2) GTEST_SKIP() << "one core";
  const ParallelRunner runner(2);
  std::atomic<int> inside{0};
  std::atomic<bool> together{false};
  runner.For(
      0, 64,
      [&](int) {
        if (++inside == 2) together = true;
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
        while (!together && std::chrono::steady_clock::now() < until) std::this_thread::yield();
        --inside;
      },
      Partition::kOnePerTask);
  EXPECT_TRUE(together);
}

}  // namespace
}  // namespace rdmesh
