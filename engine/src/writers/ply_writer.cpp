#include "writers/ply_writer.h"

#include "writers/output_file.h"

namespace rdmesh {

Status WritePly(const MeshResult& result, const std::string& path) {
  const Mesh& mesh = result.mesh;
  std::vector<float> normals = NodeNormals(result);
  OutputFile out;
  Status opened = out.Open(path);
  if (!opened.ok()) return opened;
  out.Text("ply\nformat ascii 1.0\ncomment written by rdmesh\nelement vertex ");
  out.Int(mesh.node_count());
  out.Text(
      "\nproperty double x\nproperty double y\nproperty double z\n"
      "property float nx\nproperty float ny\nproperty float nz\nelement face ");
  out.Int(mesh.triangle_count());
  out.Text("\nproperty list uchar int vertex_indices\nproperty int face_id\nend_header\n");
  for (int64_t i = 0; i < mesh.node_count(); ++i) {
    for (int k = 0; k < 3; ++k) {
      out.Number(mesh.xyz[3 * i + k]);
      out.Char(' ');
    }
    for (int k = 0; k < 3; ++k) {
      out.Number(normals[3 * i + k]);
      out.Char(k < 2 ? ' ' : '\n');
    }
  }
  for (int64_t t = 0; t < mesh.triangle_count(); ++t) {
    out.Char('3');
    for (int k = 0; k < 3; ++k) {
      out.Char(' ');
      out.Int(mesh.triangles[3 * t + k]);
    }
    out.Char(' ');
    out.Int(mesh.triangle_face[t]);
    out.Char('\n');
  }
  return out.Close();
}

}  // namespace rdmesh
