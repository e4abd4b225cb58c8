// plain_runner: the peer of issue 34, a STEP file to a mesh on disk with OCCT alone, in one
// process (bench/performance/parse_e2e.py times it against `rdmesh mesh`).
//
//   plain_runner MODEL.step OUT.msh [--tight-box]
//
// STEPControl_Reader ReadFile + TransferRoots + OneShape, then BRepMesh_IncrementalMesh in
// parallel at an absolute linear deflection of 1e-3 of the bounding-box diagonal and an angular
// deflection of 0.5 rad, then an MSH 4.1 ASCII write of the triangulation: one node block and one
// triangle block per face (entity tag = 1-based face index in TopExp order), nodes not shared
// between faces. The box is BRepBndLib::Add (what an OCCT user writes; poles and tolerances make
// it at least as large as the tight box, so the deflection is at least rdmesh's); --tight-box
// uses BRepBndLib::AddOptimal instead, the box rdmesh measures its diagonal on. Prints one JSON
// line on stdout:
//   {"read_seconds": R, "transfer_seconds": T, "box_seconds": B, "mesh_seconds": M,
//    "write_seconds": W, "faces": F, "faces_meshed": FM, "triangles": N, "nodes": V,
//    "diagonal": D, "deflection": E}
// The whole process's wall time is what the bench compares; these stages say where it went.

#include <BRepBndLib.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
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
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// A buffered text file written with std::to_chars (shortest round-trip doubles), the same
// formatting rdmesh's own writers use, so neither side of the comparison pays for printf.
class Writer {
 public:
  explicit Writer(const std::string& path) : file_(std::fopen(path.c_str(), "wb")) {
    buffer_.reserve(kSize + 64);
  }
  ~Writer() {
    if (file_ != nullptr) std::fclose(file_);
  }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  bool ok() const { return file_ != nullptr && ok_; }
  void Text(std::string_view text) {
    if (buffer_.size() + text.size() > kSize) Flush();
    buffer_.append(text.data(), text.size());
  }
  void Char(char c) {
    if (buffer_.size() + 1 > kSize) Flush();
    buffer_.push_back(c);
  }
  void Int(int64_t value) {
    char text[24];
    auto result = std::to_chars(text, text + sizeof(text), value);
    Text(std::string_view(text, result.ptr - text));
  }
  void Number(double value) {
    char text[32];
    auto result = std::to_chars(text, text + sizeof(text), value);
    Text(std::string_view(text, result.ec == std::errc() ? result.ptr - text : 0));
  }
  // Flushes and closes; false when any write failed.
  bool Close() {
    Flush();
    const bool closed = file_ != nullptr && std::fclose(file_) == 0;
    file_ = nullptr;
    return closed && ok_;
  }

 private:
  static constexpr size_t kSize = 1 << 20;
  void Flush() {
    if (file_ != nullptr && !buffer_.empty() &&
        std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size())
      ok_ = false;
    buffer_.clear();
  }
  std::FILE* file_;
  std::string buffer_;
  bool ok_ = true;
};

struct Counts {
  int64_t faces_meshed = 0, nodes = 0, triangles = 0;
};

// The triangulation of `faces` as MSH 4.1 ASCII: per meshed face a node block (world
// coordinates) and a triangle block oriented along the face's outward normal; node tags are
// global and consecutive; faces without a triangulation are left out.
bool WriteMsh(const std::string& path, const TopTools_IndexedMapOfShape& faces, Counts* counts) {
  std::vector<Handle(Poly_Triangulation)> meshes(faces.Extent() + 1);
  std::vector<TopLoc_Location> locations(faces.Extent() + 1);
  for (int i = 1; i <= faces.Extent(); ++i) {
    meshes[i] = BRep_Tool::Triangulation(TopoDS::Face(faces(i)), locations[i]);
    if (meshes[i].IsNull() || meshes[i]->NbTriangles() == 0) continue;
    ++counts->faces_meshed;
    counts->nodes += meshes[i]->NbNodes();
    counts->triangles += meshes[i]->NbTriangles();
  }
  Writer out(path);
  if (!out.ok()) return false;
  out.Text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n");
  out.Int(counts->faces_meshed);
  out.Char(' ');
  out.Int(counts->nodes);
  out.Text(" 1 ");
  out.Int(counts->nodes);
  out.Char('\n');
  std::vector<int64_t> first_tag(faces.Extent() + 1, 0);
  int64_t next_tag = 1;
  for (int i = 1; i <= faces.Extent(); ++i) {
    const Handle(Poly_Triangulation)& mesh = meshes[i];
    if (mesh.IsNull() || mesh->NbTriangles() == 0) continue;
    first_tag[i] = next_tag;
    out.Text("2 ");
    out.Int(i);
    out.Text(" 0 ");
    out.Int(mesh->NbNodes());
    out.Char('\n');
    for (int k = 0; k < mesh->NbNodes(); ++k) {
      out.Int(next_tag + k);
      out.Char('\n');
    }
    const gp_Trsf placement = locations[i].Transformation();
    for (int k = 1; k <= mesh->NbNodes(); ++k) {
      const gp_Pnt p = mesh->Node(k).Transformed(placement);
      out.Number(p.X());
      out.Char(' ');
      out.Number(p.Y());
      out.Char(' ');
      out.Number(p.Z());
      out.Char('\n');
    }
    next_tag += mesh->NbNodes();
  }
  out.Text("$EndNodes\n$Elements\n");
  out.Int(counts->faces_meshed);
  out.Char(' ');
  out.Int(counts->triangles);
  out.Text(" 1 ");
  out.Int(counts->triangles);
  out.Char('\n');
  int64_t element = 1;
  for (int i = 1; i <= faces.Extent(); ++i) {
    const Handle(Poly_Triangulation)& mesh = meshes[i];
    if (mesh.IsNull() || mesh->NbTriangles() == 0) continue;
    out.Text("2 ");
    out.Int(i);
    out.Text(" 2 ");
    out.Int(mesh->NbTriangles());
    out.Char('\n');
    const bool reversed = faces(i).Orientation() == TopAbs_REVERSED;
    for (int k = 1; k <= mesh->NbTriangles(); ++k) {
      int n[3] = {0, 0, 0};
      mesh->Triangle(k).Get(n[0], n[1], n[2]);
      if (reversed) std::swap(n[1], n[2]);
      out.Int(element++);
      for (int c : n) {
        out.Char(' ');
        out.Int(first_tag[i] + c - 1);
      }
      out.Char('\n');
    }
  }
  out.Text("$EndElements\n");
  return out.Close();
}

}  // namespace

