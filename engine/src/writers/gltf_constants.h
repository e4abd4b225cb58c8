#pragma once
// The glTF 2.0 numbers both .glb writers use (gltf_ids.cpp, gltf_compress.cpp), as the
// specification gives them: accessor component types, buffer view targets, primitive modes and
// the GLB chunk types.

#include <cstdint>

namespace rdmesh::gltf {

inline constexpr int kByte = 5120;
inline constexpr int kUnsignedByte = 5121;
inline constexpr int kShort = 5122;
inline constexpr int kUnsignedShort = 5123;
inline constexpr int kUnsignedInt = 5125;
inline constexpr int kFloat = 5126;
inline constexpr int kArrayBuffer = 34962;
inline constexpr int kElementArrayBuffer = 34963;
inline constexpr int kTriangles = 4;
inline constexpr int kLines = 1;
inline constexpr uint32_t kJsonChunk = 0x4E4F534A;  // "JSON"
inline constexpr uint32_t kBinChunk = 0x004E4942;   // "BIN\0"

}  // namespace rdmesh::gltf
