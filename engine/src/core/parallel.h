#pragma once
// The engine's one parallel loop. Release builds run it on TBB. Under ThreadSanitizer it runs on
// std::threads that take indices from an atomic counter: Debian's TBB is not instrumented, so
// TSan cannot see its fork and join, while it sees thread creation, joins and atomics. Either way
// the bodies run concurrently, so a race between them is a race in both.

#include <functional>
#include <memory>

namespace rdmesh {

/// How a loop's indices are handed out.
enum class Partition {
  kAuto,        ///< ranges of indices, sized by the scheduler (cheap bodies: edges)
  kOnePerTask,  ///< one index at a time (expensive, uneven bodies: faces)
};

/// Runs loops on up to `threads` threads (0: all cores). Not copyable; one per stage.
class ParallelRunner {
 public:
  explicit ParallelRunner(int threads);
  ~ParallelRunner();
  ParallelRunner(const ParallelRunner&) = delete;
  ParallelRunner& operator=(const ParallelRunner&) = delete;

  /// body(i) for every i in [begin, end), concurrently, in no set order; returns when all are
  /// done. The body must not throw.
  void For(int begin, int end, const std::function<void(int)>& body,
           Partition partition = Partition::kAuto) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rdmesh
