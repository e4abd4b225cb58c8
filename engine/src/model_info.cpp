#include "model_info.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <TCollection_AsciiString.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Iterator.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <algorithm>
#include <cmath>
#include <set>

#include "parallel.h"

namespace rdmesh {

SurfaceType FaceSurfaceType(const TopoDS_Face& face) {
  switch (BRepAdaptor_Surface(face, Standard_False).GetType()) {
    case GeomAbs_Plane:
      return SurfaceType::kPlane;
    case GeomAbs_Cylinder:
      return SurfaceType::kCylinder;
    case GeomAbs_Cone:
      return SurfaceType::kCone;
    case GeomAbs_Sphere:
      return SurfaceType::kSphere;
    case GeomAbs_Torus:
      return SurfaceType::kTorus;
    case GeomAbs_BezierSurface:
      return SurfaceType::kBezier;
    case GeomAbs_BSplineSurface:
      return SurfaceType::kBSpline;
    case GeomAbs_SurfaceOfRevolution:
      return SurfaceType::kRevolution;
    case GeomAbs_SurfaceOfExtrusion:
      return SurfaceType::kExtrusion;
    case GeomAbs_OffsetSurface:
      return SurfaceType::kOffset;
    default:
      return SurfaceType::kOther;
  }
}

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

std::string LabelName(const TDF_Label& label) {
  Handle(TDataStd_Name) name;
  if (!label.FindAttribute(TDataStd_Name::GetID(), name)) return "";
  return TCollection_AsciiString(name->Get()).ToCString();  // UTF-8
}

// Walks the assembly tree from `label`: counts placed leaf parts and collects part names.
void WalkParts(const TDF_Label& label, int* instances, std::vector<std::string>* names,
               std::set<std::string>* seen) {
  TDF_Label part = label;
  TDF_Label referred;
  if (XCAFDoc_ShapeTool::IsReference(label) && XCAFDoc_ShapeTool::GetReferredShape(label, referred))
    part = referred;
  if (XCAFDoc_ShapeTool::IsAssembly(part)) {
    TDF_LabelSequence components;
    XCAFDoc_ShapeTool::GetComponents(part, components);
    for (const TDF_Label& component : components) WalkParts(component, instances, names, seen);
    return;
  }
  ++*instances;
  std::string name = LabelName(part);
  if (!name.empty() && seen->insert(name).second) names->push_back(name);
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

// The tight box of all faces (as the yardstick computes it). AddOptimal is the slow part of
// loading: it runs on all cores, one face at a time; the reused boxes and the union follow in
// face order.
Bnd_Box BoundingBox(const Model& model) {
  std::vector<Bnd_Box> face_boxes(model.face_count());
  std::vector<int> optimal;
  for (int id = 1; id <= model.face_count(); ++id) {
    if (!ReusesBox(model, id)) optimal.push_back(id);
  }
  ParallelRunner(0).For(
      0, static_cast<int>(optimal.size()),
      [&](int i) {
        BRepBndLib::AddOptimal(model.face(optimal[i]), face_boxes[optimal[i] - 1],
                               /*useTriangulation=*/false, /*useShapeTolerance=*/false);
      },
      Partition::kOnePerTask);
  Bnd_Box all;
  for (int id = 1; id <= model.face_count(); ++id) {
    Bnd_Box& box = face_boxes[id - 1];
    if (ReusesBox(model, id)) {
      box = face_boxes[model.face_representative[id - 1] - 1].Transformed(
          model.face_placement[id - 1]);
    }
    all.Add(box);
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
  if (bounding_box) box = BoundingBox(model);
  if (!box.IsVoid()) {
    box.Get(info.bbox[0], info.bbox[1], info.bbox[2], info.bbox[3], info.bbox[4], info.bbox[5]);
    double dx = info.bbox[3] - info.bbox[0], dy = info.bbox[4] - info.bbox[1],
           dz = info.bbox[5] - info.bbox[2];
    info.diagonal = std::sqrt(dx * dx + dy * dy + dz * dz);
  }

  if (!model.doc.IsNull()) {
    Handle(XCAFDoc_ShapeTool) shape_tool = XCAFDoc_DocumentTool::ShapeTool(model.doc->Main());
    TDF_LabelSequence free_labels;
    shape_tool->GetFreeShapes(free_labels);
    std::set<std::string> seen;
    for (const TDF_Label& label : free_labels)
      WalkParts(label, &info.instances, &info.part_names, &seen);
  } else {
    info.instances = CountLeafShapes(model.shape);
  }
  info.closed = IsClosed(model.shape);
  return info;
}

}  // namespace rdmesh
