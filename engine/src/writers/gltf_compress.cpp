#include "writers/gltf_compress.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "writers/gltf_constants.h"
#include "writers/output_file.h"

namespace rdmesh {

namespace {

using Json = nlohmann::ordered_json;

using gltf::kArrayBuffer;
using gltf::kByte;
using gltf::kElementArrayBuffer;
using gltf::kFloat;
using gltf::kLines;
using gltf::kShort;
using gltf::kTriangles;
using gltf::kUnsignedByte;
using gltf::kUnsignedInt;
using gltf::kUnsignedShort;
// Octahedral normals in 16-bit integers: 10 bits keep them within 0.21 degrees of the exact
// normals on nist_ctc_02 (docs/GLB.md), which shading cannot show; 12 cost 2-3% more file.
constexpr int kNormalBits = 10;
// A triangle's deviation as a byte: its share of the requested deviation in steps of 1/15,
// as many colours as a deviation map shows apart; finer steps cost a byte per triangle.
constexpr double kDeviationSteps = 15.0;

int ComponentSize(int type) {
  switch (type) {
    case kByte:
    case kUnsignedByte:
      return 1;
    case kShort:
    case kUnsignedShort:
      return 2;
    default:
      return 4;
  }
}

int Components(const std::string& type) {
  if (type == "VEC2") return 2;
  if (type == "VEC3") return 3;
  if (type == "VEC4") return 4;
  return 1;
}

// The values of accessor `a`, `components` per element, whatever their component type;
// false when it overruns the binary chunk or has no buffer view.
bool ReadAccessor(const Json& json, const std::string& bin, int a, std::vector<double>* values,
                  int* components) {
  const Json& accessor = json["accessors"][a];
  if (!accessor.contains("bufferView")) return false;
  const Json& view = json["bufferViews"][accessor["bufferView"].get<int>()];
  const int type = accessor.value("componentType", 0);
  *components = Components(accessor.value("type", "SCALAR"));
  const size_t size = ComponentSize(type), element = size * *components;
  const size_t stride = view.value("byteStride", element);
  const size_t start =
      view.value("byteOffset", size_t{0}) + accessor.value("byteOffset", size_t{0});
  const size_t count = accessor["count"].get<size_t>();
  if (count > 0 && start + (count - 1) * stride + element > bin.size()) return false;
  values->resize(count * *components);
  for (size_t i = 0; i < count; ++i)
    for (int c = 0; c < *components; ++c) {
      const char* p = bin.data() + start + i * stride + c * size;
      double& v = (*values)[i * *components + c];
      if (type == kFloat) {
        float f;
        std::memcpy(&f, p, 4);
        v = f;
      } else if (type == kUnsignedInt) {
        uint32_t u;
        std::memcpy(&u, p, 4);
        v = u;
      } else if (type == kUnsignedShort) {
        uint16_t u;
        std::memcpy(&u, p, 2);
        v = u;
      } else if (type == kUnsignedByte) {
        v = static_cast<uint8_t>(*p);
      } else {
        return false;  // the plain writer makes no signed or normalized data
      }
    }
  return true;
}

template <typename T>
std::string Bytes(const std::vector<T>& values) {
  return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

// Where an accessor's data lies: a stream (one buffer view in the end) and a byte offset in it.
struct Slice {
  int stream = 0;
  size_t offset = 0;
};

// Data of one kind from every primitive, compressed as one buffer view: fewer views make less
// JSON, and the codec sees longer runs.
struct Stream {
  const char* mode = "ATTRIBUTES";  // or TRIANGLES, INDICES
  const char* filter = "NONE";
  size_t stride = 4;
  int target = 0;
  std::string raw;                // ATTRIBUTES: the decoded bytes
  std::vector<uint32_t> indices;  // TRIANGLES, INDICES: the values
  uint32_t vertex_bound = 0;      // 1 + the largest index
};

// The compressed file being built: streams compressed into `bin`, their decoded layout in the
// fallback buffer (buffer 1, no data), accessors over them.
struct Builder {
  std::vector<Stream> streams;
  Json accessors = Json::array();

  Stream* Find(const char* mode, const char* filter, size_t stride, int target, int* index) {
    for (size_t i = 0; i < streams.size(); ++i) {
      Stream& s = streams[i];
      if (std::strcmp(s.mode, mode) == 0 && std::strcmp(s.filter, filter) == 0 &&
          s.stride == stride && s.target == target) {
        *index = static_cast<int>(i);
        return &s;
      }
    }
    streams.push_back(Stream{mode, filter, stride, target, {}, {}, 0});
    *index = static_cast<int>(streams.size()) - 1;
    return &streams.back();
  }

  // Vertex attributes (target ARRAY_BUFFER) or any other table of 4-byte-aligned elements.
  Slice AddAttributeView(const std::string& raw, size_t count, size_t stride, const char* filter,
                         int target) {
    Slice slice;
    Stream* s = Find("ATTRIBUTES", filter, stride, target, &slice.stream);
    slice.offset = s->raw.size();
    s->raw += raw;
    return slice;
  }

  Slice AddIndexView(const std::vector<uint32_t>& indices, size_t vertex_count, bool triangles,
                     size_t* stride) {
    *stride = vertex_count <= 65535 ? 2 : 4;
    Slice slice;
    Stream* s = Find(triangles ? "TRIANGLES" : "INDICES", "NONE", *stride, kElementArrayBuffer,
                     &slice.stream);
    slice.offset = s->indices.size() * *stride;
    s->indices.insert(s->indices.end(), indices.begin(), indices.end());
    s->vertex_bound = std::max(s->vertex_bound, static_cast<uint32_t>(vertex_count));
    return slice;
  }

  int AddAccessor(Slice slice, int component, size_t count, const char* type, bool normalized,
                  Json min = nullptr, Json max = nullptr) {
    Json accessor = {{"bufferView", slice.stream}};
    if (slice.offset > 0) accessor["byteOffset"] = slice.offset;
    accessor["componentType"] = component;
    accessor["count"] = count;
    accessor["type"] = type;
    if (normalized) accessor["normalized"] = true;
    if (!min.is_null()) accessor["min"] = std::move(min);
    if (!max.is_null()) accessor["max"] = std::move(max);
    accessors.push_back(std::move(accessor));
    return static_cast<int>(accessors.size()) - 1;
  }

  // Unsigned integers as a SCALAR UNSIGNED_INT accessor (not a vertex attribute).
  int AddUints(const std::vector<uint32_t>& values) {
    Slice slice = AddAttributeView(Bytes(values), values.size(), 4, "NONE", 0);
    return AddAccessor(slice, kUnsignedInt, values.size(), "SCALAR", false);
  }

  // Bytes packed four to an element (the codec's elements are multiples of 4 bytes): a VEC4
  // UNSIGNED_BYTE accessor of ceil(n / 4) elements, read flat.
  int AddBytes(std::vector<uint8_t> values) {
    while (values.size() % 4 != 0 || values.empty()) values.push_back(0);
    Slice slice = AddAttributeView(Bytes(values), values.size() / 4, 4, "NONE", 0);
    return AddAccessor(slice, kUnsignedByte, values.size() / 4, "VEC4", false);
  }

  // Compresses every stream: the buffer views (view i = stream i), the binary chunk and the
  // fallback buffer's length.
  void Finish(Json* views, std::string* bin, size_t* fallback) const {
    meshopt_encodeIndexVersion(1);  // EXT_meshopt_compression decoders read version 1
    *views = Json::array();
    bin->clear();
    *fallback = 0;
    for (const Stream& s : streams) {
      std::vector<unsigned char> out;
      size_t count = 0;
      if (std::strcmp(s.mode, "ATTRIBUTES") == 0) {
        count = s.raw.size() / s.stride;
        out.resize(meshopt_encodeVertexBufferBound(count, s.stride));
        out.resize(
            meshopt_encodeVertexBuffer(out.data(), out.size(), s.raw.data(), count, s.stride));
      } else if (std::strcmp(s.mode, "TRIANGLES") == 0) {
        count = s.indices.size();
        out.resize(meshopt_encodeIndexBufferBound(count, s.vertex_bound));
        out.resize(meshopt_encodeIndexBuffer(out.data(), out.size(), s.indices.data(), count));
      } else {
        count = s.indices.size();
        out.resize(meshopt_encodeIndexSequenceBound(count, s.vertex_bound));
        out.resize(meshopt_encodeIndexSequence(out.data(), out.size(), s.indices.data(), count));
      }
      while (bin->size() % 4 != 0) bin->push_back('\0');
      while (*fallback % 4 != 0) ++*fallback;
      Json meshopt = {{"buffer", 0},
                      {"byteOffset", bin->size()},
                      {"byteLength", out.size()},
                      {"byteStride", s.stride},
                      {"count", count},
                      {"mode", s.mode}};
      if (std::strcmp(s.filter, "NONE") != 0) meshopt["filter"] = s.filter;
      Json view = {{"buffer", 1}, {"byteOffset", *fallback}, {"byteLength", count * s.stride}};
      if (s.target == kArrayBuffer) view["byteStride"] = s.stride;
      if (s.target != 0) view["target"] = s.target;
      view["extensions"]["EXT_meshopt_compression"] = meshopt;
      bin->append(out.begin(), out.end());
      *fallback += count * s.stride;
      views->push_back(std::move(view));
    }
  }
};

// An id attribute (_FACE_ID, _EDGE_ID): 16-bit integers when every id fits, else floats. Eight
// bytes a vertex, as 16-bit positions and colours, so they share one buffer view with them (one
// view less of JSON; the codec spends next to nothing on the zero bytes).
int AddIdAttribute(Builder* out, const std::vector<double>& ids) {
  const bool small =
      std::all_of(ids.begin(), ids.end(), [](double id) { return id >= 0 && id <= 65535; });
  std::string raw(ids.size() * 8, '\0');
  for (size_t i = 0; i < ids.size(); ++i) {
    if (small) {
      const auto id = static_cast<uint16_t>(ids[i]);
      std::memcpy(&raw[8 * i], &id, 2);
    } else {
      const auto id = static_cast<float>(ids[i]);
      std::memcpy(&raw[8 * i], &id, 4);
    }
  }
  Slice view = out->AddAttributeView(raw, ids.size(), 8, "NONE", kArrayBuffer);
  return out->AddAccessor(view, small ? kUnsignedShort : kFloat, ids.size(), "SCALAR", false);
}

struct Primitive {
  Json json;  // the primitive's JSON: material, mode, extras
  int mode = kTriangles;
  std::vector<uint32_t> indices;
  std::vector<double> position, normal, face_id, edge_id;
  std::vector<double> colour;      // 3 per vertex (COLOR_0) when primitives were merged
  std::vector<uint8_t> deviation;  // per triangle; empty when unknown
};

// Reads a primitive of the plain file; false when it holds what the plain writer does not make.
bool ReadPrimitive(const Json& json, const std::string& bin, const Json* source, Primitive* p) {
  p->json = *source;
  p->mode = source->value("mode", kTriangles);
  if (p->mode != kTriangles && p->mode != kLines) return false;
  int components = 0;
  for (const auto& [name, accessor] : (*source)["attributes"].items()) {
    std::vector<double>* target = name == "POSITION"   ? &p->position
                                  : name == "NORMAL"   ? &p->normal
                                  : name == "_FACE_ID" ? &p->face_id
                                  : name == "_EDGE_ID" ? &p->edge_id
                                                       : nullptr;
    if (!target || !ReadAccessor(json, bin, accessor.get<int>(), target, &components)) return false;
  }
  const size_t vertices = p->position.size() / 3;
  if (p->position.empty() || (!p->normal.empty() && p->normal.size() != 3 * vertices) ||
      (!p->face_id.empty() && p->face_id.size() != vertices) ||
      (!p->edge_id.empty() && p->edge_id.size() != vertices))
    return false;
  if (source->contains("indices")) {
    std::vector<double> indices;
    if (!ReadAccessor(json, bin, (*source)["indices"].get<int>(), &indices, &components))
      return false;
    for (double i : indices) {
      if (i < 0 || i >= static_cast<double>(vertices)) return false;
      p->indices.push_back(static_cast<uint32_t>(i));
    }
  } else {
    for (size_t i = 0; i < vertices; ++i) p->indices.push_back(static_cast<uint32_t>(i));
  }
  const size_t corners = p->mode == kTriangles ? 3 : 2;
  return p->indices.size() % corners == 0;
}

// Per triangle of a triangle primitive (before reordering), its face's estimated deviation as
// a byte (kDeviationSteps per requested deviation). The plain writer merges the faces of a
// part in runs, each run a face's triangles in the face's order; a primitive whose runs do not
// match its faces' triangle counts gets none.
std::vector<uint8_t> TriangleDeviation(const MeshResult& result, const Primitive& p) {
  const double requested = result.summary.requested_deviation;
  if (requested <= 0 || p.face_id.empty()) return {};
  const size_t triangles = p.indices.size() / 3;
  std::vector<uint8_t> bytes(triangles);
  size_t t = 0;
  while (t < triangles) {
    const double id = p.face_id[p.indices[3 * t]];
    if (id < 1 || id > static_cast<double>(result.faces.size())) return {};
    const FaceMesh& face = result.faces[static_cast<size_t>(id) - 1];
    const size_t n = face.triangle_deviation.size();
    if (n == 0 || static_cast<int64_t>(n) != face.triangle_count() || t + n > triangles) return {};
    for (size_t k = 0; k < n; ++k, ++t) {
      if (p.face_id[p.indices[3 * t]] != id) return {};
      const double steps = std::ceil(face.triangle_deviation[k] / requested * kDeviationSteps);
      bytes[t] = static_cast<uint8_t>(std::clamp(steps, 0.0, 255.0));
    }
  }
  return bytes;
}

// GPU order: triangles for the vertex cache, then vertices in first-use order (unused ones
// dropped); the per-triangle bytes follow their triangles.
void Optimise(Primitive* p) {
  const size_t vertices = p->position.size() / 3;
  std::vector<uint32_t> ordered(p->indices.size());
  meshopt_optimizeVertexCache(ordered.data(), p->indices.data(), p->indices.size(), vertices);
  if (!p->deviation.empty()) {
    // Triangles keep their corners' order; find each one's old place by its corners.
    std::map<std::array<uint32_t, 3>, std::vector<size_t>> place;
    for (size_t t = 0; t < p->indices.size() / 3; ++t)
      place[{p->indices[3 * t], p->indices[3 * t + 1], p->indices[3 * t + 2]}].push_back(t);
    std::vector<uint8_t> deviation(p->deviation.size());
    for (size_t t = 0; t < ordered.size() / 3; ++t) {
      std::vector<size_t>& old = place[{ordered[3 * t], ordered[3 * t + 1], ordered[3 * t + 2]}];
      if (old.empty()) {
        deviation.clear();
        break;
      }
      deviation[t] = p->deviation[old.back()];
      old.pop_back();
    }
    p->deviation = std::move(deviation);
  }
  std::vector<uint32_t> remap(vertices);
  const size_t kept =
      meshopt_optimizeVertexFetchRemap(remap.data(), ordered.data(), ordered.size(), vertices);
  meshopt_remapIndexBuffer(ordered.data(), ordered.data(), ordered.size(), remap.data());
  p->indices = std::move(ordered);
  auto apply = [&](std::vector<double>* stream, size_t components) {
    if (stream->empty()) return;
    std::vector<double> out(kept * components);
    for (size_t v = 0; v < vertices; ++v)
      if (remap[v] != ~0u)
        for (size_t c = 0; c < components; ++c)
          out[remap[v] * components + c] = (*stream)[v * components + c];
    *stream = std::move(out);
  };
  apply(&p->position, 3);
  apply(&p->normal, 3);
  apply(&p->face_id, 1);
  apply(&p->edge_id, 1);
  apply(&p->colour, 3);
}

// The colour (baseColorFactor) of a material, white when it has none.
std::array<double, 4> MaterialColour(const Json& material) {
  std::array<double, 4> c{1, 1, 1, 1};
  if (material.contains("pbrMetallicRoughness") &&
      material["pbrMetallicRoughness"].contains("baseColorFactor"))
    for (int k = 0; k < 4; ++k)
      c[k] = material["pbrMetallicRoughness"]["baseColorFactor"][k].get<double>();
  return c;
}

// One mesh's triangle primitives merged into one when their materials differ in name and colour
// alone (OCCT writes a primitive per colour): the colours go to COLOR_0, which the material
// multiplies (its colour made white), so the file holds one set of accessors per mesh instead
// of one per colour. Runs before Optimise, on primitives as read.
void MergeByColour(Json* json, std::vector<Primitive>* prims) {
  if (prims->size() < 2) return;
  Json* materials = json->contains("materials") ? &(*json)["materials"] : nullptr;
  auto material_of = [&](const Primitive& p) {
    if (!materials || !p.json.contains("material")) return Json(Json::object());
    return (*materials)[p.json["material"].get<int>()];
  };
  auto rest_of = [](Json material) {
    material.erase("name");
    if (material.contains("pbrMetallicRoughness"))
      material["pbrMetallicRoughness"].erase("baseColorFactor");
    return material;
  };
  const Primitive& first = prims->front();
  const Json rest = rest_of(material_of(first));
  const std::array<double, 4> first_colour = MaterialColour(material_of(first));
  bool same_colour = true, deviation = true;
  for (const Primitive& p : *prims) {
    const Json material = material_of(p);
    const std::array<double, 4> colour = MaterialColour(material);
    if (p.mode != kTriangles || p.normal.empty() != first.normal.empty() ||
        p.face_id.empty() != first.face_id.empty() || !p.edge_id.empty() ||
        rest_of(material) != rest || material.value("alphaMode", "OPAQUE") != "OPAQUE" ||
        colour[3] != first_colour[3])
      return;
    same_colour = same_colour && colour == first_colour;
    deviation = deviation && !p.deviation.empty();
  }
  if (!materials && !same_colour) return;
  Primitive merged;
  merged.json = first.json;
  for (const Primitive& p : *prims) {
    const auto base = static_cast<uint32_t>(merged.position.size() / 3);
    for (uint32_t i : p.indices) merged.indices.push_back(base + i);
    merged.position.insert(merged.position.end(), p.position.begin(), p.position.end());
    merged.normal.insert(merged.normal.end(), p.normal.begin(), p.normal.end());
    merged.face_id.insert(merged.face_id.end(), p.face_id.begin(), p.face_id.end());
    if (deviation)
      merged.deviation.insert(merged.deviation.end(), p.deviation.begin(), p.deviation.end());
    if (same_colour) continue;
    const std::array<double, 4> colour = MaterialColour(material_of(p));
    for (size_t v = 0; v < p.position.size() / 3; ++v)
      merged.colour.insert(merged.colour.end(), colour.begin(), colour.begin() + 3);
  }
  if (!same_colour) {
    Json material = material_of(first);
    material["name"] = "rdmesh vertex colours";
    material["pbrMetallicRoughness"]["baseColorFactor"] = {1.0, 1.0, 1.0, first_colour[3]};
    auto found = std::find(materials->begin(), materials->end(), material);
    merged.json["material"] = found - materials->begin();
    if (found == materials->end()) materials->push_back(material);
  }
  if (merged.json.contains("extras")) {
    merged.json["extras"].erase("triangle_deviation");
    if (merged.json["extras"].empty()) merged.json.erase("extras");
  }
  prims->assign(1, std::move(merged));
}

// Leaves out the materials no primitive uses any more (merged ones) and renumbers the rest.
void PruneMaterials(Json* json) {
  if (!json->contains("materials") || !json->contains("meshes")) return;
  Json& materials = (*json)["materials"];
  std::vector<int> index(materials.size(), -1);
  for (const Json& mesh : (*json)["meshes"])
    for (const Json& p : mesh["primitives"])
      if (p.contains("material")) index[p["material"].get<int>()] = 0;
  Json kept = Json::array();
  for (size_t i = 0; i < materials.size(); ++i)
    if (index[i] == 0) {
      index[i] = static_cast<int>(kept.size());
      kept.push_back(materials[i]);
    }
  materials = std::move(kept);
  for (Json& mesh : (*json)["meshes"])
    for (Json& p : mesh["primitives"])
      if (p.contains("material")) p["material"] = index[p["material"].get<int>()];
}

// COLOR_0: 16-bit normalized linear RGB (the materials' baseColorFactor, which is linear too).
int AddColours(Builder* out, const std::vector<double>& colours) {
  const size_t n = colours.size() / 3;
  std::vector<uint16_t> raw(4 * n, 0);
  for (size_t v = 0; v < n; ++v)
    for (int c = 0; c < 3; ++c)
      raw[4 * v + c] =
          static_cast<uint16_t>(std::lround(std::clamp(colours[3 * v + c], 0.0, 1.0) * 65535));
  Slice view = out->AddAttributeView(Bytes(raw), n, 8, "NONE", kArrayBuffer);
  return out->AddAccessor(view, kUnsignedShort, n, "VEC3", true);
}

// How a mesh's positions are stored: integers q with position = (q + origin) * step.
struct Grid {
  double step = 0.0;                // 0: floats kept as they are
  std::array<int64_t, 3> origin{};  // grid cells; the child node's translation is origin * step
  bool shorts = false;              // 16-bit integers (node scale = step), else grid floats
};

Grid ChooseGrid(const std::vector<Primitive>& prims, double max_local_shift) {
  if (!(max_local_shift > 0) || !std::isfinite(max_local_shift)) return Grid{};
  double low[3], high[3];
  std::fill(low, low + 3, std::numeric_limits<double>::max());
  std::fill(high, high + 3, std::numeric_limits<double>::lowest());
  for (const Primitive& p : prims)
    for (size_t i = 0; i < p.position.size(); ++i)
      low[i % 3] = std::min(low[i % 3], p.position[i]),
              high[i % 3] = std::max(high[i % 3], p.position[i]);
  auto place = [&](double step, Grid* grid) {  // -> the largest |q|
    grid->step = step;
    double cells = 0;
    for (int c = 0; c < 3; ++c) {
      grid->origin[c] = std::llround(0.5 * (low[c] + high[c]) / step);
      cells = std::max(cells, std::max(std::abs(low[c] / step - grid->origin[c]),
                                       std::abs(high[c] / step - grid->origin[c])));
    }
    return cells + 1;  // rounding can add one cell
  };
  // A vertex rounded to the nearest grid point moves at most sqrt(3)/2 of a step.
  const double step = max_local_shift / (0.5 * std::sqrt(3.0));
  Grid grid;
  grid.shorts = place(step, &grid) <= 32767.0;
  if (grid.shorts) return grid;
  // Floats hold the grid exactly when the step is a power of two and |q| stays below 2^23;
  // beyond that the positions stay as they are.
  if (place(std::exp2(std::floor(std::log2(step))), &grid) >= 8388608.0) return Grid{};
  return grid;
}

// POSITION of one primitive on `grid`; the largest distance (mesh units) between a decoded
// position and the plain one goes to `*shift`.
int AddPositions(Builder* out, const Primitive& p, const Grid& grid, double* shift) {
  const size_t n = p.position.size() / 3;
  std::vector<int64_t> q(3 * n);
  std::array<double, 3> low, high;
  low.fill(std::numeric_limits<double>::max());
  high.fill(std::numeric_limits<double>::lowest());
  if (grid.step > 0)
    for (size_t i = 0; i < 3 * n; ++i)
      q[i] = std::llround(p.position[i] / grid.step) - grid.origin[i % 3];
  if (grid.shorts) {
    std::vector<int16_t> raw(4 * n, 0);
    for (size_t v = 0; v < n; ++v)
      for (int c = 0; c < 3; ++c) {
        raw[4 * v + c] = static_cast<int16_t>(q[3 * v + c]);
        low[c] = std::min(low[c], static_cast<double>(q[3 * v + c]));
        high[c] = std::max(high[c], static_cast<double>(q[3 * v + c]));
        const double decoded = static_cast<double>(q[3 * v + c] + grid.origin[c]) * grid.step;
        *shift = std::max(*shift, std::abs(decoded - p.position[3 * v + c]));
      }
    Slice view = out->AddAttributeView(Bytes(raw), n, 8, "NONE", kArrayBuffer);
    return out->AddAccessor(view, kShort, n, "VEC3", false, Json(low), Json(high));
  }
  std::vector<float> values(3 * n);
  for (size_t i = 0; i < 3 * n; ++i)
    values[i] = grid.step > 0 ? static_cast<float>(static_cast<double>(q[i]) * grid.step)
                              : static_cast<float>(p.position[i]);
  const char* filter = "NONE";
  std::string raw = Bytes(values);
  if (grid.step > 0) {
    // The smallest mantissa that keeps every grid float exact (checked by decoding).
    for (int bits = 2; bits <= 24; ++bits) {
      std::vector<uint32_t> encoded(3 * n);
      meshopt_encodeFilterExp(encoded.data(), n, 12, bits, values.data());
      std::vector<uint32_t> decoded = encoded;
      meshopt_decodeFilterExp(decoded.data(), n, 12);
      if (std::memcmp(decoded.data(), values.data(), 12 * n) == 0) {
        raw = Bytes(encoded);
        filter = "EXPONENTIAL";
        break;
      }
    }
  }
  for (size_t v = 0; v < n; ++v)
    for (int c = 0; c < 3; ++c) {
      const double f = values[3 * v + c];
      low[c] = std::min(low[c], f), high[c] = std::max(high[c], f);
      if (grid.step > 0)
        *shift = std::max(*shift, std::abs(f + grid.origin[c] * grid.step - p.position[3 * v + c]));
    }
  Slice view = out->AddAttributeView(raw, n, 12, filter, kArrayBuffer);
  return out->AddAccessor(view, kFloat, n, "VEC3", false, Json(low), Json(high));
}

int AddNormals(Builder* out, const std::vector<double>& normals) {
  const size_t n = normals.size() / 3;
  std::vector<float> xyzw(4 * n, 0.0f);
  for (size_t v = 0; v < n; ++v)
    for (int c = 0; c < 3; ++c) xyzw[4 * v + c] = static_cast<float>(normals[3 * v + c]);
  std::vector<int16_t> encoded(4 * n);
  meshopt_encodeFilterOct(encoded.data(), n, 8, kNormalBits, xyzw.data());
  Slice view = out->AddAttributeView(Bytes(encoded), n, 8, "OCTAHEDRAL", kArrayBuffer);
  return out->AddAccessor(view, kShort, n, "VEC3", true);
}

// A LINES primitive's edge table (extras.edges) as accessors, when smaller than its JSON.
void EdgeTable(Builder* out, Json* primitive) {
  if (!primitive->contains("extras") || !(*primitive)["extras"].contains("edges")) return;
  const Json& edges = (*primitive)["extras"]["edges"];
  std::vector<uint32_t> ids, flags, faces;
  std::vector<float> dihedral;
  for (const Json& e : edges) {
    ids.push_back(e["id"].get<uint32_t>());
    const uint32_t face_count = static_cast<uint32_t>(e["faces"].size());
    flags.push_back((e["seam"].get<bool>() ? 1u : 0u) | (e["sharp"].get<bool>() ? 2u : 0u) |
                    face_count << 8);
    dihedral.push_back(static_cast<float>(e["dihedral"].get<double>()));
    for (const Json& f : e["faces"]) faces.push_back(f.get<uint32_t>());
  }
  if (ids.empty()) return;
  Builder trial;
  trial.AddUints(ids);
  trial.AddUints(flags);
  trial.AddAttributeView(Bytes(dihedral), dihedral.size(), 4, "NONE", 0);
  if (!faces.empty()) trial.AddUints(faces);
  Json views;
  std::string bytes;
  size_t length = 0;
  trial.Finish(&views, &bytes, &length);
  // Each accessor costs about 100 bytes of JSON.
  if (bytes.size() + 4 * 100 >= edges.dump().size()) return;
  Json table = {{"id", out->AddUints(ids)}, {"flags", out->AddUints(flags)}};
  Slice view = out->AddAttributeView(Bytes(dihedral), dihedral.size(), 4, "NONE", 0);
  table["dihedral"] = out->AddAccessor(view, kFloat, dihedral.size(), "SCALAR", false);
  if (!faces.empty()) table["faces"] = out->AddUints(faces);
  (*primitive)["extras"].erase("edges");
  (*primitive)["extras"]["edge_table"] = table;
}

using Linear = std::array<double, 9>;

Linear NodeLinear(const Json& node) {
  Linear m = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (node.contains("matrix")) {
    const Json& x = node["matrix"];
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) m[3 * r + k] = x[4 * k + r].get<double>();
    return m;
  }
  if (node.contains("rotation")) {
    const Json& q = node["rotation"];
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    m = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
         2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
         2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
  }
  if (node.contains("scale"))
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) m[3 * r + k] *= node["scale"][k].get<double>();
  return m;
}

// How far a unit step in each mesh's frame can go in the world: the largest column norm of the
// linear part of any node placing it (exact for rotations with uniform scale, which is all the
// plain writer makes). Meshes no node draws count 1.
std::vector<double> MeshScales(const Json& json) {
  std::vector<double> scale(json.contains("meshes") ? json["meshes"].size() : 0, 0.0);
  if (json.contains("nodes") && json.contains("scenes")) {
    std::vector<std::pair<int, Linear>> stack;
    for (const Json& scene : json["scenes"])
      for (const Json& root : scene["nodes"])
        stack.push_back({root.get<int>(), Linear{1, 0, 0, 0, 1, 0, 0, 0, 1}});
    while (!stack.empty()) {
      auto [index, parent] = stack.back();
      stack.pop_back();
      const Json& node = json["nodes"][index];
      const Linear local = NodeLinear(node);
      Linear world{};
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k)
          for (int j = 0; j < 3; ++j) world[3 * r + k] += parent[3 * r + j] * local[3 * j + k];
      if (node.contains("children"))
        for (const Json& child : node["children"]) stack.push_back({child.get<int>(), world});
      if (!node.contains("mesh")) continue;
      double norm = 0;
      for (int k = 0; k < 3; ++k)
        norm = std::max(norm, std::sqrt(world[k] * world[k] + world[3 + k] * world[3 + k] +
                                        world[6 + k] * world[6 + k]));
      double& s = scale[node["mesh"].get<int>()];
      s = std::max(s, norm);
    }
  }
  for (double& s : scale)
    if (!(s > 0)) s = 1.0;
  return scale;
}

