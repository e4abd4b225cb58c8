#include "writers/gltf_ids.h"

#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <utility>

#include "rdmesh/options.h"
#include "writers/gltf_compress.h"
#include "writers/gltf_constants.h"
#include "writers/output_file.h"

namespace rdmesh {

namespace {

using Json = nlohmann::ordered_json;

using gltf::kArrayBuffer;
using gltf::kBinChunk;
using gltf::kElementArrayBuffer;
using gltf::kFloat;
using gltf::kJsonChunk;
using gltf::kLines;
using gltf::kUnsignedInt;

struct Glb {
  Json json;
  std::string bin;
};

uint32_t ReadU32(const std::string& bytes, size_t at) {
  uint32_t value;
  std::memcpy(&value, bytes.data() + at, 4);
  return value;
}

Result<Glb> ReadGlbFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < 20 || bytes.compare(0, 4, "glTF") != 0 || ReadU32(bytes, 8) != bytes.size())
    return WriteError(path, "the glTF writer left no valid .glb");
  Glb glb;
  size_t at = 12;
  while (at + 8 <= bytes.size()) {
    uint32_t length = ReadU32(bytes, at), type = ReadU32(bytes, at + 4);
    if (at + 8 + length > bytes.size()) return WriteError(path, "a .glb chunk overruns the file");
    std::string chunk = bytes.substr(at + 8, length);
    if (type == kJsonChunk) glb.json = Json::parse(chunk);
    if (type == kBinChunk) glb.bin = std::move(chunk);
    at += 8 + length;
  }
  if (!glb.json.is_object()) return WriteError(path, "the .glb has no JSON chunk");
  return glb;
}

Status WriteGlbFile(const std::string& path, Glb& glb) {
  if (!glb.bin.empty()) {
    if (!glb.json.contains("buffers") || glb.json["buffers"].empty())
      glb.json["buffers"] = Json::array({Json::object()});
    glb.json["buffers"][0]["byteLength"] = glb.bin.size();
  }
  std::string text = glb.json.dump();
  while (text.size() % 4 != 0) text.push_back(' ');
  while (glb.bin.size() % 4 != 0) glb.bin.push_back('\0');
  uint32_t total = 12 + 8 + static_cast<uint32_t>(text.size()) +
                   (glb.bin.empty() ? 0 : 8 + static_cast<uint32_t>(glb.bin.size()));
  OutputFile out;
  Status opened = out.Open(path);
  if (!opened.ok()) return opened;
  out.Text("glTF");
  out.Binary(uint32_t{2});
  out.Binary(total);
  out.Binary(static_cast<uint32_t>(text.size()));
  out.Binary(kJsonChunk);
  out.Text(text);
  if (!glb.bin.empty()) {
    out.Binary(static_cast<uint32_t>(glb.bin.size()));
    out.Binary(kBinChunk);
    out.Text(glb.bin);
  }
  return out.Close();
}

