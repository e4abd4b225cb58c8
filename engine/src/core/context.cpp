#include "rdmesh/context.h"

namespace rdmesh {

namespace {
int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
}  // namespace

void Context::SetDeadline(std::chrono::steady_clock::time_point deadline) {
  int64_t ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(deadline.time_since_epoch()).count();
  int64_t current = deadline_ns_.load();
  // 0 means no deadline; otherwise keep the earlier one (retry if another thread set one).
  while ((current == 0 || ns < current) && !deadline_ns_.compare_exchange_weak(current, ns)) {
  }
}

void Context::SetTimeout(double seconds) {
  if (seconds <= 0) return;
  SetDeadline(std::chrono::steady_clock::now() +
              std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                  std::chrono::duration<double>(seconds)));
}

bool Context::ShouldStop() const {
  if (cancelled_.load(std::memory_order_relaxed)) return true;
  int64_t deadline = deadline_ns_.load(std::memory_order_relaxed);
  return deadline != 0 && NowNs() > deadline;
}

Status Context::StopStatus() const {
  if (cancelled_.load()) return Status(StatusCode::kCancelled, "the run was cancelled");
  int64_t deadline = deadline_ns_.load();
  if (deadline != 0 && NowNs() > deadline)
    return Status(StatusCode::kDeadlineExceeded, "the run passed its time limit");
  return Status::Ok();
}

void Context::ReportProgress(const Progress& progress) {
  std::lock_guard<std::mutex> lock(callback_mutex_);
  if (progress_) progress_(progress);
}

void Context::ReportFace(const FaceMesh& face) {
  std::lock_guard<std::mutex> lock(callback_mutex_);
  if (face_done_) face_done_(face);
}

}  // namespace rdmesh
