#include "model/model_info.h"

#include <BRepBndLib.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Iterator.hxx>
#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <utility>
#include <vector>

#include "core/parallel.h"
#include "geometry/surface_type.h"
#include "model/face_boxes.h"
#include "model/xcaf_api.h"

namespace rdmesh {

namespace {

int CountShapes(const TopoDS_Shape& shape, TopAbs_ShapeEnum type) {
  TopTools_IndexedMapOfShape map;
  TopExp::MapShapes(shape, type, map);
  return map.Extent();
}

// Every non-degenerate edge bounds exactly two faces, a seam counting twice for its face.
bool IsClosed(const TopoDS_Shape& shape) {
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  if (edge_faces.IsEmpty()) return false;
  for (int i = 1; i <= edge_faces.Extent(); ++i) {
    const TopoDS_Edge& edge = TopoDS::Edge(edge_faces.FindKey(i));
    if (BRep_Tool::Degenerated(edge)) continue;
    TopTools_IndexedMapOfShape faces;  // distinct faces (the list repeats seams and shared faces)
    for (const TopoDS_Shape& face : edge_faces(i)) faces.Add(face);
    int uses = 0;
    for (int f = 1; f <= faces.Extent(); ++f)
      uses += BRep_Tool::IsClosed(edge, TopoDS::Face(faces(f))) ? 2 : 1;
    if (uses != 2) return false;
  }
  return true;
}

// Without a document: every non-compound shape under the top compounds is one instance.
int CountLeafShapes(const TopoDS_Shape& shape) {
  if (shape.ShapeType() != TopAbs_COMPOUND) return 1;
  int count = 0;
  for (TopoDS_Iterator it(shape); it.More(); it.Next()) count += CountLeafShapes(it.Value());
  return count;
}

// Whether face `id` takes its representative's box, moved: an instanced face placed by a
// translation.
bool ReusesBox(const Model& model, int id) {
  const gp_Trsf& placement = model.face_placement[id - 1];
  return model.face_representative[id - 1] != id &&
         (placement.Form() == gp_Identity || placement.Form() == gp_Translation);
}

// Surface types whose loose box (BRepBndLib::Add: poles, analytic bounds or boundary edges,
// enlarged by the tolerances) is known to hold the face; other types are always boxed tightly.
bool LooseBoxHolds(SurfaceType type) {
  switch (type) {
    case SurfaceType::kPlane:
    case SurfaceType::kCylinder:
    case SurfaceType::kCone:
    case SurfaceType::kSphere:
    case SurfaceType::kTorus:
    case SurfaceType::kBezier:
    case SurfaceType::kBSpline:
      return true;
    default:
      return false;
  }
}

// Surface types whose faces SampledFaceBox boxes (where it returns a box): AddOptimal's surface
// optimiser is the slowest part of loading files with such faces.
bool SampledFaces(SurfaceType type) {
  switch (type) {
    case SurfaceType::kBezier:
    case SurfaceType::kBSpline:
    case SurfaceType::kRevolution:
    case SurfaceType::kOffset:
    case SurfaceType::kOther:
      return true;
    default:
      return false;
  }
}

// Whether `inner`, grown by `margin`, lies inside `outer` (neither void nor open).
bool Inside(const Bnd_Box& inner, const Bnd_Box& outer, double margin) {
  if (inner.IsVoid() || outer.IsVoid() || inner.IsOpen() || outer.IsOpen()) return false;
  double a[6], b[6];
  inner.Get(a[0], a[1], a[2], a[3], a[4], a[5]);
  outer.Get(b[0], b[1], b[2], b[3], b[4], b[5]);
  for (int k = 0; k < 3; ++k) {
    if (a[k] - margin < b[k] || a[k + 3] + margin > b[k + 3]) return false;
  }
  return true;
}

// The tight box of all faces (as the yardstick computes it): the union of every face's
// BRepBndLib::AddOptimal box, where an instanced face placed by a translation moves its
// representative's. AddOptimal is the slow part of loading, so it runs on all cores, and only
// where it can change the union: first on the faces whose cheap loose box reaches furthest in
// each of the six directions (and on every face of a type whose loose box is not known to hold
// it), then on each face whose loose box, grown by a margin, is not inside that first union. A
// face skipped so has its tight box inside its loose box, inside the union: the union is the
// same as with every face boxed.
// `types` holds each face's surface type (FaceSurfaceType).
Bnd_Box BoundingBox(const Model& model, const std::vector<SurfaceType>& types) {
  const int nf = model.face_count();
  std::vector<Bnd_Box> tight(nf), loose(nf);
  std::vector<char> holds(nf, 0), computed(nf, 0);
  std::vector<int> owners;  // faces with a box of their own
  for (int id = 1; id <= nf; ++id) {
    if (!ReusesBox(model, id)) owners.push_back(id);
  }
  const ParallelRunner runner(0);
  runner.For(0, static_cast<int>(owners.size()), [&](int i) {
    const int id = owners[i];
    holds[id - 1] = LooseBoxHolds(types[id - 1]);
    if (types[id - 1] == SurfaceType::kTorus || types[id - 1] == SurfaceType::kSphere) {
      // Tight in closed form: the optimiser's slowest cases otherwise.
      tight[id - 1] = ClosedFormFaceBox(model.face(id));
      if (!tight[id - 1].IsVoid()) {
        loose[id - 1] = tight[id - 1];
        computed[id - 1] = 1;
        return;
      }
    }
    if (holds[id - 1]) {
      BRepBndLib::Add(model.face(id), loose[id - 1], /*useTriangulation=*/false);
    } else if (types[id - 1] == SurfaceType::kRevolution ||
               types[id - 1] == SurfaceType::kExtrusion) {
      loose[id - 1] = SweptFaceBox(model.face(id));
      holds[id - 1] = !loose[id - 1].IsVoid();
    }
  });
  // The box a face contributes, loose or tight, from its own or its representative's.
  auto moved = [&](const std::vector<Bnd_Box>& boxes, int id) {
    if (!ReusesBox(model, id)) return boxes[id - 1];
    return boxes[model.face_representative[id - 1] - 1].Transformed(model.face_placement[id - 1]);
  };
  auto owner_of = [&](int id) {
    return ReusesBox(model, id) ? model.face_representative[id - 1] : id;
  };
  auto compute = [&](const std::vector<int>& wanted) {  // owners, each once
    std::vector<int> todo;
    for (int id : wanted) {
      if (!computed[id - 1]) computed[id - 1] = 1, todo.push_back(id);
    }
    runner.For(
        0, static_cast<int>(todo.size()),
        [&](int i) {
          const int id = todo[i];
          if (SampledFaces(types[id - 1])) {
            tight[id - 1] = SampledFaceBox(model.face(id));
            if (!tight[id - 1].IsVoid()) return;
          }
          BRepBndLib::AddOptimal(model.face(id), tight[id - 1],
                                 /*useTriangulation=*/false, /*useShapeTolerance=*/false);
        },
        Partition::kOnePerTask);
  };
  // Round 1: the faces of other types, and per direction the kSeeds reaching furthest.
  constexpr int kSeeds = 4;
  std::vector<int> first;
  std::vector<std::pair<double, int>> reach[6];
  for (int id = 1; id <= nf; ++id) {
    const Bnd_Box box = moved(loose, id);
    if (!holds[owner_of(id) - 1] || box.IsVoid() || box.IsOpen()) {
      first.push_back(owner_of(id));
      continue;
    }
    double c[6];
    box.Get(c[0], c[1], c[2], c[3], c[4], c[5]);
    for (int k = 0; k < 6; ++k) reach[k].push_back({k < 3 ? -c[k] : c[k], id});
  }
  for (auto& candidates : reach) {
    const int n = std::min<int>(kSeeds, static_cast<int>(candidates.size()));
    std::partial_sort(candidates.begin(), candidates.begin() + n, candidates.end(),
                      std::greater<>());
    for (int i = 0; i < n; ++i) first.push_back(owner_of(candidates[i].second));
  }
  compute(first);
  Bnd_Box seed;
  for (int id = 1; id <= nf; ++id) {
    if (computed[owner_of(id) - 1]) seed.Add(moved(tight, id));
  }
  // Round 2: every face whose loose box is not inside the first union by a margin.
  const double margin = seed.IsVoid() ? 0.0 : 1e-7 * std::sqrt(seed.SquareExtent());
  std::vector<int> second;
  for (int id = 1; id <= nf; ++id) {
    if (!computed[owner_of(id) - 1] && !Inside(moved(loose, id), seed, margin)) {
      second.push_back(owner_of(id));
    }
  }
  compute(second);
  Bnd_Box all;
  for (int id = 1; id <= nf; ++id) {
    if (computed[owner_of(id) - 1]) all.Add(moved(tight, id));
  }
  return all;
}

}  // namespace

ModelInfo ComputeModelInfo(const Model& model, bool bounding_box) {
  ModelInfo info;
  info.faces = model.face_count();
  info.edges = model.edge_count();
  info.vertices = model.vertices.Extent();
  info.solids = CountShapes(model.shape, TopAbs_SOLID);
  info.shells = CountShapes(model.shape, TopAbs_SHELL);

  std::vector<SurfaceType> types(info.faces, SurfaceType::kOther);
  for (int id = 1; id <= info.faces; ++id) {
    int rep = model.face_representative[id - 1];
    if (rep == id) {
      ++info.unique_faces;
      types[id - 1] = FaceSurfaceType(model.face(id));
    } else {
      types[id - 1] = types[rep - 1];
    }
    ++info.surface_types[SurfaceTypeName(types[id - 1])];
  }

  Bnd_Box box;
  if (bounding_box) box = BoundingBox(model, types);
  if (!box.IsVoid()) {
    box.Get(info.bbox[0], info.bbox[1], info.bbox[2], info.bbox[3], info.bbox[4], info.bbox[5]);
    double dx = info.bbox[3] - info.bbox[0], dy = info.bbox[4] - info.bbox[1],
           dz = info.bbox[5] - info.bbox[2];
    info.diagonal = std::sqrt(dx * dx + dy * dy + dz * dz);
  }

  if (!model.doc.IsNull()) {
    // A document has been built or read in this process, so its framework is at hand.
    Result<const XcafApi*> xcaf = Xcaf();
    if (xcaf.ok()) (*xcaf)->walk_parts(model.doc, &info.instances, &info.part_names);
  } else {
    info.instances = CountLeafShapes(model.shape);
  }
  info.closed = IsClosed(model.shape);
  return info;
}

}  // namespace rdmesh
