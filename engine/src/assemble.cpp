#include "assemble.h"

#include <cstring>
#include <map>
#include <tuple>

namespace rdmesh {

void Assemble(std::vector<FaceMesh>* faces, const std::vector<std::vector<NodeRef>>& refs,
              Mesh* mesh) {
  *mesh = Mesh();
  std::map<std::tuple<int, int, uint64_t>, int64_t> shared;  // (dim, entity, t bits) -> id
  // Per-triangle deviations only when every assembled face has them.
  bool with_deviation = true;
  for (const FaceMesh& f : *faces)
    if (f.status == FaceStatus::kOk &&
        f.triangle_deviation.size() != static_cast<size_t>(f.triangle_count()))
      with_deviation = false;
  for (size_t fi = 0; fi < faces->size(); ++fi) {
    FaceMesh& f = (*faces)[fi];
    f.global_ids.clear();
    if (f.status != FaceStatus::kOk) continue;
    for (int i = 0; i < f.node_count(); ++i) {
      const NodeRef& r = refs[fi][i];
      int64_t id = mesh->node_count();
      if (r.dim < 2) {
        uint64_t bits = 0;
        if (r.dim == 1) std::memcpy(&bits, &r.t, sizeof bits);
        auto [it, inserted] = shared.emplace(std::make_tuple(r.dim, r.entity, bits), id);
        if (!inserted) {
          f.global_ids.push_back(it->second);
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
