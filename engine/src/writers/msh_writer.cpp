#include "writers/msh_writer.h"

#include <BRepBndLib.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <algorithm>
#include <numeric>
#include <utility>
#include <vector>

#include "writers/output_file.h"

namespace rdmesh {

namespace {

void WriteBox(const TopoDS_Shape& shape, OutputFile* out) {
  Bnd_Box box;
  BRepBndLib::Add(shape, box, /*useTriangulation=*/false);
  double b[6] = {0, 0, 0, 0, 0, 0};
  if (!box.IsVoid()) box.Get(b[0], b[1], b[2], b[3], b[4], b[5]);
  for (double value : b) {
    out->Number(value);
    out->Char(' ');
  }
}

// Signed bounding-entity tags, written as "count tag tag ...".
void WriteBounds(const std::vector<int>& tags, OutputFile* out) {
  out->Int(static_cast<int64_t>(tags.size()));
  for (int tag : tags) {
    out->Char(' ');
    out->Int(tag);
  }
  out->Char('\n');
}

void WriteEntities(const Model& model, OutputFile* out) {
  out->Text("$Entities\n");
  out->Int(model.vertices.Extent());
  out->Char(' ');
  out->Int(model.edge_count());
  out->Char(' ');
  out->Int(model.face_count());
  out->Text(" 0\n");
  for (int v = 1; v <= model.vertices.Extent(); ++v) {
    gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(model.vertices(v)));
    out->Int(v);
    for (double c : {p.X(), p.Y(), p.Z()}) {
      out->Char(' ');
      out->Number(c);
    }
    out->Text(" 0\n");  // no physical tags
  }
  for (int e = 1; e <= model.edge_count(); ++e) {
    out->Int(e);
    out->Char(' ');
    WriteBox(model.edge(e), out);
    out->Text("0 ");
    TopoDS_Vertex first, last;
    TopExp::Vertices(model.edge(e), first, last, /*CumOri=*/true);
    std::vector<int> bounds;
    if (!first.IsNull()) bounds.push_back(model.vertices.FindIndex(first));
    if (!last.IsNull()) bounds.push_back(-model.vertices.FindIndex(last));
    WriteBounds(bounds, out);
  }
  for (int f = 1; f <= model.face_count(); ++f) {
    out->Int(f);
    out->Char(' ');
    WriteBox(model.face(f), out);
    out->Text("0 ");
    std::vector<int> bounds;
    for (TopExp_Explorer it(model.face(f), TopAbs_EDGE); it.More(); it.Next()) {
      int id = model.edges.FindIndex(it.Current());
      int tag = it.Current().Orientation() == TopAbs_REVERSED ? -id : id;
      if (id > 0 && std::find(bounds.begin(), bounds.end(), tag) == bounds.end())
        bounds.push_back(tag);
    }
    WriteBounds(bounds, out);
  }
  out->Text("$EndEntities\n");
}

Status CheckClassification(const Model& model, const Mesh& mesh) {
  size_t nodes = static_cast<size_t>(mesh.node_count());
  if (mesh.node_dim.size() != nodes || mesh.node_entity.size() != nodes ||
      mesh.node_param.size() != 2 * nodes)
    return Status(StatusCode::kInternal, "the mesh lacks node classification (node_dim, ...)");
  const int counts[3] = {model.vertices.Extent(), model.edge_count(), model.face_count()};
  for (size_t i = 0; i < nodes; ++i) {
    int dim = mesh.node_dim[i];
    if (dim < 0 || dim > 2 || mesh.node_entity[i] < 1 || mesh.node_entity[i] > counts[dim])
      return Status(StatusCode::kInternal,
                    "node " + std::to_string(i) + " is classified on a missing entity");
  }
  return Status::Ok();
}

void WriteNodes(const Mesh& mesh, bool parametric, OutputFile* out) {
  // Node ids sorted by (dimension, entity), stable in id within an entity.
  std::vector<int64_t> order(mesh.node_count());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&mesh](int64_t a, int64_t b) {
    return std::make_pair(mesh.node_dim[a], mesh.node_entity[a]) <
           std::make_pair(mesh.node_dim[b], mesh.node_entity[b]);
  });
  std::vector<std::pair<size_t, size_t>> blocks;  // [begin, end) in `order`
  for (size_t i = 0; i < order.size(); ++i) {
    if (i == 0 || mesh.node_dim[order[i]] != mesh.node_dim[order[i - 1]] ||
        mesh.node_entity[order[i]] != mesh.node_entity[order[i - 1]])
      blocks.push_back({i, i});
    blocks.back().second = i + 1;
  }

  out->Text("$Nodes\n");
  out->Int(static_cast<int64_t>(blocks.size()));
  out->Char(' ');
  out->Int(mesh.node_count());
  out->Text(mesh.node_count() > 0 ? " 1 " : " 0 ");
  out->Int(mesh.node_count());
  out->Char('\n');
  for (const auto& [begin, end] : blocks) {
    int dim = mesh.node_dim[order[begin]];
    out->Int(dim);
    out->Char(' ');
    out->Int(mesh.node_entity[order[begin]]);
    const int params = parametric ? dim : 0;
    out->Text(params > 0 ? " 1 " : " 0 ");
    out->Int(static_cast<int64_t>(end - begin));
    out->Char('\n');
    for (size_t i = begin; i < end; ++i) {
      out->Int(order[i] + 1);
      out->Char('\n');
    }
    for (size_t i = begin; i < end; ++i) {
      int64_t node = order[i];
      for (int k = 0; k < 3; ++k) {
        if (k > 0) out->Char(' ');
        out->Number(mesh.xyz[3 * node + k]);
      }
      for (int k = 0; k < params; ++k) {
        out->Char(' ');
        out->Number(mesh.node_param[2 * node + k]);
      }
      out->Char('\n');
    }
  }
  out->Text("$EndNodes\n");
}

