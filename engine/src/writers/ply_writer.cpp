#include "writers/ply_writer.h"

#include "writers/face_nodes.h"
#include "writers/output_file.h"

namespace rdmesh {

Status WritePly(const MeshResult& result, const std::string& path) {
  const Mesh& mesh = result.mesh;
  const FaceNodes split = SplitNodesByFace(result);
  OutputFile out;
  Status opened = out.Open(path);
  if (!opened.ok()) return opened;
  out.Text("ply\nformat ascii 1.0\ncomment written by rdmesh\nelement vertex ");
  out.Int(split.vertex_count());
  out.Text(
      "\nproperty double x\nproperty double y\nproperty double z\n"
      "property float nx\nproperty float ny\nproperty float nz\nproperty int node_id\n"
      "element face ");
  out.Int(mesh.triangle_count());
  const bool deviation =
      mesh.triangle_deviation.size() == static_cast<size_t>(mesh.triangle_count());
  out.Text("\nproperty list uchar int vertex_indices\nproperty int face_id\n");
  if (deviation) out.Text("property double deviation\n");
  out.Text("end_header\n");
  for (int64_t i = 0; i < split.vertex_count(); ++i) {
    const int64_t node = split.node[i];
    for (int k = 0; k < 3; ++k) {
      out.Number(mesh.xyz[3 * node + k]);
      out.Char(' ');
    }
    for (int k = 0; k < 3; ++k) {
      out.Number(split.normals[3 * i + k]);
      out.Char(' ');
    }
    out.Int(node);
    out.Char('\n');
  }
  for (int64_t t = 0; t < mesh.triangle_count(); ++t) {
    out.Char('3');
    for (int k = 0; k < 3; ++k) {
      out.Char(' ');
      out.Int(split.triangles[3 * t + k]);
    }
    out.Char(' ');
    out.Int(mesh.triangle_face[t]);
    if (deviation) {
      out.Char(' ');
      out.Number(mesh.triangle_deviation[t]);
    }
    out.Char('\n');
  }
  return out.Close();
}

}  // namespace rdmesh
