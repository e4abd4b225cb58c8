#pragma once
// Length-prefixed protobuf messages on a stream socket: the wire of the daemon <-> worker protocol
// (proto/rdmesh/internal/worker.proto). A frame is a 4-byte little-endian length, then the
// serialised message.

#include <google/protobuf/message_lite.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace rdmesh::server {

/// The largest frame either side accepts (a FaceMesh event is at most ~1 MiB).
constexpr uint32_t kMaxFrameBytes = 64u << 20;

/// Writes one frame; false when the peer is gone (or the message does not serialise). Never
/// raises SIGPIPE. Not thread-safe for one fd: one writer at a time.
bool WriteFrame(int fd, const google::protobuf::MessageLite& message);

enum class FrameRead { kMessage, kTimeout, kClosed, kCorrupt };

/// Reads one frame into `message`. Waits up to `timeout_ms` for its first byte (-1 = forever);
/// once a frame has begun, reads it to its end. kClosed on end of file or a read error, kCorrupt
/// when the length passes kMaxFrameBytes or the bytes do not parse.
FrameRead ReadFrame(int fd, google::protobuf::MessageLite* message, int timeout_ms);

/// Reads frames from one fd through a buffer: one read() brings in as many frames as the socket
/// holds, so a stream of small frames (a worker's per-face events) costs a system call per
/// buffer-full instead of a poll and two reads per frame. Use one reader per fd for the fd's
/// whole life: bytes read ahead belong to the frames that follow. Same results as ReadFrame.
class FrameReader {
 public:
  explicit FrameReader(int fd) : fd_(fd) {}

  /// As ReadFrame: waits up to `timeout_ms` (-1 = forever) when no frame has begun; a frame
  /// that has begun is read to its end.
  FrameRead Read(google::protobuf::MessageLite* message, int timeout_ms);

 private:
  static constexpr std::size_t kInitialBuffer = 256 << 10;
  static constexpr std::size_t kMinRead = 64 << 10;  // room for one read() at least

  /// Reads what the fd holds (at least one byte, blocking) after end_, first making room for a
  /// frame of `need` bytes from begin_; false on end of file or an error.
  bool Fill(std::size_t need);

  int fd_;
  std::vector<char> buffer_;  // its size is the capacity; bytes read, not yet used: [begin_, end_)
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
};

}  // namespace rdmesh::server
