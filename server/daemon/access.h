#pragma once
// Access control: the bearer token and the server-side file root.

#include <string>

#include "rdmesh/status.h"

namespace rdmesh::server {

/// The token in a token file: its content without surrounding whitespace. kIoError when the
/// file cannot be read, kInvalidArgument when it holds no token.
Result<std::string> ReadTokenFile(const std::string& path);

/// True when an "authorization" metadata value is "Bearer <token>" (constant-time compare).
bool BearerTokenMatches(const std::string& header_value, const std::string& token);

/// The canonical path of `requested` (relative to `root`, or absolute) when it names an existing
/// regular file under `root` after symlinks are resolved. kPermissionDenied for anything outside
/// the root (including "..", or symlinks leading out), kNotFound for a missing file.
Result<std::string> ResolveUnderRoot(const std::string& root, const std::string& requested);

}  // namespace rdmesh::server