// Every node draws the first of its mesh's copies (`alias`), the copies go, and a mesh whose
// positions are on a grid gets it from its node (KHR_mesh_quantization): folded into the node's
// own translation and uniform scale when the node has no children and no matrix, else through a
// new child node that draws the mesh.
void PlaceGrids(Json* json, const std::vector<size_t>& alias, const std::vector<Grid>& grids) {
  if (!json->contains("nodes")) return;
  Json& nodes = (*json)["nodes"];
  for (size_t n = 0, count = nodes.size(); n < count; ++n) {
    if (!nodes[n].contains("mesh")) continue;
    const size_t mesh = alias[nodes[n]["mesh"].get<size_t>()];
    nodes[n]["mesh"] = mesh;
    const Grid& grid = grids[mesh];
    if (!(grid.step > 0)) continue;
    const double offset[3] = {grid.origin[0] * grid.step, grid.origin[1] * grid.step,
                              grid.origin[2] * grid.step};
    const double scale = grid.shorts ? grid.step : 1.0;
    Json& node = nodes[n];
    const Json s = node.value("scale", Json::array({1.0, 1.0, 1.0}));
    if (!node.contains("children") && !node.contains("matrix") && s[0] == s[1] && s[1] == s[2]) {
      const Linear linear = NodeLinear(node);  // rotation times the uniform scale
      Json t = node.value("translation", Json::array({0.0, 0.0, 0.0}));
      for (int r = 0; r < 3; ++r)
        t[r] = t[r].get<double>() + linear[3 * r] * offset[0] + linear[3 * r + 1] * offset[1] +
               linear[3 * r + 2] * offset[2];
      node["translation"] = t;
      const double folded = s[0].get<double>() * scale;
      if (folded != 1.0) node["scale"] = {folded, folded, folded};
      continue;
    }
    Json child = {{"mesh", mesh}, {"translation", {offset[0], offset[1], offset[2]}}};
    if (grid.shorts) child["scale"] = {scale, scale, scale};
    node.erase("mesh");
    nodes.push_back(child);
    nodes[n]["children"].push_back(nodes.size() - 1);
  }
  // Renumber the meshes without the copies.
  Json& meshes = (*json)["meshes"];
  std::vector<size_t> index(alias.size());
  Json kept = Json::array();
  for (size_t m = 0; m < alias.size(); ++m)
    if (alias[m] == m) {
      index[m] = kept.size();
      kept.push_back(std::move(meshes[m]));
    }
  meshes = std::move(kept);
  for (Json& node : nodes)
    if (node.contains("mesh")) node["mesh"] = index[node["mesh"].get<size_t>()];
}

