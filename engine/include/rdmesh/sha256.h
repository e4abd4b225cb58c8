#pragma once
// Content hashes: the ids of models in the service and the keys of the persistent model store.

#include <string>
#include <string_view>

namespace rdmesh {

/// SHA-256 of `bytes` (FIPS 180-4) as 64 lower-case hex digits. Thread-safe.
std::string Sha256Hex(std::string_view bytes);

/// True for a string of exactly 64 lower-case hex digits.
bool IsSha256Hex(std::string_view id);

}  // namespace rdmesh