int main(int argc, char** argv) {
  const bool tight_box = argc == 4 && std::strcmp(argv[3], "--tight-box") == 0;
  if (argc != 3 && !tight_box) {
    std::fprintf(stderr, "usage: plain_runner MODEL.step OUT.msh [--tight-box]\n");
    return 2;
  }
  const std::string step = argv[1], out = argv[2];
  // OCCT's reader talks on stdout; keep stdout for the one JSON line.
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer));

  auto start = Clock::now();
  STEPControl_Reader reader;
  if (reader.ReadFile(step.c_str()) != IFSelect_RetDone) {
    std::fprintf(stderr, "plain_runner: cannot read %s\n", step.c_str());
    return 3;
  }
  const double read_seconds = Since(start);
  start = Clock::now();
  reader.TransferRoots();
  const TopoDS_Shape shape = reader.OneShape();
  const double transfer_seconds = Since(start);
  if (shape.IsNull()) {
    std::fprintf(stderr, "plain_runner: no shape in %s\n", step.c_str());
    return 3;
  }

  start = Clock::now();
  Bnd_Box box;
  if (tight_box) {
    BRepBndLib::AddOptimal(shape, box, /*useTriangulation=*/false, /*useShapeTolerance=*/false);
  } else {
    BRepBndLib::Add(shape, box, /*useTriangulation=*/false);
  }
  const double diagonal = box.IsVoid() ? 0.0 : std::sqrt(box.SquareExtent());
  const double box_seconds = Since(start);
  if (!(diagonal > 0)) {
    std::fprintf(stderr, "plain_runner: empty bounding box in %s\n", step.c_str());
    return 3;
  }

  IMeshTools_Parameters parameters;
  parameters.Deflection = 1e-3 * diagonal;
  parameters.Angle = 0.5;
  parameters.Relative = Standard_False;
  parameters.InParallel = Standard_True;
  start = Clock::now();
  try {
    BRepMesh_IncrementalMesh mesher(shape, parameters);
  } catch (const Standard_Failure& failure) {
    std::fprintf(stderr, "plain_runner: BRepMesh failed: %s\n", failure.GetMessageString());
    return 4;
  }
  const double mesh_seconds = Since(start);

  start = Clock::now();
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  Counts counts;
  if (!WriteMsh(out, faces, &counts)) {
    std::fprintf(stderr, "plain_runner: cannot write %s\n", out.c_str());
    return 5;
  }
  const double write_seconds = Since(start);
  std::printf(
      "{\"read_seconds\": %.6f, \"transfer_seconds\": %.6f, \"box_seconds\": %.6f, "
      "\"mesh_seconds\": %.6f, \"write_seconds\": %.6f, \"faces\": %d, \"faces_meshed\": %lld, "
      "\"triangles\": %lld, \"nodes\": %lld, \"diagonal\": %.17g, \"deflection\": %.17g}\n",
      read_seconds, transfer_seconds, box_seconds, mesh_seconds, write_seconds, faces.Extent(),
      static_cast<long long>(counts.faces_meshed), static_cast<long long>(counts.triangles),
      static_cast<long long>(counts.nodes), diagonal, parameters.Deflection);
  return 0;
}
