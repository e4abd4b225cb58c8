// brepmesh_runner: the OpenCASCADE BRepMesh reference for the benchmark (bench/run_bench.py).
//
//   brepmesh_runner MODEL.step DEFLECTION ANGLE OUT.msh
//
// Meshes every face of MODEL.step with BRepMesh_IncrementalMesh at an absolute linear
// deflection DEFLECTION (model units, as a user asking for a max deviation would set it) and an
// angular deflection ANGLE (radians), in parallel over faces. Writes OUT.msh as MSH 4.1 ASCII
// with one surface entity per face (entity tag = 1-based face index in TopExp order, the order
// the yardstick uses too), so the same scorer evaluates BRepMesh and rdmesh. Prints one JSON
// line on stdout:
//   {"mesher": "brepmesh", "seconds": S, "triangles": N, "faces": F, "faces_meshed": M, ...}
// `seconds` is the BRepMesh call alone: loading the STEP file and writing the mesh are not timed,
// matching rdmesh's own `seconds`.

#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IMeshTools_Parameters.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Poly_Triangulation.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace {

// One face's triangulation in world coordinates, oriented along the face's outward normal.
struct FaceMesh {
  std::vector<gp_Pnt> nodes;
  std::vector<std::array<int, 3>> triangles;  // 0-based indices into nodes
};

bool ReadStep(const std::string& path, TopoDS_Shape* shape) {
  STEPControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) return false;
  reader.TransferRoots();
  *shape = reader.OneShape();
  return !shape->IsNull();
}

FaceMesh ExtractFace(const TopoDS_Face& face) {
  FaceMesh mesh;
  TopLoc_Location location;
  Handle(Poly_Triangulation) triangulation = BRep_Tool::Triangulation(face, location);
  if (triangulation.IsNull()) return mesh;
  const gp_Trsf placement = location.Transformation();
  mesh.nodes.reserve(triangulation->NbNodes());
  for (int i = 1; i <= triangulation->NbNodes(); ++i)
    mesh.nodes.push_back(triangulation->Node(i).Transformed(placement));
  const bool reversed = face.Orientation() == TopAbs_REVERSED;
  mesh.triangles.reserve(triangulation->NbTriangles());
  for (int i = 1; i <= triangulation->NbTriangles(); ++i) {
    int n1 = 0, n2 = 0, n3 = 0;
    triangulation->Triangle(i).Get(n1, n2, n3);
    if (reversed) std::swap(n2, n3);
    mesh.triangles.push_back({n1 - 1, n2 - 1, n3 - 1});
  }
  return mesh;
}

// MSH 4.1 ASCII: one node block and one triangle block per meshed face; node tags are global
// and consecutive; faces that got no triangles are left out (the scorer counts them uncovered).
bool WriteMsh(const std::string& path, const std::vector<FaceMesh>& faces) {
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (out == nullptr) return false;
  long blocks = 0, node_count = 0, triangle_count = 0;
  for (const FaceMesh& f : faces) {
    if (f.triangles.empty()) continue;
    ++blocks;
    node_count += static_cast<long>(f.nodes.size());
    triangle_count += static_cast<long>(f.triangles.size());
  }
  std::fprintf(out, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
  std::fprintf(out, "$Nodes\n%ld %ld 1 %ld\n", blocks, node_count, node_count);
  std::vector<long> first_tag(faces.size(), 0);
  long next_tag = 1;
  for (size_t i = 0; i < faces.size(); ++i) {
    const FaceMesh& f = faces[i];
    if (f.triangles.empty()) continue;
    first_tag[i] = next_tag;
    std::fprintf(out, "2 %zu 0 %zu\n", i + 1, f.nodes.size());
    for (size_t k = 0; k < f.nodes.size(); ++k)
      std::fprintf(out, "%ld\n", next_tag + static_cast<long>(k));
    for (const gp_Pnt& p : f.nodes) std::fprintf(out, "%.17g %.17g %.17g\n", p.X(), p.Y(), p.Z());
    next_tag += static_cast<long>(f.nodes.size());
  }
  std::fprintf(out, "$EndNodes\n$Elements\n%ld %ld 1 %ld\n", blocks, triangle_count,
               triangle_count);
  long element = 1;
  for (size_t i = 0; i < faces.size(); ++i) {
    const FaceMesh& f = faces[i];
    if (f.triangles.empty()) continue;
    std::fprintf(out, "2 %zu 2 %zu\n", i + 1, f.triangles.size());
    for (const auto& t : f.triangles)
      std::fprintf(out, "%ld %ld %ld %ld\n", element++, first_tag[i] + t[0], first_tag[i] + t[1],
                   first_tag[i] + t[2]);
  }
  std::fprintf(out, "$EndElements\n");
  return std::fclose(out) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: brepmesh_runner MODEL.step DEFLECTION ANGLE OUT.msh\n");
    return 2;
  }
  const std::string step = argv[1], out = argv[4];
  const double deflection = std::atof(argv[2]), angle = std::atof(argv[3]);
  if (!(deflection > 0) || !(angle > 0)) {
    std::fprintf(stderr, "brepmesh_runner: DEFLECTION and ANGLE must be positive\n");
    return 2;
  }
  // OCCT's reader talks on stdout; keep stdout for the one JSON line.
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer));

  TopoDS_Shape shape;
  if (!ReadStep(step, &shape)) {
    std::fprintf(stderr, "brepmesh_runner: cannot read %s\n", step.c_str());
    return 3;
  }
  TopTools_IndexedMapOfShape face_map;
  TopExp::MapShapes(shape, TopAbs_FACE, face_map);

  IMeshTools_Parameters parameters;
  parameters.Deflection = deflection;
  parameters.Angle = angle;
  parameters.Relative = Standard_False;
  parameters.InParallel = Standard_True;

  const auto start = std::chrono::steady_clock::now();
  try {
    BRepMesh_IncrementalMesh mesher(shape, parameters);
  } catch (const Standard_Failure& failure) {
    std::fprintf(stderr, "brepmesh_runner: BRepMesh failed: %s\n", failure.GetMessageString());
    return 4;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<FaceMesh> faces;
  faces.reserve(face_map.Extent());
  long triangles = 0;
  int faces_meshed = 0;
  for (int i = 1; i <= face_map.Extent(); ++i) {
    faces.push_back(ExtractFace(TopoDS::Face(face_map(i))));
    triangles += static_cast<long>(faces.back().triangles.size());
    faces_meshed += faces.back().triangles.empty() ? 0 : 1;
  }
  if (!WriteMsh(out, faces)) {
    std::fprintf(stderr, "brepmesh_runner: cannot write %s\n", out.c_str());
    return 5;
  }
  std::printf(
      "{\"mesher\": \"brepmesh\", \"seconds\": %.4f, \"triangles\": %ld, \"faces\": %d, "
      "\"faces_meshed\": %d, \"deflection\": %.6g, \"angle\": %.6g}\n",
      seconds, triangles, face_map.Extent(), faces_meshed, deflection, angle);
  return 0;
}
