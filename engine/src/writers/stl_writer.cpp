#include "writers/stl_writer.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "writers/output_file.h"

namespace rdmesh {

Status WriteStl(const MeshResult& result, const std::string& path) {
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "STL is little-endian");
  const Mesh& mesh = result.mesh;
  if (mesh.triangle_count() > std::numeric_limits<uint32_t>::max())
    return WriteError(path, "too many triangles for STL");
  OutputFile out;
  Status opened = out.Open(path);
  if (!opened.ok()) return opened;
  std::string header = "binary STL written by rdmesh";
  header.resize(80, ' ');
  out.Text(header);
  out.Binary(static_cast<uint32_t>(mesh.triangle_count()));
  for (int64_t t = 0; t < mesh.triangle_count(); ++t) {
    const double* p[3];
    for (int k = 0; k < 3; ++k) p[k] = &mesh.xyz[3 * mesh.triangles[3 * t + k]];
    double u[3], v[3];
    for (int k = 0; k < 3; ++k) {
      u[k] = p[1][k] - p[0][k];
      v[k] = p[2][k] - p[0][k];
    }
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (double c : n) out.Binary(static_cast<float>(length > 0.0 ? c / length : 0.0));
    for (int corner = 0; corner < 3; ++corner)
      for (int k = 0; k < 3; ++k) out.Binary(static_cast<float>(p[corner][k]));
    out.Binary(static_cast<uint16_t>(0));
  }
  return out.Close();
}

}  // namespace rdmesh