template <typename T>
std::string Bytes(const std::vector<T>& values) {
  return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

// Appends `bytes` to the binary chunk as a new buffer view; returns its index.
int AddView(Glb* glb, const std::string& bytes, int target, int stride) {
  while (glb->bin.size() % 4 != 0) glb->bin.push_back('\0');
  Json view = {{"buffer", 0}, {"byteOffset", glb->bin.size()}, {"byteLength", bytes.size()}};
  if (stride > 0) view["byteStride"] = stride;
  view["target"] = target;
  glb->bin += bytes;
  Json& views = glb->json["bufferViews"];
  views.push_back(view);
  return static_cast<int>(views.size()) - 1;
}

int AddAccessor(Json* json, int view, int component, size_t count, const char* type, Json min,
                Json max) {
  Json accessor = {
      {"bufferView", view}, {"componentType", component}, {"count", count}, {"type", type}};
  if (!min.is_null()) accessor["min"] = std::move(min);
  if (!max.is_null()) accessor["max"] = std::move(max);
  Json& accessors = (*json)["accessors"];
  accessors.push_back(accessor);
  return static_cast<int>(accessors.size()) - 1;
}

// TEXCOORD_0 = (face id, 0) -> _FACE_ID: the texture coordinate views are rewritten in place to
// one float per vertex, and the binary chunk is rebuilt view by view.
Status FaceIds(Glb* glb, const std::string& path) {
  Json& json = glb->json;
  std::set<int> uv_accessors;
  if (json.contains("meshes"))
    for (Json& mesh : json["meshes"])
      for (Json& primitive : mesh["primitives"])
        if (primitive["attributes"].contains("TEXCOORD_0"))
          uv_accessors.insert(primitive["attributes"]["TEXCOORD_0"].get<int>());
  if (uv_accessors.empty()) return Status::Ok();
  Json& accessors = json["accessors"];
  Json& views = json["bufferViews"];
  std::map<int, std::vector<int>> view_accessors;  // view -> its TEXCOORD_0 accessors
  for (int a : uv_accessors) {
    const Json& accessor = accessors[a];
    if (accessor.value("componentType", 0) != kFloat || accessor.value("type", "") != "VEC2")
      return WriteError(path, "unexpected texture coordinates from the glTF writer");
    view_accessors[accessor["bufferView"].get<int>()].push_back(a);
  }
  for (size_t a = 0; a < accessors.size(); ++a)
    if (!uv_accessors.count(static_cast<int>(a)) &&
        view_accessors.count(accessors[a].value("bufferView", -1)))
      return WriteError(path, "texture coordinates share a buffer view with other data");

  std::string bin;
  for (size_t v = 0; v < views.size(); ++v) {
    Json& view = views[v];
    const size_t offset = view.value("byteOffset", size_t{0});
    const size_t length = view["byteLength"].get<size_t>();
    if (offset + length > glb->bin.size()) return WriteError(path, "a buffer view overruns");
    while (bin.size() % 4 != 0) bin.push_back('\0');
    auto found = view_accessors.find(static_cast<int>(v));
    if (found == view_accessors.end()) {
      view["byteOffset"] = bin.size();
      bin.append(glb->bin, offset, length);
      continue;
    }
    const size_t stride = view.value("byteStride", size_t{8});
    std::vector<int>& list = found->second;
    std::sort(list.begin(), list.end(), [&](int a, int b) {
      return accessors[a].value("byteOffset", size_t{0}) <
             accessors[b].value("byteOffset", size_t{0});
    });
    std::vector<float> ids;
    for (int a : list) {
      Json& accessor = accessors[a];
      const size_t start = accessor.value("byteOffset", size_t{0});
      const size_t count = accessor["count"].get<size_t>();
      if (count > 0 && start + (count - 1) * stride + 8 > length)
        return WriteError(path, "texture coordinates overrun their buffer view");
      float low = std::numeric_limits<float>::max(), high = std::numeric_limits<float>::lowest();
      accessor["byteOffset"] = ids.size() * sizeof(float);
      for (size_t i = 0; i < count; ++i) {
        float id;
        std::memcpy(&id, glb->bin.data() + offset + start + i * stride, sizeof(float));
        ids.push_back(id);
        low = std::min(low, id), high = std::max(high, id);
      }
      accessor["type"] = "SCALAR";
      accessor.erase("normalized");
      if (count > 0) {
        accessor["min"] = Json::array({low});
        accessor["max"] = Json::array({high});
      } else {
        accessor.erase("min");
        accessor.erase("max");
      }
    }
    view["byteOffset"] = bin.size();
    view["byteLength"] = ids.size() * sizeof(float);
    view["byteStride"] = sizeof(float);
    bin += Bytes(ids);
  }
  glb->bin = std::move(bin);
  for (Json& mesh : json["meshes"])
    for (Json& primitive : mesh["primitives"]) {
      Json& attributes = primitive["attributes"];
      if (!attributes.contains("TEXCOORD_0")) continue;
      attributes["_FACE_ID"] = attributes["TEXCOORD_0"];
      attributes.erase("TEXCOORD_0");
    }
  return Status::Ok();
}

// The floats of accessor `a` (`components` per element), read through its buffer view's stride.
std::vector<float> ReadFloats(const Glb& glb, int a, int components) {
  const Json& accessor = glb.json["accessors"][a];
  const Json& view = glb.json["bufferViews"][accessor["bufferView"].get<int>()];
  const size_t element = sizeof(float) * components;
  const size_t stride = view.value("byteStride", element);
  const size_t start =
      view.value("byteOffset", size_t{0}) + accessor.value("byteOffset", size_t{0});
  const size_t count = accessor["count"].get<size_t>();
  std::vector<float> values(count * components);
  if (accessor.value("componentType", 0) != kFloat ||
      (count > 0 && start + (count - 1) * stride + element > glb.bin.size()))
    return {};
  for (size_t i = 0; i < count; ++i)
    std::memcpy(&values[i * components], glb.bin.data() + start + i * stride, element);
  return values;
}

// A glTF node's transform as a 3x4 row-major matrix (rotation and scale, then translation).
using Affine = std::array<double, 12>;

Affine Compose(const Affine& a, const Affine& b) {  // a after b
  Affine c{};
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 4; ++k) {
      double sum = k == 3 ? a[4 * r + 3] : 0.0;
      for (int j = 0; j < 3; ++j) sum += a[4 * r + j] * b[4 * j + k];
      c[4 * r + k] = sum;
    }
  return c;
}

