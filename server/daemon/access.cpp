#include "daemon/access.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

namespace rdmesh::server {
namespace fs = std::filesystem;

Result<std::string> ReadTokenFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status(StatusCode::kIoError, "cannot read the token file " + path);
  std::ostringstream content;
  content << in.rdbuf();
  std::string token = content.str();
  const char* kSpace = " \t\r\n";
  const std::size_t begin = token.find_first_not_of(kSpace);
  if (begin == std::string::npos) {
    return Status(StatusCode::kInvalidArgument, "the token file " + path + " is empty");
  }
  token = token.substr(begin, token.find_last_not_of(kSpace) - begin + 1);
  return token;
}

bool BearerTokenMatches(const std::string& header_value, const std::string& token) {
  const std::string expected = "Bearer " + token;
  // Compare every byte whatever the first difference, so timing tells nothing about the token.
  unsigned char diff = header_value.size() == expected.size() ? 0 : 1;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const unsigned char got = i < header_value.size() ? header_value[i] : 0;
    diff |= static_cast<unsigned char>(got ^ static_cast<unsigned char>(expected[i]));
  }
  return diff == 0 && !token.empty();
}

Result<std::string> ResolveUnderRoot(const std::string& root, const std::string& requested) {
  std::error_code error;
  const fs::path root_path = fs::canonical(root, error);
  if (error) return Status(StatusCode::kInternal, "the data root " + root + " is not usable");
  if (requested.empty()) return Status(StatusCode::kInvalidArgument, "empty server_path");
  fs::path path(requested);
  if (path.is_relative()) path = root_path / path;
  const fs::path resolved = fs::weakly_canonical(path, error);
  if (error) return Status(StatusCode::kNotFound, "cannot resolve " + requested);
  const fs::path relative = resolved.lexically_relative(root_path);
  if (relative.empty() || *relative.begin() == "..") {
    return Status(StatusCode::kPermissionDenied,
                  "server_path " + requested + " lies outside the server's data root");
  }
  if (!fs::exists(resolved, error)) {
    return Status(StatusCode::kNotFound, "no file " + requested + " under the data root");
  }
  if (!fs::is_regular_file(resolved, error)) {
    return Status(StatusCode::kInvalidArgument, requested + " is not a regular file");
  }
  return resolved.string();
}

}  // namespace rdmesh::server