// The plain file draws each solid's edges through a node and a mesh of their own under the root
// node "edges"; the compressed one draws them all through the first, which saves a node, a mesh
// and their accessors per solid. `meshes`: the solids' edge meshes (the first kept); `drop`: the
// other child nodes.
struct EdgeMerge {
  std::vector<size_t> meshes;
  size_t keep = 0;
  std::set<size_t> drop;
};

EdgeMerge FindEdgeMeshes(const Json& json) {
  if (!json.contains("nodes") || !json.contains("meshes")) return {};
  const Json& nodes = json["nodes"];
  for (const Json& node : nodes) {
    if (node.value("name", "") != "edges" || !node.contains("children") || node.contains("mesh"))
      continue;
    EdgeMerge merge;
    for (const Json& c : node["children"]) {
      const Json& child = nodes[c.get<size_t>()];
      if (!child.contains("mesh") || child.contains("children") || child.contains("matrix") ||
          child.contains("translation") || child.contains("rotation") || child.contains("scale"))
        return {};
      const Json& primitives = json["meshes"][child["mesh"].get<size_t>()]["primitives"];
      if (primitives.size() != 1 || primitives[0].value("mode", kTriangles) != kLines) return {};
      merge.meshes.push_back(child["mesh"].get<size_t>());
      if (merge.meshes.size() == 1)
        merge.keep = c.get<size_t>();
      else
        merge.drop.insert(c.get<size_t>());
    }
    if (merge.meshes.size() < 2) return {};
    return merge;
  }
  return {};
}

