#include "worker/worker_pool.h"

#include <algorithm>
#include <chrono>
#include <utility>

namespace rdmesh::server {
namespace {

/// How often Acquire looks at its stop condition while it waits for a worker.
constexpr int kPollMs = 20;

}  // namespace

WorkerPool::WorkerPool(WorkerSettings settings, int max_workers)
    : settings_(std::move(settings)), max_workers_(std::max(1, max_workers)) {}

WorkerPool::~WorkerPool() { Close(); }

Status WorkerPool::Prestart(int count) {
  std::lock_guard<std::mutex> lock(mutex_);
  keep_ = std::min(count, max_workers_);
  while (live_ < keep_) {
    Result<std::unique_ptr<WorkerProcess>> worker = WorkerProcess::Start(settings_);
    if (!worker.ok()) return worker.status();
    pids_.push_back((*worker)->pid());
    idle_.push_back(std::move(*worker));
    ++live_;
  }
  return Status::Ok();
}

std::unique_ptr<WorkerProcess> WorkerPool::Acquire(const std::string& model_id,
                                                   const std::function<bool()>& stop,
                                                   Status* error) {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    if (closed_) {
      *error = Status(StatusCode::kCancelled, "the server is shutting down");
      return nullptr;
    }
    // Idle workers that died while idle (killed from outside) are dropped.
    for (std::size_t i = 0; i < idle_.size();) {
      if (idle_[i]->Exited()) {
        pids_.erase(std::remove(pids_.begin(), pids_.end(), idle_[i]->pid()), pids_.end());
        idle_.erase(idle_.begin() + static_cast<std::ptrdiff_t>(i));
        --live_;
        ++lost_;
      } else {
        ++i;
      }
    }
    if (!idle_.empty()) {
      std::size_t pick = idle_.size() - 1;  // the most recently returned
      for (std::size_t i = 0; i < idle_.size(); ++i) {
        if (idle_[i]->Holds(model_id)) pick = i;
      }
      std::unique_ptr<WorkerProcess> worker = std::move(idle_[pick]);
      idle_.erase(idle_.begin() + static_cast<std::ptrdiff_t>(pick));
      return worker;
    }
    if (live_ < max_workers_) {
      Result<std::unique_ptr<WorkerProcess>> worker = WorkerProcess::Start(settings_);
      if (!worker.ok()) {
        *error = worker.status();
        return nullptr;
      }
      pids_.push_back((*worker)->pid());
      ++live_;
      return std::move(*worker);
    }
    returned_.wait_for(lock, std::chrono::milliseconds(kPollMs));
    if (stop()) {
      *error = Status(StatusCode::kCancelled, "cancelled while waiting for a worker");
      return nullptr;
    }
  }
}

void WorkerPool::Release(std::unique_ptr<WorkerProcess> worker) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (closed_) {
    pids_.erase(std::remove(pids_.begin(), pids_.end(), worker->pid()), pids_.end());
    --live_;
    worker.reset();  // kills it
    return;
  }
  idle_.push_back(std::move(worker));
  returned_.notify_one();
}

void WorkerPool::Discard(std::unique_ptr<WorkerProcess> worker) {
  worker->Reap(std::chrono::milliseconds(0));
  std::lock_guard<std::mutex> lock(mutex_);
  pids_.erase(std::remove(pids_.begin(), pids_.end(), worker->pid()), pids_.end());
  worker.reset();
  --live_;
  ++lost_;
  if (!closed_ && live_ < keep_) {
    Result<std::unique_ptr<WorkerProcess>> replacement = WorkerProcess::Start(settings_);
    if (replacement.ok()) {
      pids_.push_back((*replacement)->pid());
      idle_.push_back(std::move(*replacement));
      ++live_;
    }
  }
  returned_.notify_one();
}

void WorkerPool::Close() {
  std::vector<std::unique_ptr<WorkerProcess>> idle;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    idle.swap(idle_);
    for (const auto& worker : idle) {
      pids_.erase(std::remove(pids_.begin(), pids_.end(), worker->pid()), pids_.end());
    }
    live_ -= static_cast<int>(idle.size());
  }
  idle.clear();  // kills and reaps them
}

int WorkerPool::live() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return live_;
}

int WorkerPool::idle() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(idle_.size());
}

int64_t WorkerPool::lost() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return lost_;
}

std::vector<pid_t> WorkerPool::pids() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pids_;
}

}  // namespace rdmesh::server
