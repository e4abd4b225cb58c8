#include "writers/output_file.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>

namespace rdmesh {

namespace {
constexpr size_t kBufferSize = 1 << 20;
}  // namespace

Status WriteError(const std::string& path, const std::string& reason) {
  return Status(StatusCode::kIoError, "cannot write '" + path + "': " + reason);
}

OutputFile::~OutputFile() {
  if (file_ != nullptr) std::fclose(file_);
}

Status OutputFile::Open(const std::string& path, bool append) {
  path_ = path;
  file_ = std::fopen(path.c_str(), append ? "ab" : "wb");
  if (file_ == nullptr) return WriteError(path, std::strerror(errno));
  buffer_.reserve(kBufferSize + 64);
  return Status::Ok();
}

Status OutputFile::Close() {
  Flush();
  int error = 0;
  if (file_ != nullptr && std::fclose(file_) != 0) error = errno;
  file_ = nullptr;
  if (error != 0) return WriteError(path_, std::strerror(error));
  if (failed_) return WriteError(path_, "write failed (disk full?)");
  return Status::Ok();
}

void OutputFile::Flush() {
  if (file_ != nullptr && !buffer_.empty() &&
      std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size())
    failed_ = true;
  buffer_.clear();
}

void OutputFile::Text(std::string_view text) {
  if (buffer_.size() + text.size() > kBufferSize) Flush();
  if (text.size() > kBufferSize) {
    if (file_ != nullptr && std::fwrite(text.data(), 1, text.size(), file_) != text.size())
      failed_ = true;
    return;
  }
  buffer_.append(text.data(), text.size());
}

void OutputFile::Char(char c) {
  if (buffer_.size() + 1 > kBufferSize) Flush();
  buffer_.push_back(c);
}

void OutputFile::Number(double value) {
  char text[32];
  auto [end, error] = std::to_chars(text, text + sizeof(text), value);
  Text(std::string_view(text, error == std::errc() ? end - text : 0));
}

void OutputFile::Number(float value) {
  char text[24];
  auto [end, error] = std::to_chars(text, text + sizeof(text), value);
  Text(std::string_view(text, error == std::errc() ? end - text : 0));
}

void OutputFile::Int(int64_t value) {
  char text[24];
  auto [end, error] = std::to_chars(text, text + sizeof(text), value);
  Text(std::string_view(text, end - text));
}

void TriangleAreaNormal(const Mesh& mesh, int64_t t, double normal[3]) {
  const int32_t* v = &mesh.triangles[3 * t];
  const double* a = &mesh.xyz[3 * static_cast<int64_t>(v[0])];
  const double* b = &mesh.xyz[3 * static_cast<int64_t>(v[1])];
  const double* c = &mesh.xyz[3 * static_cast<int64_t>(v[2])];
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  normal[0] = u[1] * w[2] - u[2] * w[1];
  normal[1] = u[2] * w[0] - u[0] * w[2];
  normal[2] = u[0] * w[1] - u[1] * w[0];
}

std::vector<float> NodeNormals(const MeshResult& result) {
  const Mesh& mesh = result.mesh;
  int64_t nodes = mesh.node_count();
  std::vector<double> sum(3 * nodes, 0.0);
  std::vector<bool> has_face_normal(nodes, false);
  for (const FaceMesh& face : result.faces) {
    if (face.normals.size() != face.xyz.size() || face.global_ids.size() * 3 != face.xyz.size())
      continue;
    for (size_t i = 0; i < face.global_ids.size(); ++i) {
      int64_t node = face.global_ids[i];
      if (node < 0 || node >= nodes) continue;
      for (int k = 0; k < 3; ++k) sum[3 * node + k] += face.normals[3 * i + k];
      has_face_normal[node] = true;
    }
  }
  for (int64_t t = 0; t < mesh.triangle_count(); ++t) {
    const int32_t* v = &mesh.triangles[3 * t];
    double n[3];
    TriangleAreaNormal(mesh, t, n);
    for (int corner = 0; corner < 3; ++corner) {
      if (has_face_normal[v[corner]]) continue;
      for (int k = 0; k < 3; ++k) sum[3 * v[corner] + k] += n[k];
    }
  }
  std::vector<float> normals(3 * nodes, 0.0f);
  for (int64_t i = 0; i < nodes; ++i) {
    double length = std::sqrt(sum[3 * i] * sum[3 * i] + sum[3 * i + 1] * sum[3 * i + 1] +
                              sum[3 * i + 2] * sum[3 * i + 2]);
    if (length == 0.0) continue;
    for (int k = 0; k < 3; ++k) normals[3 * i + k] = static_cast<float>(sum[3 * i + k] / length);
  }
  return normals;
}

}  // namespace rdmesh