// Removes the nodes `drop` (no mesh of theirs is drawn elsewhere) and renumbers the others.
void RemoveNodes(Json* json, const std::set<size_t>& drop) {
  Json& nodes = (*json)["nodes"];
  std::vector<int64_t> index(nodes.size(), -1);
  Json kept = Json::array();
  for (size_t n = 0; n < nodes.size(); ++n)
    if (!drop.count(n)) {
      index[n] = static_cast<int64_t>(kept.size());
      kept.push_back(std::move(nodes[n]));
    }
  auto remap = [&](Json* list) {
    Json out = Json::array();
    for (const Json& n : *list)
      if (index[n.get<size_t>()] >= 0) out.push_back(index[n.get<size_t>()]);
    *list = std::move(out);
  };
  for (Json& node : kept)
    if (node.contains("children")) remap(&node["children"]);
  nodes = std::move(kept);
  if (json->contains("scenes"))
    for (Json& scene : (*json)["scenes"])
      if (scene.contains("nodes")) remap(&scene["nodes"]);
}

// The solids' edge primitives as one: vertices and segments one solid after the other, the
// edge tables concatenated, and extras.groups naming each solid's range of segments.
Status ReadMergedEdges(const Json& json, const std::string& bin, const EdgeMerge& merge,
                       Primitive* merged) {
  Json edges = Json::array(), groups = Json::array();
  bool tables = true;
  for (size_t k = 0; k < merge.meshes.size(); ++k) {
    const Json& mesh = json["meshes"][merge.meshes[k]];
    Primitive p;
    if (!ReadPrimitive(json, bin, &mesh["primitives"][0], &p) || p.edge_id.empty())
      return Status(StatusCode::kInternal, "unexpected edge lines");
    if (k == 0) merged->json = p.json, merged->mode = kLines;
    const auto base = static_cast<uint32_t>(merged->position.size() / 3);
    groups.push_back({{"name", mesh.value("name", "")},
                      {"segments", {merged->indices.size() / 2, p.indices.size() / 2}}});
    for (uint32_t i : p.indices) merged->indices.push_back(base + i);
    merged->position.insert(merged->position.end(), p.position.begin(), p.position.end());
    merged->edge_id.insert(merged->edge_id.end(), p.edge_id.begin(), p.edge_id.end());
    if (p.json.contains("extras") && p.json["extras"].contains("edges"))
      for (const Json& e : p.json["extras"]["edges"]) edges.push_back(e);
    else
      tables = false;
  }
  if (tables) merged->json["extras"]["edges"] = std::move(edges);
  merged->json["extras"]["groups"] = std::move(groups);
  return Status::Ok();
}

}  // namespace

