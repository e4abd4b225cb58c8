#include "rdmesh/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace rdmesh {

Status WriteFileAtomically(const std::string& path, const std::string& partial,
                           const std::string& bytes, mode_t mode, bool durable) {
  const int fd = open(partial.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, mode);
  bool ok = fd >= 0;
  std::size_t written = 0;
  while (ok && written < bytes.size()) {
    const ssize_t n = write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) written += static_cast<std::size_t>(n);
  }
  const int error = errno;
  if (fd >= 0) {
    if (durable) ok = ok && fsync(fd) == 0;
    ok = close(fd) == 0 && ok;
  }
  if (ok) ok = std::rename(partial.c_str(), path.c_str()) == 0;
  if (!ok) {
    unlink(partial.c_str());
    return Status(StatusCode::kIoError, std::strerror(error));
  }
  return Status::Ok();
}

}  // namespace rdmesh
