#pragma once
// A buffered output file with number formatting, and helpers shared by the mesh writers.

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// kIoError "cannot write 'path': reason".
Status WriteError(const std::string& path, const std::string& reason);

/// A file written through a 1 MiB buffer. Text numbers use the shortest form that reads back
/// to the same double. Not thread-safe; one writer per file.
class OutputFile {
 public:
  OutputFile() = default;
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile();

  /// Creates or truncates `path` (or, with `append`, writes on at its end); kIoError when it
  /// cannot be opened.
  Status Open(const std::string& path, bool append = false);
  /// Flushes and closes; kIoError when any write failed (disk full, ...).
  Status Close();

  void Text(std::string_view text);
  void Char(char c);
  /// A double in shortest round-trip form ("0.1", "1e-07").
  void Number(double value);
  /// A float in shortest round-trip form.
  void Number(float value);
  void Int(int64_t value);
  /// Raw little-endian bytes of a trivially copyable value (binary formats).
  template <typename T>
  void Binary(const T& value) {
    Text(std::string_view(reinterpret_cast<const char*>(&value), sizeof(T)));
  }

 private:
  void Flush();

  std::FILE* file_ = nullptr;
  std::string path_;
  std::string buffer_;
  bool failed_ = false;
};

/// Triangle `t` of `mesh`: its normal scaled by twice its area, outward (corners
/// counter-clockwise).
void TriangleAreaNormal(const Mesh& mesh, int64_t t, double normal[3]);

/// 3 floats per node of `result.mesh`: unit normals, the average of the exact surface normals of
/// the faces that share the node (result.faces[i].normals), or of the area-weighted triangle
/// normals where faces carry none.
std::vector<float> NodeNormals(const MeshResult& result);

}  // namespace rdmesh