Status CompressGlb(const Model& model, const MeshResult& result, double max_shift,
                   const std::string& path, Json* json, std::string* bin) {
  if (json->contains("images") || json->contains("skins") || json->contains("animations"))
    return WriteError(path, "compression covers meshes only; the .glb holds images or skins");
  Builder out;
  const std::vector<double> scales = MeshScales(*json);
  const size_t mesh_count = json->contains("meshes") ? (*json)["meshes"].size() : 0;
  std::vector<Grid> grids(mesh_count);  // per mesh its positions' grid (step 0: none)
  // OCCT writes an instanced part's mesh again for every node that draws it: each mesh equal
  // to an earlier one (same JSON, same scale) is drawn through the earlier one instead.
  std::vector<size_t> alias(mesh_count);
  std::map<std::string, size_t> seen;
  const EdgeMerge edges = FindEdgeMeshes(*json);
  if (!edges.meshes.empty()) {
    (*json)["nodes"][edges.keep]["name"] = "edges of every solid";
    RemoveNodes(json, edges.drop);
  }
  if (json->contains("meshes")) {
    Json& meshes = (*json)["meshes"];
    for (size_t m = 0; m < meshes.size(); ++m) {
      const bool edge_mesh =
          std::find(edges.meshes.begin(), edges.meshes.end(), m) != edges.meshes.end();
      if (edge_mesh && m != edges.meshes[0]) {
        alias[m] = edges.meshes[0];  // drawn by no node any more: dropped with the copies
        continue;
      }
      // Instances' scales differ in the last bits (rotations): nine digits tell them apart; a
      // copy drawn larger by a rounding error keeps within the 1e-9 the check below allows.
      char scale[32];
      std::snprintf(scale, sizeof(scale), "@%.9g", scales[m]);
      alias[m] = seen.emplace(meshes[m].dump() + scale, m).first->second;
      if (alias[m] != m && scales[m] <= scales[alias[m]] * (1 + 1e-10)) continue;
      alias[m] = m;
      std::vector<Primitive> prims;
      if (edge_mesh) {
        prims.emplace_back();
        if (!ReadMergedEdges(*json, *bin, edges, &prims.back()).ok())
          return WriteError(path, "unexpected edge lines from the glTF writer");
        meshes[m]["name"] = "edges of every solid";
      }
      for (const Json& source : meshes[m]["primitives"]) {
        if (edge_mesh) break;
        Primitive p;
        if (!ReadPrimitive(*json, *bin, &source, &p))
          return WriteError(path, "unexpected primitive layout from the glTF writer");
        if (p.mode == kTriangles) p.deviation = TriangleDeviation(result, p);
        prims.push_back(std::move(p));
      }
      MergeByColour(json, &prims);
      for (Primitive& p : prims)
        if (p.mode == kTriangles) Optimise(&p);
      const Grid grid = ChooseGrid(prims, max_shift / scales[m]);
      double shift = 0.0;
      for (Primitive& p : prims) {
        Json attributes = Json::object();
        attributes["POSITION"] = AddPositions(&out, p, grid, &shift);
        if (!p.normal.empty()) attributes["NORMAL"] = AddNormals(&out, p.normal);
        if (!p.face_id.empty()) attributes["_FACE_ID"] = AddIdAttribute(&out, p.face_id);
        if (!p.edge_id.empty()) attributes["_EDGE_ID"] = AddIdAttribute(&out, p.edge_id);
        if (!p.colour.empty()) attributes["COLOR_0"] = AddColours(&out, p.colour);
        Json& target = p.json;
        target["attributes"] = attributes;
        size_t stride = 4;
        const size_t vertices = p.position.size() / 3;
        Slice view = out.AddIndexView(p.indices, vertices, p.mode == kTriangles, &stride);
        target["indices"] = out.AddAccessor(view, stride == 2 ? kUnsignedShort : kUnsignedInt,
                                            p.indices.size(), "SCALAR", false);
        if (!p.deviation.empty())
          target["extras"]["triangle_deviation"] = out.AddBytes(p.deviation);
        if (p.mode == kLines) EdgeTable(&out, &target);
      }
      meshes[m]["primitives"] = Json::array();
      for (Primitive& p : prims) meshes[m]["primitives"].push_back(std::move(p.json));
      if (shift * scales[m] > max_shift * (1 + 1e-9) && grid.step > 0)
        return Status(StatusCode::kInternal, "a compressed position moved " +
                                                 std::to_string(shift * scales[m]) + " (allowed " +
                                                 std::to_string(max_shift) + ")");
      grids[m] = grid;
    }
  }
  PruneMaterials(json);
  PlaceGrids(json, alias, grids);
  // Per face id (entry f - 1): its surface type, an index into `surface_types`.
  std::vector<uint8_t> surface(model.face_count(), static_cast<uint8_t>(SurfaceType::kOther));
  for (const FaceMesh& face : result.faces)
    if (face.face_id >= 1 && face.face_id <= model.face_count())
      surface[face.face_id - 1] = static_cast<uint8_t>(face.surface_type);
  Json names = Json::array();
  for (int t = 0; t <= static_cast<int>(SurfaceType::kOther); ++t)
    names.push_back(SurfaceTypeName(static_cast<SurfaceType>(t)));
  if (model.face_count() > 0)
    (*json)["extras"]["rdmesh"]["faces"] = {{"surface_type", out.AddBytes(surface)},
                                            {"surface_types", names}};
  if (result.summary.requested_deviation > 0) {
    (*json)["extras"]["rdmesh"]["requested_deviation"] = result.summary.requested_deviation;
    (*json)["extras"]["rdmesh"]["deviation_steps"] = kDeviationSteps;
  }

  size_t fallback = 0;
  out.Finish(&(*json)["bufferViews"], bin, &fallback);
  (*json)["accessors"] = out.accessors;
  (*json)["buffers"] =
      Json::array({{{"byteLength", bin->size()}},
                   {{"byteLength", fallback},
                    {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}}});
  for (const char* list : {"extensionsUsed", "extensionsRequired"})
    for (const char* name : {"EXT_meshopt_compression", "KHR_mesh_quantization"}) {
      Json& names_used = (*json)[list];
      if (std::find(names_used.begin(), names_used.end(), name) == names_used.end())
        names_used.push_back(name);
    }
  return Status::Ok();
}

}  // namespace rdmesh
