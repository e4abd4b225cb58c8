#include "daemon/job_limiter.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace rdmesh::server {
namespace {

using Admission = JobLimiter::Admission;

TEST(JobLimiterTest, AdmitsUpToMaxJobsThenQueuesThenRefuses) {
  JobLimiter limiter(2, 1);
  EXPECT_EQ(limiter.Acquire(nullptr), Admission::kAdmitted);
  EXPECT_EQ(limiter.Acquire(nullptr), Admission::kAdmitted);
  EXPECT_EQ(limiter.running(), 2);

  std::atomic<bool> admitted{false};
  std::thread waiter([&] { admitted = limiter.Acquire(nullptr) == Admission::kAdmitted; });
  while (limiter.queued() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_EQ(limiter.Acquire(nullptr), Admission::kQueueFull);  // 2 running, 1 waiting

  limiter.Release();
  waiter.join();
  EXPECT_TRUE(admitted);
  EXPECT_EQ(limiter.running(), 2);
  EXPECT_EQ(limiter.queued(), 0);
  limiter.Release();
  limiter.Release();
  EXPECT_EQ(limiter.running(), 0);
}

TEST(JobLimiterTest, WaitingJobStopsWhenAskedTo) {
  JobLimiter limiter(1, 4);
  ASSERT_EQ(limiter.Acquire(nullptr), Admission::kAdmitted);
  std::atomic<bool> stop{false};
  Admission result = Admission::kAdmitted;
  std::thread waiter([&] { result = limiter.Acquire([&] { return stop.load(); }); });
  while (limiter.queued() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  const auto start = std::chrono::steady_clock::now();
  stop = true;
  waiter.join();
  EXPECT_EQ(result, Admission::kStopped);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(500));
  EXPECT_EQ(limiter.queued(), 0);
  EXPECT_EQ(limiter.running(), 1);
  limiter.Release();
}

TEST(JobLimiterTest, CloseWakesWaitersAndRefusesNewJobs) {
  JobLimiter limiter(1, 4);
  ASSERT_EQ(limiter.Acquire(nullptr), Admission::kAdmitted);
  Admission result = Admission::kAdmitted;
  std::thread waiter([&] { result = limiter.Acquire(nullptr); });
  while (limiter.queued() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  limiter.Close();
  waiter.join();
  EXPECT_EQ(result, Admission::kClosed);
  EXPECT_EQ(limiter.Acquire(nullptr), Admission::kClosed);
  limiter.Release();
}

TEST(JobLimiterTest, ZeroQueueRefusesAtOnce) {
  JobLimiter limiter(1, 0);
  ASSERT_EQ(limiter.Acquire(nullptr), Admission::kAdmitted);
  EXPECT_EQ(limiter.Acquire(nullptr), Admission::kQueueFull);
  {
    JobSlot slot(&limiter);  // releases the first job's slot
  }
  EXPECT_EQ(limiter.running(), 0);
}

}  // namespace
}  // namespace rdmesh::server
