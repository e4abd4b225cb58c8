#include "writers/obj_writer.h"

#include <Message_ProgressRange.hxx>
#include <RWObj_CafWriter.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_IndexedDataMapOfStringString.hxx>
#include <fstream>

#include "writers/face_triangulations.h"
#include "writers/output_file.h"

namespace rdmesh {

namespace {

// How many v, vn and vt records an OBJ file holds.
struct ObjRecords {
  int64_t v = 0, vn = 0, vt = 0;
};

ObjRecords CountRecords(const std::string& path) {
  ObjRecords records;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.size() < 2 || line[0] != 'v') continue;
    if (line[1] == ' ') ++records.v;
    if (line[1] == 'n' && line.size() > 2 && line[2] == ' ') ++records.vn;
    if (line[1] == 't' && line.size() > 2 && line[2] == ' ') ++records.vt;
  }
  return records;
}

// Appends the "edges" group: vertex records for the lines' nodes, then one `l` per line.
Status AppendEdgeLines(const MeshResult& result, const std::vector<EdgeLine>& edges,
                       const std::string& path) {
  const Mesh& mesh = result.mesh;
  std::vector<int64_t> index(mesh.node_count(), 0);  // 1-based within the group; 0 = not yet
  std::vector<int32_t> used;
  for (const EdgeLine& line : edges) {
    if (line.degenerate || line.nodes.size() < 2) continue;
    for (int32_t node : line.nodes)
      if (index[node] == 0) {
        used.push_back(node);
        index[node] = static_cast<int64_t>(used.size());
      }
  }
  if (used.empty()) return Status::Ok();
  const ObjRecords before = CountRecords(path);
  const bool normals = before.vn > 0 && before.vn == before.v;
  const bool texture = before.vt > 0 && before.vt == before.v;
  std::vector<float> node_normals;
  if (normals) node_normals = NodeNormals(result);

  OutputFile out;
  Status opened = out.Open(path, /*append=*/true);
  if (!opened.ok()) return opened;
  out.Text("g edges\n");
  for (int32_t node : used) {
    out.Text("v");
    for (int k = 0; k < 3; ++k) {
      out.Char(' ');
      out.Number(mesh.xyz[3 * static_cast<int64_t>(node) + k]);
    }
    out.Char('\n');
    if (normals) {
      out.Text("vn");
      for (int k = 0; k < 3; ++k) {
        out.Char(' ');
        out.Number(node_normals[3 * static_cast<int64_t>(node) + k]);
      }
      out.Char('\n');
    }
    if (texture) out.Text("vt 0 0\n");
  }
  for (const EdgeLine& line : edges) {
    if (line.degenerate || line.nodes.size() < 2) continue;
    out.Char('l');
    for (int32_t node : line.nodes) {
      out.Char(' ');
      out.Int(before.v + index[node]);
    }
    out.Char('\n');
  }
  return out.Close();
}

}  // namespace

Status WriteObj(const Model& model, const MeshResult& result, const std::vector<EdgeLine>& edges,
                const std::string& path) {
  if (result.mesh.triangle_count() == 0) {  // RWObj_CafWriter refuses to write nothing
    OutputFile out;
    Status opened = out.Open(path);
    if (!opened.ok()) return opened;
    out.Text("# written by rdmesh: no faces were meshed\n");
    return out.Close();
  }
  try {
    Handle(TDocStd_Document) doc = DocumentForWriting(model);
    ScopedFaceTriangulations lent(model, result);
    RWObj_CafWriter writer(path.c_str());
    TColStd_IndexedDataMapOfStringString file_info;
    file_info.Add("generator", "rdmesh");
    if (!writer.Perform(doc, file_info, Message_ProgressRange()))
      return WriteError(path, "the OBJ writer failed (directory missing or not writable?)");
  } catch (const Standard_Failure& failure) {
    return WriteError(path, std::string("the OBJ writer failed: ") + failure.GetMessageString());
  }
  return AppendEdgeLines(result, edges, path);
}

}  // namespace rdmesh
