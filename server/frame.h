#pragma once
// Length-prefixed protobuf messages on a stream socket: the wire of the daemon <-> worker protocol
// (proto/rdmesh/internal/worker.proto). A frame is a 4-byte little-endian length, then the
// serialised message.

#include <google/protobuf/message_lite.h>

#include <cstdint>

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

}  // namespace rdmesh::server
