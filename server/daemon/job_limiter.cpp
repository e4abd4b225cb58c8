#include "daemon/job_limiter.h"

#include <algorithm>

namespace rdmesh::server {

JobLimiter::JobLimiter(int max_jobs, int max_queue)
    : max_jobs_(std::max(1, max_jobs)), max_queue_(std::max(0, max_queue)) {}

JobLimiter::Admission JobLimiter::Acquire(const std::function<bool()>& should_stop,
                                          std::chrono::milliseconds poll) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (closed_) return Admission::kClosed;
  if (running_ < max_jobs_) {
    ++running_;
    return Admission::kAdmitted;
  }
  if (queued_ >= max_queue_) return Admission::kQueueFull;
  ++queued_;
  while (true) {
    slot_freed_.wait_for(lock, poll);
    if (closed_) {
      --queued_;
      return Admission::kClosed;
    }
    if (running_ < max_jobs_) {
      --queued_;
      ++running_;
      return Admission::kAdmitted;
    }
    if (should_stop && should_stop()) {
      --queued_;
      return Admission::kStopped;
    }
  }
}

void JobLimiter::Release() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    --running_;
  }
  slot_freed_.notify_one();
}

void JobLimiter::Close() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
  }
  slot_freed_.notify_all();
}

int JobLimiter::running() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return running_;
}

int JobLimiter::queued() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queued_;
}

}  // namespace rdmesh::server