Affine NodeTransform(const Json& node) {
  Affine m = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  if (node.contains("matrix")) {  // column-major 4x4
    const Json& x = node["matrix"];
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 4; ++k) m[4 * r + k] = x[4 * k + r].get<double>();
    return m;
  }
  if (node.contains("rotation")) {
    const Json& q = node["rotation"];
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    m = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),     0,
         2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),     0,
         2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y), 0};
  }
  if (node.contains("scale"))
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) m[4 * r + k] *= node["scale"][k].get<double>();
  if (node.contains("translation"))
    for (int r = 0; r < 3; ++r) m[4 * r + 3] = node["translation"][r].get<double>();
  return m;
}

// An instanced part's mesh carries the face ids of the instance it was lent from (_FACE_ID).
// Each node that draws such a mesh elsewhere gets extras.rdmesh.face_ids: {"lent id": its own
// face id}: the centroid of each lent face's vertices, carried to the model's frame through the
// node's world transform, picks the instance face whose node centroid is nearest (one distance
// per instance, so a part placed n times costs n^2 per face, not n^2 per node).
void InstanceFaceIds(Glb* glb, const Model& model, const MeshResult& result) {
  Json& json = glb->json;
  if (!json.contains("nodes") || !json.contains("scenes")) return;
  std::map<int, std::vector<int>> instances;  // representative -> faces with a mesh
  std::vector<std::array<double, 3>> centroid(model.face_count() + 1, {0.0, 0.0, 0.0});
  for (int f = 1; f <= model.face_count(); ++f) {
    if (static_cast<size_t>(f) > result.faces.size()) break;
    const std::vector<double>& q = result.faces[f - 1].xyz;
    if (q.empty()) continue;
    instances[model.face_representative[f - 1]].push_back(f);
    for (size_t k = 0; k + 2 < q.size(); k += 3)
      for (int c = 0; c < 3; ++c) centroid[f][c] += q[k + c] / static_cast<double>(q.size() / 3);
  }
  std::vector<std::pair<int, Affine>> stack;
  for (const Json& root : json["scenes"][json.value("scene", 0)]["nodes"])
    stack.push_back({root.get<int>(), Affine{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}});
  while (!stack.empty()) {
    auto [index, parent] = stack.back();
    stack.pop_back();
    Json& node = json["nodes"][index];
    const Affine world = Compose(parent, NodeTransform(node));
    if (node.contains("children"))
      for (const Json& child : node["children"]) stack.push_back({child.get<int>(), world});
    if (!node.contains("mesh")) continue;
    Json map = Json::object();
    for (const Json& primitive : json["meshes"][node["mesh"].get<int>()]["primitives"]) {
      const Json& attributes = primitive["attributes"];
      if (!attributes.contains("_FACE_ID") || !attributes.contains("POSITION")) continue;
      std::vector<float> ids = ReadFloats(*glb, attributes["_FACE_ID"].get<int>(), 1);
      std::vector<float> xyz = ReadFloats(*glb, attributes["POSITION"].get<int>(), 3);
      if (xyz.size() != 3 * ids.size()) continue;
      std::map<int, std::array<double, 4>> sums;  // lent face -> sum of x y z, count
      for (size_t i = 0; i < ids.size(); ++i) {
        std::array<double, 4>& sum = sums[static_cast<int>(ids[i])];
        for (int c = 0; c < 3; ++c) sum[c] += xyz[3 * i + c];
        sum[3] += 1.0;
      }
      for (const auto& [lent, sum] : sums) {
        if (lent < 1 || lent > model.face_count()) continue;
        const auto found = instances.find(model.face_representative[lent - 1]);
        if (found == instances.end() || found->second.size() < 2) continue;
        double g[3];  // the centroid in glTF's world, metres, +Y up
        for (int r = 0; r < 3; ++r)
          g[r] = (world[4 * r] * sum[0] + world[4 * r + 1] * sum[1] + world[4 * r + 2] * sum[2]) /
                     sum[3] +
                 world[4 * r + 3];
        const double p[3] = {1000.0 * g[0], -1000.0 * g[2], 1000.0 * g[1]};  // model frame, mm
        int best = lent;
        double best_distance = std::numeric_limits<double>::infinity();
        for (int f : found->second) {
          const std::array<double, 3>& q = centroid[f];
          const double d = (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
                           (q[2] - p[2]) * (q[2] - p[2]);
          if (d < best_distance) best_distance = d, best = f;
        }
        if (best != lent) map[std::to_string(lent)] = best;
      }
    }
    if (!map.empty()) node["extras"]["rdmesh"]["face_ids"] = map;
  }
}

// The solid id (1..S) each edge line is drawn with: the lowest solid holding the edge, or 0.
std::vector<int> EdgeSolids(const Model& model, const std::vector<EdgeLine>& edges,
                            int* solid_count) {
  TopTools_IndexedMapOfShape solids;
  TopExp::MapShapes(model.shape, TopAbs_SOLID, solids);
  TopTools_IndexedDataMapOfShapeListOfShape edge_solids;
  TopExp::MapShapesAndAncestors(model.shape, TopAbs_EDGE, TopAbs_SOLID, edge_solids);
  *solid_count = solids.Extent();
  std::vector<int> result;
  for (const EdgeLine& line : edges) {
    int best = 0;
    if (const TopTools_ListOfShape* list = edge_solids.Seek(model.edge(line.edge_id)))
      for (const TopoDS_Shape& solid : *list) {
        int s = solids.FindIndex(solid);
        if (s > 0 && (best == 0 || s < best)) best = s;
      }
    result.push_back(best);
  }
  return result;
}

// A mesh of one LINES primitive for `lines` (indices into `edges`); returns the mesh index.
int AddEdgeMesh(Glb* glb, const Mesh& mesh, const std::vector<EdgeLine>& edges,
                const std::vector<size_t>& lines, const std::string& name) {
  std::vector<float> positions, ids;
  std::vector<uint32_t> indices;
  Json listed = Json::array();
  float low[3], high[3];
  std::fill(low, low + 3, std::numeric_limits<float>::max());
  std::fill(high, high + 3, std::numeric_limits<float>::lowest());
  for (size_t l : lines) {
    const EdgeLine& line = edges[l];
    const auto first = static_cast<uint32_t>(ids.size());
    for (size_t k = 0; k < line.nodes.size(); ++k) {
      const double* p = &mesh.xyz[3 * static_cast<int64_t>(line.nodes[k])];
      for (int c = 0; c < 3; ++c) {
        auto value = static_cast<float>(p[c]);
        positions.push_back(value);
        low[c] = std::min(low[c], value), high[c] = std::max(high[c], value);
      }
      ids.push_back(static_cast<float>(line.edge_id));
      if (k > 0) indices.push_back(first + k - 1), indices.push_back(first + k);
    }
    listed.push_back({{"id", line.edge_id},
                      {"faces", line.faces},
                      {"seam", line.seam},
                      {"sharp", line.sharp},
                      {"dihedral", line.dihedral}});
  }
  Json& json = glb->json;
  int position_view = AddView(glb, Bytes(positions), kArrayBuffer, 12);
  int id_view = AddView(glb, Bytes(ids), kArrayBuffer, 4);
  int index_view = AddView(glb, Bytes(indices), kElementArrayBuffer, 0);
  const size_t count = ids.size();
  int position =
      AddAccessor(&json, position_view, kFloat, count, "VEC3",
                  Json::array({low[0], low[1], low[2]}), Json::array({high[0], high[1], high[2]}));
  auto [min_id, max_id] = std::minmax_element(ids.begin(), ids.end());
  int id = AddAccessor(&json, id_view, kFloat, count, "SCALAR", Json::array({*min_id}),
                       Json::array({*max_id}));
  auto [min_index, max_index] = std::minmax_element(indices.begin(), indices.end());
  int index = AddAccessor(&json, index_view, kUnsignedInt, indices.size(), "SCALAR",
                          Json::array({*min_index}), Json::array({*max_index}));
  Json primitive = {{"attributes", {{"POSITION", position}, {"_EDGE_ID", id}}},
                    {"indices", index},
                    {"mode", kLines},
                    {"extras", {{"edges", listed}}}};
  json["meshes"].push_back({{"name", name}, {"primitives", Json::array({primitive})}});
  return static_cast<int>(json["meshes"].size()) - 1;
}

void EdgeNodes(Glb* glb, const Model& model, const Mesh& mesh, const std::vector<EdgeLine>& edges) {
  int solid_count = 0;
  std::vector<int> solid = EdgeSolids(model, edges, &solid_count);
  std::vector<std::vector<size_t>> groups(solid_count + 1);  // [0]: edges in no solid
  for (size_t l = 0; l < edges.size(); ++l)
    if (!edges[l].degenerate && edges[l].nodes.size() >= 2) groups[solid[l]].push_back(l);
  Json& json = glb->json;
  Json children = Json::array();
  for (int s = 1; s <= solid_count + 1; ++s) {
    const std::vector<size_t>& group = groups[s % (solid_count + 1)];
    if (group.empty()) continue;
    std::string name = s <= solid_count ? "edges of solid " + std::to_string(s) : "free edges";
    int m = AddEdgeMesh(glb, mesh, edges, group, name);
    json["nodes"].push_back({{"name", name}, {"mesh", m}});
    children.push_back(json["nodes"].size() - 1);
  }
  if (children.empty()) return;
  // Model units (mm) to metres and +Z up to glTF's +Y up, as the faces: -90 degrees about X.
  const double half = 0.70710678118654752;
  json["nodes"].push_back({{"name", "edges"},
                           {"children", children},
                           {"rotation", {-half, 0.0, 0.0, half}},
                           {"scale", {0.001, 0.001, 0.001}}});
  const int root = static_cast<int>(json["nodes"].size()) - 1;
  if (!json.contains("scenes") || json["scenes"].empty())
    json["scenes"] = Json::array({{{"nodes", Json::array()}}}), json["scene"] = 0;
  json["scenes"][json.value("scene", 0)]["nodes"].push_back(root);
}

}  // namespace

