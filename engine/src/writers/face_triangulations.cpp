#include "writers/face_triangulations.h"

#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gp_Pnt2d.hxx>

namespace rdmesh {

namespace {

std::mutex& LendMutex() {
  static std::mutex mutex;
  return mutex;
}

bool HasMesh(const MeshResult& result, int face_id) {
  if (face_id < 1 || face_id > static_cast<int>(result.faces.size())) return false;
  const FaceMesh& face = result.faces[face_id - 1];
  return face.status == FaceStatus::kOk && face.triangle_count() > 0;
}

// `face`'s mesh in the frame and orientation of its TShape; with `uv_id` > 0, every node's
// (u, v) is (uv_id, 0).
Handle(Poly_Triangulation) ToTShapeFrame(const TopoDS_Face& face, const FaceMesh& mesh, int uv_id) {
  gp_Trsf to_world = face.Location().Transformation();
  gp_Trsf to_local = to_world.Inverted();
  bool mirrored = to_world.VectorialPart().Determinant() < 0.0;
  bool reversed = face.Orientation() == TopAbs_REVERSED;
  int nodes = static_cast<int>(mesh.node_count());
  int triangles = static_cast<int>(mesh.triangle_count());
  bool has_uv = uv_id > 0 || mesh.uv.size() == 2 * mesh.xyz.size() / 3;
  bool has_normals = mesh.normals.size() == mesh.xyz.size();
  Handle(Poly_Triangulation) triangulation =
      new Poly_Triangulation(nodes, triangles, has_uv, has_normals);
  for (int i = 0; i < nodes; ++i) {
    gp_Pnt p(mesh.xyz[3 * i], mesh.xyz[3 * i + 1], mesh.xyz[3 * i + 2]);
    triangulation->SetNode(i + 1, p.Transformed(to_local));
    if (uv_id > 0)
      triangulation->SetUVNode(i + 1, gp_Pnt2d(uv_id, 0.0));
    else if (has_uv)
      triangulation->SetUVNode(i + 1, gp_Pnt2d(mesh.uv[2 * i], mesh.uv[2 * i + 1]));
    if (has_normals) {
      gp_XYZ n(mesh.normals[3 * i], mesh.normals[3 * i + 1], mesh.normals[3 * i + 2]);
      n.Multiply(to_local.VectorialPart());  // no translation
      if (reversed) n.Reverse();
      triangulation->SetNormal(i + 1, n.Modulus() > 0.0 ? gp_Dir(n) : gp_Dir(0.0, 0.0, 1.0));
    }
  }
  bool flip = reversed != mirrored;
  for (int t = 0; t < triangles; ++t) {
    int a = mesh.triangles[3 * t] + 1;
    int b = mesh.triangles[3 * t + 1] + 1;
    int c = mesh.triangles[3 * t + 2] + 1;
    triangulation->SetTriangle(t + 1, flip ? Poly_Triangle(a, c, b) : Poly_Triangle(a, b, c));
  }
  return triangulation;
}

}  // namespace

ScopedFaceTriangulations::ScopedFaceTriangulations(const Model& model, const MeshResult& result,
                                                   bool uv_face_ids)
    : lock_(LendMutex()) {
  int count = model.face_count();
  std::vector<int> source(count + 1, 0);  // representative id -> face id whose mesh it lends
  for (int id = 1; id <= count; ++id) {
    int rep = model.face_representative[id - 1];
    if (source[rep] == 0 && HasMesh(result, id)) source[rep] = id;
  }
  for (int id = 1; id <= count; ++id) {
    if (model.face_representative[id - 1] != id) continue;  // one TShape per class
    const TopoDS_Face& face = model.face(id);
    Handle(BRep_TFace) tface = Handle(BRep_TFace)::DownCast(face.TShape());
    if (tface.IsNull()) continue;
    saved_.push_back({tface, tface->Triangulations(), tface->ActiveTriangulation()});
    int from = source[id];
    Handle(Poly_Triangulation) triangulation =
        from == 0 ? Handle(Poly_Triangulation)()
                  : ToTShapeFrame(model.face(from), result.faces[from - 1], uv_face_ids ? id : 0);
    tface->Triangulation(triangulation, /*theToReset=*/true);
  }
}

ScopedFaceTriangulations::~ScopedFaceTriangulations() {
  for (Saved& saved : saved_) saved.tface->Triangulations(saved.triangulations, saved.active);
}

Handle(TDocStd_Document) DocumentForWriting(const Model& model) {
  if (!model.doc.IsNull()) return model.doc;
  Handle(TDocStd_Document) doc = new TDocStd_Document("MDTV-XCAF");
  XCAFApp_Application::GetApplication()->InitDocument(doc);
  XCAFDoc_DocumentTool::ShapeTool(doc->Main())->AddShape(model.shape, /*makeAssembly=*/true);
  return doc;
}

}  // namespace rdmesh
