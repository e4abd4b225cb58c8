#include "assembly/assemble.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <functional>
#include <iterator>
#include <utility>
#include <vector>

#include "core/parallel.h"

namespace rdmesh {

namespace {

// A boundary node's B-rep identity: a vertex, or an edge and the bits of its parameter.
struct SharedKey {
  uint64_t bits = 0;
  uint32_t entity_dim = 0;  // entity id x 2 + dim
  bool operator==(const SharedKey& o) const { return bits == o.bits && entity_dim == o.entity_dim; }
};

// Boundary node -> mesh node id: open addressing over one array of 16-byte slots (a node map of
// a large model holds a million entries; one allocation instead of one per entry, and new memory
// costs a page fault per 4 KiB).
class SharedNodes {
 public:
  // Room for `expected` keys at half load; it grows past that.
  explicit SharedNodes(size_t expected) {
    size_t capacity = 16;
    while (capacity < 2 * expected) capacity *= 2;
    slots_.resize(capacity);
  }
  // The id stored for `key`, or `id` after storing it there (second: true) when there is none.
  std::pair<int64_t, bool> Insert(const SharedKey& key, int32_t id) {
    const size_t mask = slots_.size() - 1;
    for (size_t i = Hash(key) & mask;; i = (i + 1) & mask) {
      Slot& slot = slots_[i];
      if (slot.id < 0) {
        slot.bits = key.bits, slot.entity_dim = key.entity_dim, slot.id = id;
        if (++size_ * 2 > slots_.size()) Grow();
        return {id, true};
      }
      if (slot.key() == key) return {slot.id, false};
    }
  }

 private:
  struct Slot {
    uint64_t bits = 0;
    uint32_t entity_dim = 0;
    int32_t id = -1;  // mesh node ids are int32 (Mesh::triangles)
    SharedKey key() const { return {bits, entity_dim}; }
  };
  static_assert(sizeof(Slot) == 16);
  static size_t Hash(const SharedKey& k) {
    uint64_t h = k.bits ^ k.entity_dim;
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
      size_t i = Hash(s.key()) & mask;
      while (slots_[i].id >= 0) i = (i + 1) & mask;
      slots_[i] = s;
    }
  }
  std::vector<Slot> slots_;
  size_t size_ = 0;
};

}  // namespace