Status AddGltfIdsAndEdges(const Model& model, const MeshResult& result,
                          const std::vector<EdgeLine>& edges, bool compress,
                          const std::string& path) {
  const Mesh& mesh = result.mesh;
  Result<Glb> read = ReadGlbFile(path);
  if (!read.ok()) return read.status();
  Glb& glb = *read;
  Status ids = FaceIds(&glb, path);
  if (!ids.ok()) return ids;
  InstanceFaceIds(&glb, model, result);
  if (!edges.empty()) EdgeNodes(&glb, model, mesh, edges);
  Json degenerate = Json::array();
  for (const EdgeLine& line : edges)
    if (line.degenerate || line.nodes.size() < 2) degenerate.push_back(line.edge_id);
  glb.json["extras"]["rdmesh"] = {
      {"_FACE_ID",
       "per vertex of every triangle primitive: the B-rep face id (1..F, rdmesh's face ids) of "
       "the face the triangle belongs to; a node drawing an instanced part's mesh at another "
       "instance has extras.rdmesh.face_ids mapping those ids to its own faces' ids"},
      {"_EDGE_ID",
       "per vertex of the LINES primitives under the node 'edges': the B-rep edge id (1..E); "
       "each primitive's extras.edges lists its edges with their faces, seam and sharp flags and "
       "dihedral angle (degrees, -1 undefined); degenerate_edges lists the edges without extent, "
       "which have no line"},
      {"normals", "NORMAL is the exact surface normal of the vertex's face at the vertex"}};
  if (!edges.empty()) glb.json["extras"]["rdmesh"]["degenerate_edges"] = degenerate;
  if (compress) {
    // One short note instead of the plain file's three: in a small file they weigh.
    for (const char* key : {"_FACE_ID", "_EDGE_ID", "normals"})
      glb.json["extras"]["rdmesh"].erase(key);
    glb.json["extras"]["rdmesh"]["compressed"] =
        "meshopt, rdmesh's docs/GLB.md: _FACE_ID / _EDGE_ID per vertex the B-rep face / edge id "
        "(a node's extras.rdmesh.face_ids maps an instance's); NORMAL the face's exact normal; "
        "positions within 1.5% of requested_deviation (mm); extras.edge_table: id, flags (1 "
        "seam, 2 sharp, face count << 8), dihedral, faces; faces.surface_type[f - 1] indexes "
        "surface_types; extras.triangle_deviation per triangle, in requested_deviation / "
        "deviation_steps";
    // Model units are mm and glTF's are metres (WriteGlb).
    const double max_shift = kCompressRoundingShare * result.summary.requested_deviation * 1e-3;
    Status compressed = CompressGlb(model, result, max_shift, path, &glb.json, &glb.bin);
    if (!compressed.ok()) return compressed;
  }
  return WriteGlbFile(path, glb);
}

}  // namespace rdmesh
