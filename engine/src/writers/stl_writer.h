#pragma once

#include <string>

#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Writes `result.mesh` as binary STL: an 80-byte header, the triangle count, then per triangle
/// its unit facet normal (outward, from the counter-clockwise corners) and three corners, all
/// float32 in model units. kIoError naming the path on failure.
Status WriteStl(const MeshResult& result, const std::string& path);

}  // namespace rdmesh
