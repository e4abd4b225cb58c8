#pragma once
// Reading a whole file under a size limit: the daemon reads server-side models and TLS files
// with it, the worker its spooled models.

#include <cstdint>
#include <string>

#include "rdmesh/status.h"

namespace rdmesh::server {

/// The file's bytes; kResourceExhausted when it is larger than `max_bytes`.
Result<std::string> ReadFileLimited(const std::string& path, uint64_t max_bytes);

}  // namespace rdmesh::server
