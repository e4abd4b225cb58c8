#pragma once
// A last-resort deadline for the command line: --timeout must end the process even if a stage
// fails to notice its Context's deadline.

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace rdmesh::cli {

/// Calls `on_expire` from its own thread when `seconds` (> 0) pass before Disarm(); does nothing
/// when `seconds` <= 0. `on_expire` is expected to end the process (std::_Exit).
class Watchdog {
 public:
  Watchdog(double seconds, std::function<void()> on_expire);
  ~Watchdog() { Disarm(); }
  Watchdog(const Watchdog&) = delete;
  Watchdog& operator=(const Watchdog&) = delete;

  /// Stops the watchdog; returns once its thread has ended. Idempotent.
  void Disarm();

 private:
  std::mutex mutex_;
  std::condition_variable wake_;
  bool disarmed_ = false;
  std::thread thread_;
};

}  // namespace rdmesh::cli
