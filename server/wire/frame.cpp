#include "wire/frame.h"

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <string>

namespace rdmesh::server {
namespace {

/// Waits up to `timeout_ms` (-1 = forever) for `fd` to be readable: kMessage when it is.
FrameRead WaitReadable(int fd, int timeout_ms) {
  pollfd wait{fd, POLLIN, 0};
  while (true) {
    const int ready = poll(&wait, 1, timeout_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) return FrameRead::kClosed;
    return ready == 0 ? FrameRead::kTimeout : FrameRead::kMessage;
  }
}

uint32_t FrameSize(const unsigned char* header) {
  return static_cast<uint32_t>(header[0]) | static_cast<uint32_t>(header[1]) << 8 |
         static_cast<uint32_t>(header[2]) << 16 | static_cast<uint32_t>(header[3]) << 24;
}

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
  const FrameRead ready = WaitReadable(fd, timeout_ms);
  if (ready != FrameRead::kMessage) return ready;
  unsigned char header[4];
  if (!ReadAll(fd, reinterpret_cast<char*>(header), 4)) return FrameRead::kClosed;
  const uint32_t size = FrameSize(header);
  if (size > kMaxFrameBytes) return FrameRead::kCorrupt;
  std::string body(size, '\0');
  if (!ReadAll(fd, body.data(), size)) return FrameRead::kClosed;
  if (!message->ParseFromString(body)) return FrameRead::kCorrupt;
  return FrameRead::kMessage;
}

bool FrameReader::Fill(std::size_t need) {
  if (begin_ == end_) begin_ = end_ = 0;
  if (buffer_.size() - begin_ < need || buffer_.size() - end_ < kMinRead) {
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(begin_));
    end_ -= begin_;
    begin_ = 0;
    buffer_.resize(std::max({buffer_.size(), need, end_ + kMinRead, kInitialBuffer}));
  }
  ssize_t got;
  do {
    got = read(fd_, buffer_.data() + end_, buffer_.size() - end_);
  } while (got < 0 && errno == EINTR);
  if (got <= 0) return false;
  end_ += static_cast<std::size_t>(got);
  return true;
}

FrameRead FrameReader::Read(google::protobuf::MessageLite* message, int timeout_ms) {
  if (begin_ == end_) {  // nothing buffered: wait for the first byte
    const FrameRead ready = WaitReadable(fd_, timeout_ms);
    if (ready != FrameRead::kMessage) return ready;
    if (!Fill(4)) return FrameRead::kClosed;
  }
  while (end_ - begin_ < 4) {
    if (!Fill(4)) return FrameRead::kClosed;
  }
  const uint32_t size = FrameSize(reinterpret_cast<const unsigned char*>(buffer_.data() + begin_));
  if (size > kMaxFrameBytes) return FrameRead::kCorrupt;
  const std::size_t frame = 4 + static_cast<std::size_t>(size);
  while (end_ - begin_ < frame) {
    if (!Fill(frame)) return FrameRead::kClosed;
  }
  const char* body = buffer_.data() + begin_ + 4;
  begin_ += frame;
  if (!message->ParseFromArray(body, static_cast<int>(size))) return FrameRead::kCorrupt;
  return FrameRead::kMessage;
}

}  // namespace rdmesh::server
