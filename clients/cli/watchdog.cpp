#include "watchdog.h"

#include <chrono>

namespace rdmesh::cli {

Watchdog::Watchdog(double seconds, std::function<void()> on_expire) {
  if (seconds <= 0) return;
  auto deadline = std::chrono::steady_clock::now() +
                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                      std::chrono::duration<double>(seconds));
  thread_ = std::thread([this, deadline, on_expire = std::move(on_expire)] {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!wake_.wait_until(lock, deadline, [this] { return disarmed_; })) on_expire();
  });
}

void Watchdog::Disarm() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    disarmed_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

}  // namespace rdmesh::cli
