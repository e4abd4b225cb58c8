#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>

namespace rdmesh::server {

/// Admission control for meshing jobs: at most `max_jobs` run at once and at most `max_queue`
/// more wait for a slot; beyond that a job is refused at once (the service answers
/// RESOURCE_EXHAUSTED). Thread-safe.
class JobLimiter {
 public:
  enum class Admission {
    kAdmitted,   ///< the caller holds a slot and must call Release()
    kQueueFull,  ///< max_jobs running and max_queue waiting
    kStopped,    ///< `should_stop` turned true while waiting (cancelled or past the deadline)
    kClosed,     ///< the server is shutting down
  };

  JobLimiter(int max_jobs, int max_queue);
  JobLimiter(const JobLimiter&) = delete;
  JobLimiter& operator=(const JobLimiter&) = delete;

  /// Takes a slot, waiting in the queue for one when all are busy. `should_stop` is polled
  /// every `poll` while waiting.
  Admission Acquire(const std::function<bool()>& should_stop,
                    std::chrono::milliseconds poll = std::chrono::milliseconds(20));
  /// Gives back a slot taken by Acquire.
  void Release();
  /// Refuses every later Acquire and wakes the waiting ones (kClosed). Running jobs keep going.
  void Close();

  int running() const;
  int queued() const;
  int max_jobs() const { return max_jobs_; }
  int max_queue() const { return max_queue_; }

 private:
  const int max_jobs_;
  const int max_queue_;
  mutable std::mutex mutex_;
  std::condition_variable slot_freed_;
  int running_ = 0;
  int queued_ = 0;
  bool closed_ = false;
};

/// Holds a JobLimiter slot for a scope.
class JobSlot {
 public:
  explicit JobSlot(JobLimiter* limiter) : limiter_(limiter) {}
  ~JobSlot() {
    if (limiter_ != nullptr) limiter_->Release();
  }
  JobSlot(const JobSlot&) = delete;
  JobSlot& operator=(const JobSlot&) = delete;

 private:
  JobLimiter* limiter_;
};

}  // namespace rdmesh::server