void Assemble(std::vector<FaceMesh>* faces, const std::vector<std::vector<NodeRef>>& refs,
              Mesh* mesh, int threads) {
  *mesh = Mesh();
  const int nf = static_cast<int>(faces->size());
  // Per-triangle deviations only when every assembled face has them.
  bool with_deviation = true;
  size_t boundary = 0;
  for (int fi = 0; fi < nf; ++fi) {
    const FaceMesh& f = (*faces)[fi];
    if (f.status != FaceStatus::kOk) continue;
    if (f.triangle_deviation.size() != static_cast<size_t>(f.triangle_count()))
      with_deviation = false;
    for (const NodeRef& r : refs[fi]) boundary += r.dim < 2;
  }
  // 1. Node ids, serially in face order: a node is new unless a boundary node with its B-rep
  // identity came before it. `fresh` marks the new ones, which take the next id. The map starts
  // with room for half the boundary references: most boundary nodes lie on two faces.
  SharedNodes shared(boundary / 2);
  std::vector<std::vector<uint8_t>> fresh(nf);
  int64_t nodes = 0;
  for (int fi = 0; fi < nf; ++fi) {
    FaceMesh& f = (*faces)[fi];
    f.global_ids.clear();
    if (f.status != FaceStatus::kOk) continue;
    f.global_ids.resize(f.node_count());
    fresh[fi].assign(f.node_count(), 1);
    for (int i = 0; i < f.node_count(); ++i) {
      const NodeRef& r = refs[fi][i];
      if (r.dim < 2) {
        uint64_t bits = 0;
        if (r.dim == 1) std::memcpy(&bits, &r.t, sizeof bits);
        const SharedKey key{bits,
                            static_cast<uint32_t>(r.entity) << 1 | static_cast<uint32_t>(r.dim)};
        auto [known, inserted] = shared.Insert(key, static_cast<int32_t>(nodes));
        if (!inserted) {
          f.global_ids[i] = known;
          fresh[fi][i] = 0;
          continue;
        }
      }
      f.global_ids[i] = nodes++;
    }
  }
  // 2. Per face, its first triangle (triangles collapsed at a pole are dropped).
  std::vector<int64_t> first_triangle(nf + 1, 0);
  const ParallelRunner runner(threads);
  runner.For(0, nf, [&](int fi) {
    const FaceMesh& f = (*faces)[fi];
    if (f.status != FaceStatus::kOk) return;
    int64_t kept = 0;
    for (size_t k = 0; k + 2 < f.triangles.size(); k += 3) {
      const int64_t a = f.global_ids[f.triangles[k]], b = f.global_ids[f.triangles[k + 1]],
                    c = f.global_ids[f.triangles[k + 2]];
      kept += a != b && b != c && c != a;
    }
    first_triangle[fi + 1] = kept;
  });
  for (int fi = 0; fi < nf; ++fi) first_triangle[fi + 1] += first_triangle[fi];
  // 3. The arrays are sized on all threads: they are new memory, and its first touch costs a
  // page fault per 4 KiB. Then every face writes its own new nodes and its triangles.
  const int64_t triangles = first_triangle[nf];
  const std::function<void()> sizes[] = {
      [&] { mesh->xyz.resize(3 * nodes); },
      [&] { mesh->triangles.resize(3 * triangles); },
      [&] { mesh->node_param.resize(2 * nodes); },
      [&] { mesh->triangle_deviation.resize(with_deviation ? triangles : 0); },
      [&] { mesh->triangle_face.resize(triangles); },
      [&] { mesh->node_entity.resize(nodes); },
      [&] { mesh->node_dim.resize(nodes); },
  };
  runner.For(
      0, std::size(sizes), [&](int i) { sizes[i](); }, Partition::kOnePerTask);
  runner.For(0, nf, [&](int fi) {
    const FaceMesh& f = (*faces)[fi];
    if (f.status != FaceStatus::kOk) return;
    for (int i = 0; i < f.node_count(); ++i) {
      if (!fresh[fi][i]) continue;
      const NodeRef& r = refs[fi][i];
      const int64_t id = f.global_ids[i];
      std::copy_n(&f.xyz[3 * i], 3, &mesh->xyz[3 * id]);
      mesh->node_dim[id] = static_cast<int8_t>(r.dim);
      mesh->node_entity[id] = r.dim == 2 ? f.face_id : r.entity;
      if (r.dim == 2) {
        mesh->node_param[2 * id] = f.uv[2 * i], mesh->node_param[2 * id + 1] = f.uv[2 * i + 1];
      } else {
        mesh->node_param[2 * id] = r.dim == 1 ? r.t : 0.0, mesh->node_param[2 * id + 1] = 0.0;
      }
    }
    int64_t t = first_triangle[fi];
    for (size_t k = 0; k + 2 < f.triangles.size(); k += 3) {
      const int64_t a = f.global_ids[f.triangles[k]], b = f.global_ids[f.triangles[k + 1]],
                    c = f.global_ids[f.triangles[k + 2]];
      if (a == b || b == c || c == a) continue;  // collapsed at a pole
      mesh->triangles[3 * t] = static_cast<int32_t>(a);
      mesh->triangles[3 * t + 1] = static_cast<int32_t>(b);
      mesh->triangles[3 * t + 2] = static_cast<int32_t>(c);
      mesh->triangle_face[t] = f.face_id;
      if (with_deviation) mesh->triangle_deviation[t] = f.triangle_deviation[k / 3];
      ++t;
    }
  });
}

}  // namespace rdmesh
