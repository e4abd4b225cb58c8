#include "writers/vtu_writer.h"

#include <cstdint>
#include <type_traits>

#include "writers/face_nodes.h"
#include "writers/output_file.h"

namespace rdmesh {

namespace {

// Writes values separated by spaces, `per_line` to a line.
template <typename T>
void WriteValues(const std::vector<T>& values, size_t per_line, OutputFile* out) {
  for (size_t i = 0; i < values.size(); ++i) {
    if constexpr (std::is_floating_point_v<T>) {
      out->Number(values[i]);
    } else {
      out->Int(values[i]);
    }
    out->Char((i + 1) % per_line == 0 ? '\n' : ' ');
  }
  if (values.size() % per_line != 0) out->Char('\n');
}

}  // namespace

Status WriteVtu(const MeshResult& result, const std::string& path) {
  const Mesh& mesh = result.mesh;
  int64_t triangles = mesh.triangle_count();
  const FaceNodes split = SplitNodesByFace(result);
  std::vector<double> points(3 * split.node.size());
  for (size_t i = 0; i < split.node.size(); ++i)
    for (int k = 0; k < 3; ++k) points[3 * i + k] = mesh.xyz[3 * split.node[i] + k];
  OutputFile out;
  Status opened = out.Open(path);
  if (!opened.ok()) return opened;
  out.Text(
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"");
  out.Int(split.vertex_count());
  out.Text("\" NumberOfCells=\"");
  out.Int(triangles);
  out.Text(
      "\">\n<PointData Normals=\"Normals\">\n"
      "<DataArray type=\"Float32\" Name=\"Normals\" NumberOfComponents=\"3\" format=\"ascii\">\n");
  WriteValues(split.normals, 3, &out);
  out.Text("</DataArray>\n<DataArray type=\"Int64\" Name=\"node_id\" format=\"ascii\">\n");
  WriteValues(split.node, 16, &out);
  out.Text(
      "</DataArray>\n</PointData>\n<CellData Scalars=\"face_id\">\n"
      "<DataArray type=\"Int32\" Name=\"face_id\" format=\"ascii\">\n");
  WriteValues(mesh.triangle_face, 16, &out);
  if (mesh.triangle_deviation.size() == static_cast<size_t>(triangles)) {
    out.Text("</DataArray>\n<DataArray type=\"Float64\" Name=\"deviation\" format=\"ascii\">\n");
    WriteValues(mesh.triangle_deviation, 8, &out);
  }
  out.Text(
      "</DataArray>\n</CellData>\n<Points>\n"
      "<DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n");
  WriteValues(points, 3, &out);
  out.Text(
      "</DataArray>\n</Points>\n<Cells>\n"
      "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
  WriteValues(split.triangles, 3, &out);
  out.Text("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
  for (int64_t t = 1; t <= triangles; ++t) {
    out.Int(3 * t);
    out.Char(t % 16 == 0 || t == triangles ? '\n' : ' ');
  }
  out.Text("</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
  for (int64_t t = 1; t <= triangles; ++t) out.Text(t % 16 == 0 || t == triangles ? "5\n" : "5 ");
  out.Text("</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
  return out.Close();
}

}  // namespace rdmesh
