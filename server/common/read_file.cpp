#include "common/read_file.h"

#include <filesystem>
#include <fstream>
#include <system_error>

namespace rdmesh::server {
namespace fs = std::filesystem;

Result<std::string> ReadFileLimited(const std::string& path, uint64_t max_bytes) {
  std::error_code error;
  const uintmax_t size = fs::file_size(path, error);
  if (error) return Status(StatusCode::kIoError, "cannot stat " + path);
  if (size > max_bytes) {
    return Status(StatusCode::kResourceExhausted,
                  "the model is " + std::to_string(size) + " bytes, more than the server's " +
                      "--max-model-bytes of " + std::to_string(max_bytes));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status(StatusCode::kIoError, "cannot open " + path);
  std::string bytes(size, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  if (static_cast<uintmax_t>(in.gcount()) != size) {
    return Status(StatusCode::kIoError, "short read of " + path);
  }
  return bytes;
}

}  // namespace rdmesh::server
