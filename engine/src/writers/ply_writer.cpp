#include "writers/ply_writer.h"

#include <cstdint>

#include "writers/output_file.h"

namespace rdmesh {

Status WritePly(const MeshResult& result, const std::string& path) {
  static_assert(sizeof(float) == 4 && sizeof(double) == 8, "PLY needs IEEE float and double");
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "binary_little_endian is written as is");
  const Mesh& mesh = result.mesh;
  std::vector<float> normals = NodeNormals(result);
  OutputFile out;
  Status opened = out.Open(path);
  if (!opened.ok()) return opened;
  out.Text("ply\nformat binary_little_endian 1.0\ncomment written by rdmesh\nelement vertex ");
  out.Int(mesh.node_count());
  out.Text(
      "\nproperty double x\nproperty double y\nproperty double z\n"
      "property float nx\nproperty float ny\nproperty float nz\nelement face ");
  out.Int(mesh.triangle_count());
  out.Text("\nproperty list uchar int vertex_indices\nproperty int face_id\nend_header\n");
  for (int64_t i = 0; i < mesh.node_count(); ++i) {
    for (int k = 0; k < 3; ++k) out.Binary(mesh.xyz[3 * i + k]);
    for (int k = 0; k < 3; ++k) out.Binary(normals[3 * i + k]);
  }
  for (int64_t t = 0; t < mesh.triangle_count(); ++t) {
    out.Binary(static_cast<uint8_t>(3));
    for (int k = 0; k < 3; ++k) out.Binary(static_cast<int32_t>(mesh.triangles[3 * t + k]));
    out.Binary(static_cast<int32_t>(mesh.triangle_face[t]));
  }
  return out.Close();
}

}  // namespace rdmesh