void WriteElements(const Model& model, const Mesh& mesh, const std::vector<EdgeLine>& edges,
                   OutputFile* out) {
  std::vector<std::vector<int64_t>> by_face(model.face_count() + 1);
  for (int64_t t = 0; t < mesh.triangle_count(); ++t) by_face[mesh.triangle_face[t]].push_back(t);
  int64_t blocks = std::count_if(by_face.begin(), by_face.end(),
                                 [](const std::vector<int64_t>& ts) { return !ts.empty(); });
  int64_t elements = mesh.triangle_count();
  for (const EdgeLine& line : edges) {
    if (line.degenerate || line.nodes.size() < 2) continue;
    ++blocks;
    elements += static_cast<int64_t>(line.nodes.size()) - 1;
  }
  out->Text("$Elements\n");
  out->Int(blocks);
  out->Char(' ');
  out->Int(elements);
  out->Text(elements > 0 ? " 1 " : " 0 ");
  out->Int(elements);
  out->Char('\n');
  int64_t tag = 0;
  for (int f = 1; f <= model.face_count(); ++f) {
    if (by_face[f].empty()) continue;
    out->Text("2 ");
    out->Int(f);
    out->Text(" 2 ");
    out->Int(static_cast<int64_t>(by_face[f].size()));
    out->Char('\n');
    for (int64_t t : by_face[f]) {
      out->Int(++tag);
      for (int k = 0; k < 3; ++k) {
        out->Char(' ');
        out->Int(mesh.triangles[3 * t + k] + 1);
      }
      out->Char('\n');
    }
  }
  for (const EdgeLine& line : edges) {
    if (line.degenerate || line.nodes.size() < 2) continue;
    out->Text("1 ");
    out->Int(line.edge_id);
    out->Text(" 1 ");
    out->Int(static_cast<int64_t>(line.nodes.size()) - 1);
    out->Char('\n');
    for (size_t k = 0; k + 1 < line.nodes.size(); ++k) {
      out->Int(++tag);
      out->Char(' ');
      out->Int(line.nodes[k] + 1);
      out->Char(' ');
      out->Int(line.nodes[k + 1] + 1);
      out->Char('\n');
    }
  }
  out->Text("$EndElements\n");
}

}  // namespace

Status WriteMsh(const Model& model, const MeshResult& result, const std::vector<EdgeLine>& edges,
                bool parametric, const std::string& path) {
  const Mesh& mesh = result.mesh;
  Status classified = CheckClassification(model, mesh);
  if (!classified.ok()) return classified;
  for (int32_t face : mesh.triangle_face)
    if (face < 1 || face > model.face_count())
      return Status(StatusCode::kInternal, "a triangle has face id " + std::to_string(face));

  OutputFile out;
  Status opened = out.Open(path);
  if (!opened.ok()) return opened;
  out.Text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
  WriteEntities(model, &out);
  WriteNodes(mesh, parametric, &out);
  WriteElements(model, mesh, edges, &out);
  return out.Close();
}

}  // namespace rdmesh
