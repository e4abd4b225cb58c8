#include "assemble.h"

#include <cstring>
#include <utility>
#include <vector>

namespace rdmesh {

namespace {

// A boundary node's B-rep identity: a vertex, or an edge and the bits of its parameter.
struct SharedKey {
  int dim = 0;
  int entity = 0;
  uint64_t bits = 0;
  bool operator==(const SharedKey& o) const {
    return dim == o.dim && entity == o.entity && bits == o.bits;
  }
};

// Boundary node -> mesh node id: open addressing over one array (a node map of a large model
// holds a million entries; one allocation instead of one per entry).
class SharedNodes {
 public:
  explicit SharedNodes(size_t expected) {
    size_t capacity = 16;
    while (capacity < 2 * expected) capacity *= 2;
    slots_.resize(capacity);
  }
  // The id stored for `key`, or `id` after storing it there (second: true) when there is none.
  std::pair<int64_t, bool> Insert(const SharedKey& key, int64_t id) {
    const size_t mask = slots_.size() - 1;
    for (size_t i = Hash(key) & mask;; i = (i + 1) & mask) {
      Slot& slot = slots_[i];
      if (slot.id < 0) {
        slot.key = key, slot.id = id;
        if (++size_ * 2 > slots_.size()) Grow();
        return {id, true};
      }
      if (slot.key == key) return {slot.id, false};
    }
  }

 private:
  struct Slot {
    SharedKey key;
    int64_t id = -1;
  };
  static size_t Hash(const SharedKey& k) {
    uint64_t h = k.bits ^ (static_cast<uint64_t>(static_cast<uint32_t>(k.entity)) << 1 |
                           static_cast<uint64_t>(k.dim));
    h ^= h >> 33;  // the finaliser of MurmurHash3: parameter bits differ mostly at the bottom
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    h ^= h >> 33;
    return static_cast<size_t>(h);
  }
  void Grow() {
    std::vector<Slot> old(2 * slots_.size());
    old.swap(slots_);
    const size_t mask = slots_.size() - 1;
    for (const Slot& s : old) {
      if (s.id < 0) continue;
      size_t i = Hash(s.key) & mask;
      while (slots_[i].id >= 0) i = (i + 1) & mask;
      slots_[i] = s;
    }
  }
  std::vector<Slot> slots_;
  size_t size_ = 0;
};

}  // namespace

void Assemble(std::vector<FaceMesh>* faces, const std::vector<std::vector<NodeRef>>& refs,
              Mesh* mesh) {
  *mesh = Mesh();
  // Per-triangle deviations only when every assembled face has them.
  bool with_deviation = true;
  size_t nodes = 0, triangles = 0, boundary = 0;
  for (size_t fi = 0; fi < faces->size(); ++fi) {
    const FaceMesh& f = (*faces)[fi];
    if (f.status != FaceStatus::kOk) continue;
    if (f.triangle_deviation.size() != static_cast<size_t>(f.triangle_count()))
      with_deviation = false;
    nodes += f.node_count();
    triangles += f.triangle_count();
    for (const NodeRef& r : refs[fi]) boundary += r.dim < 2;
  }
  SharedNodes shared(boundary);
  mesh->xyz.reserve(3 * nodes);
  mesh->node_dim.reserve(nodes);
  mesh->node_entity.reserve(nodes);
  mesh->node_param.reserve(2 * nodes);
  mesh->triangles.reserve(3 * triangles);
  mesh->triangle_face.reserve(triangles);
  if (with_deviation) mesh->triangle_deviation.reserve(triangles);
  for (size_t fi = 0; fi < faces->size(); ++fi) {
    FaceMesh& f = (*faces)[fi];
    f.global_ids.clear();
    if (f.status != FaceStatus::kOk) continue;
    f.global_ids.reserve(f.node_count());
    for (int i = 0; i < f.node_count(); ++i) {
      const NodeRef& r = refs[fi][i];
      int64_t id = mesh->node_count();
      if (r.dim < 2) {
        uint64_t bits = 0;
        if (r.dim == 1) std::memcpy(&bits, &r.t, sizeof bits);
        auto [known, inserted] = shared.Insert(SharedKey{r.dim, r.entity, bits}, id);
        if (!inserted) {
          f.global_ids.push_back(known);
          continue;
        }
      }
      f.global_ids.push_back(id);
      mesh->xyz.insert(mesh->xyz.end(), {f.xyz[3 * i], f.xyz[3 * i + 1], f.xyz[3 * i + 2]});
      mesh->node_dim.push_back(static_cast<int8_t>(r.dim));
      mesh->node_entity.push_back(r.dim == 2 ? f.face_id : r.entity);
      if (r.dim == 2)
        mesh->node_param.insert(mesh->node_param.end(), {f.uv[2 * i], f.uv[2 * i + 1]});
      else
        mesh->node_param.insert(mesh->node_param.end(), {r.dim == 1 ? r.t : 0.0, 0.0});
    }
    for (size_t k = 0; k + 2 < f.triangles.size(); k += 3) {
      int64_t a = f.global_ids[f.triangles[k]], b = f.global_ids[f.triangles[k + 1]],
              c = f.global_ids[f.triangles[k + 2]];
      if (a == b || b == c || c == a) continue;  // collapsed at a pole
      mesh->triangles.insert(
          mesh->triangles.end(),
          {static_cast<int32_t>(a), static_cast<int32_t>(b), static_cast<int32_t>(c)});
      mesh->triangle_face.push_back(f.face_id);
      if (with_deviation) mesh->triangle_deviation.push_back(f.triangle_deviation[k / 3]);
    }
  }
}

}  // namespace rdmesh
