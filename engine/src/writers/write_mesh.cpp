// WriteMesh: checks the mesh and picks the writer from the file extension.

#include <Standard_Failure.hxx>
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

#include "model/model.h"
#include "model/xcaf_api.h"
#include "rdmesh/engine.h"
#include "writers/msh_writer.h"
#include "writers/output_file.h"
#include "writers/ply_writer.h"
#include "writers/stl_writer.h"
#include "writers/vtu_writer.h"

namespace rdmesh {

namespace {

// The arrays agree in size and every index is in range.
Status CheckMesh(const Model& model, const Mesh& mesh) {
  if (mesh.xyz.size() % 3 != 0 || mesh.triangles.size() % 3 != 0 ||
      mesh.triangle_face.size() != static_cast<size_t>(mesh.triangle_count()))
    return Status(StatusCode::kInternal, "inconsistent mesh arrays");
  int64_t nodes = mesh.node_count();
  for (int32_t node : mesh.triangles)
    if (node < 0 || node >= nodes)
      return Status(StatusCode::kInternal, "a triangle refers to node " + std::to_string(node));
  for (int32_t face : mesh.triangle_face)
    if (face < 1 || face > model.face_count())
      return Status(StatusCode::kInternal, "a triangle has face id " + std::to_string(face));
  return Status::Ok();
}

Status CheckEdges(const Model& model, const Mesh& mesh, const std::vector<EdgeLine>& edges) {
  for (const EdgeLine& line : edges) {
    if (line.edge_id < 1 || line.edge_id > model.edge_count())
      return Status(StatusCode::kInternal,
                    "an edge line has edge id " + std::to_string(line.edge_id));
    for (int32_t node : line.nodes)
      if (node < 0 || node >= mesh.node_count())
        return Status(StatusCode::kInternal, "edge line " + std::to_string(line.edge_id) +
                                                 " refers to node " + std::to_string(node));
  }
  return Status::Ok();
}

std::string Extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// `edges` are the lines to write (empty when not asked for).
Status Dispatch(const Model& model, const MeshResult& result, const std::vector<EdgeLine>& edges,
                const WriteOptions& options, const std::string& path) {
  std::string ext = Extension(path);
  if (ext == ".msh") return WriteMsh(model, result, edges, options.msh_parametric, path);
  if (ext == ".stl") return WriteStl(result, path);
  if (ext == ".obj" || ext == ".glb") {
    // Both write through the model's XCAF document (names, colours, the assembly tree).
    Result<const XcafApi*> xcaf = Xcaf();
    if (!xcaf.ok()) return xcaf.status();
    if (ext == ".obj") return (*xcaf)->write_obj(model, result, edges, path);
    return (*xcaf)->write_glb(model, result, edges, options.compress, path);
  }
  if (ext == ".ply") return WritePly(result, path);
  if (ext == ".vtu") return WriteVtu(result, path);
  std::string supported;
  for (const std::string& format : SupportedOutputFormats())
    supported += (supported.empty() ? "" : ", ") + format;
  return Status(StatusCode::kInvalidArgument, "cannot write '" + path + "': unknown format '" +
                                                  ext + "' (supported: " + supported + ")");
}

}  // namespace

std::vector<std::string> SupportedOutputFormats() {
  return {".msh", ".stl", ".obj", ".ply", ".vtu", ".glb"};
}

Status WriteMesh(const Model& model, const MeshResult& result, const std::string& path,
                 const WriteOptions& options) {
  Status checked = CheckMesh(model, result.mesh);
  if (!checked.ok()) return checked;
  const std::string ext = Extension(path);
  const bool edges_wanted = options.edges && (ext == ".msh" || ext == ".obj" || ext == ".glb");
  try {
    std::vector<EdgeLine> derived;
    if (edges_wanted && result.edges.empty() && result.mesh.triangle_count() > 0) {
      Result<std::vector<EdgeLine>> built = BuildEdgeLines(model, result.mesh);
      if (!built.ok()) return built.status();
      derived = std::move(*built);
    }
    const std::vector<EdgeLine>& edges =
        edges_wanted && !result.edges.empty() ? result.edges : derived;  // derived: maybe none
    checked = CheckEdges(model, result.mesh, edges);
    if (!checked.ok()) return checked;
    return Dispatch(model, result, edges, options, path);
  } catch (const Standard_Failure& failure) {
    return WriteError(path, failure.GetMessageString());
  } catch (const std::bad_alloc&) {
    return Status(StatusCode::kResourceExhausted, "out of memory writing '" + path + "'");
  } catch (const std::exception& e) {
    return WriteError(path, e.what());
  }
}

}  // namespace rdmesh
