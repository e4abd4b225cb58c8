#include "frame.h"

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <string>

namespace rdmesh::server {
namespace {

bool SendAll(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t sent = send(fd, data, size, MSG_NOSIGNAL);
    if (sent < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += sent;
    size -= static_cast<std::size_t>(sent);
  }
  return true;
}

/// Reads exactly `size` bytes; false on end of file or an error.
bool ReadAll(int fd, char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t got = read(fd, data, size);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    data += got;
    size -= static_cast<std::size_t>(got);
  }
  return true;
}

}  // namespace

bool WriteFrame(int fd, const google::protobuf::MessageLite& message) {
  const std::size_t size = message.ByteSizeLong();
  if (size > kMaxFrameBytes) return false;
  std::string buffer(4 + size, '\0');
  for (int i = 0; i < 4; ++i) buffer[i] = static_cast<char>((size >> (8 * i)) & 0xff);
  if (!message.SerializeToArray(buffer.data() + 4, static_cast<int>(size))) return false;
  return SendAll(fd, buffer.data(), buffer.size());
}

FrameRead ReadFrame(int fd, google::protobuf::MessageLite* message, int timeout_ms) {
  pollfd wait{fd, POLLIN, 0};
  while (true) {
    const int ready = poll(&wait, 1, timeout_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) return FrameRead::kClosed;
    if (ready == 0) return FrameRead::kTimeout;
    break;
  }
  unsigned char header[4];
  if (!ReadAll(fd, reinterpret_cast<char*>(header), 4)) return FrameRead::kClosed;
  const uint32_t size = static_cast<uint32_t>(header[0]) | static_cast<uint32_t>(header[1]) << 8 |
                        static_cast<uint32_t>(header[2]) << 16 |
                        static_cast<uint32_t>(header[3]) << 24;
  if (size > kMaxFrameBytes) return FrameRead::kCorrupt;
  std::string body(size, '\0');
  if (!ReadAll(fd, body.data(), size)) return FrameRead::kClosed;
  if (!message->ParseFromString(body)) return FrameRead::kCorrupt;
  return FrameRead::kMessage;
}

}  // namespace rdmesh::server
