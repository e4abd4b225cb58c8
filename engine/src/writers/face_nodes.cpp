#include "writers/face_nodes.h"

#include <cmath>
#include <unordered_map>

#include "writers/output_file.h"

namespace rdmesh {

namespace {

uint64_t Key(int32_t face, int64_t node) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(face)) << 32) |
         static_cast<uint64_t>(static_cast<uint32_t>(node));
}

}  // namespace

FaceNodes SplitNodesByFace(const MeshResult& result) {
  const Mesh& mesh = result.mesh;
  const int64_t triangles = mesh.triangle_count();
  FaceNodes split;
  split.triangles.resize(3 * triangles);
  std::unordered_map<uint64_t, int64_t> vertex_of;
  vertex_of.reserve(mesh.xyz.size() / 2);
  for (int64_t t = 0; t < triangles; ++t) {
    const int32_t face = mesh.triangle_face[t];
    for (int k = 0; k < 3; ++k) {
      const int32_t node = mesh.triangles[3 * t + k];
      auto [it, added] = vertex_of.try_emplace(Key(face, node), split.vertex_count());
      if (added) split.node.push_back(node);
      split.triangles[3 * t + k] = it->second;
    }
  }

  const int64_t vertices = split.vertex_count();
  std::vector<double> sum(3 * vertices, 0.0);
  std::vector<bool> exact(vertices, false);
  for (const FaceMesh& face : result.faces) {
    if (face.normals.size() != face.xyz.size() || face.global_ids.size() * 3 != face.xyz.size())
      continue;
    for (size_t i = 0; i < face.global_ids.size(); ++i) {
      auto found = vertex_of.find(Key(face.face_id, face.global_ids[i]));
      if (found == vertex_of.end()) continue;
      for (int k = 0; k < 3; ++k) sum[3 * found->second + k] = face.normals[3 * i + k];
      exact[found->second] = true;
    }
  }
  for (int64_t t = 0; t < triangles; ++t) {
    const int64_t* v = &split.triangles[3 * t];
    double normal[3];  // twice the area, outward
    TriangleAreaNormal(mesh, t, normal);
    for (int corner = 0; corner < 3; ++corner) {
      if (exact[v[corner]]) continue;
      for (int k = 0; k < 3; ++k) sum[3 * v[corner] + k] += normal[k];
    }
  }
  split.normals.assign(3 * vertices, 0.0f);
  for (int64_t i = 0; i < vertices; ++i) {
    const double* s = &sum[3 * i];
    const double length = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    if (length == 0.0) continue;
    for (int k = 0; k < 3; ++k) split.normals[3 * i + k] = static_cast<float>(s[k] / length);
  }
  return split;
}

}  // namespace rdmesh
