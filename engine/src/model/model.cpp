#include "model/model.h"

#include <BRepGProp.hxx>
#include <BRepLib.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_DataMapOfShapeInteger.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <vector>

#include "core/parallel.h"
#include "geometry/surface_type.h"
#include "model/face_area.h"
#include "model/model_info.h"
#include "model/model_payload.h"
#include "model/model_readers.h"
#include "model/xcaf_api.h"

namespace rdmesh {

const char* FormatName(ModelFormat format) {
  switch (format) {
    case ModelFormat::kStep:
      return "step";
    case ModelFormat::kIges:
      return "iges";
    case ModelFormat::kBrep:
      return "brep";
    case ModelFormat::kAuto:
      break;
  }
  return "unknown";
}

namespace {

// Face instancing: faces that share a TShape are meshed once, through the first of them.
void FindInstances(Model* model) {
  int count = model->face_count();
  model->face_representative.assign(count, 0);
  model->face_placement.assign(count, gp_Trsf());
  model->face_flipped.assign(count, false);
  TopTools_DataMapOfShapeInteger first_by_tshape;  // unlocated FORWARD face -> first face id
  for (int id = 1; id <= count; ++id) {
    const TopoDS_Face& face = model->face(id);
    TopoDS_Shape key = face.Located(TopLoc_Location()).Oriented(TopAbs_FORWARD);
    const int* found = first_by_tshape.Seek(key);
    if (found == nullptr) {
      first_by_tshape.Bind(key, id);
      model->face_representative[id - 1] = id;
      continue;
    }
    const TopoDS_Face& rep = model->face(*found);
    model->face_representative[id - 1] = *found;
    // World of rep = T_rep * local, world of face = T_face * local.
    gp_Trsf placement = face.Location().Transformation();
    placement.Multiply(rep.Location().Transformation().Inverted());
    model->face_placement[id - 1] = placement;
    model->face_flipped[id - 1] = face.Orientation() != rep.Orientation();
  }
}

// A face placed like an earlier one (its representative) takes that face's area, scaled.
bool CopiesAnEarlierFace(const Model& model, int id) {
  const int rep = model.face_representative[id - 1];
  return rep != id && rep < id;
}

// The exact areas, on all cores: each face on its own, then the copies in face order.
void ComputeFaceAreas(Model* model) {
  int count = model->face_count();
  model->face_area.assign(count, 0.0);
  std::vector<int> computed;
  for (int id = 1; id <= count; ++id) {
    if (!CopiesAnEarlierFace(*model, id)) computed.push_back(id);
  }
  ParallelRunner(0).For(0, static_cast<int>(computed.size()), [&](int i) {
    const int id = computed[i];
    try {
      if (const std::optional<double> area = ClosedFormFaceArea(model->face(id))) {
        model->face_area[id - 1] = *area;
        return;
      }
      if (const std::optional<double> area = NaturalPatchArea(model->face(id))) {
        model->face_area[id - 1] = *area;
        return;
      }
      GProp_GProps props;
      BRepGProp::SurfaceProperties(model->face(id), props);
      model->face_area[id - 1] = std::abs(props.Mass());
    } catch (const Standard_Failure&) {
      model->face_area[id - 1] = 0.0;  // a broken face: meshing will report it
    }
  });
  for (int id = 1; id <= count; ++id) {
    if (!CopiesAnEarlierFace(*model, id)) continue;
    const double scale = model->face_placement[id - 1].ScaleFactor();
    model->face_area[id - 1] =
        model->face_area[model->face_representative[id - 1] - 1] * scale * scale;
  }
}

}  // namespace

DerivedValues DerivedValuesOf(const Model& model) {
  DerivedValues derived;
  derived.face_area = model.face_area;
  derived.bbox = model.info.bbox;
  derived.diagonal = model.info.diagonal;
  return derived;
}

namespace {

// The last line of `message` that says something, without OCCT's address prefix.
std::string InnermostReason(const std::string& message) {
  // OCCT's nested exceptions print one per line, innermost last, as "0xADDRESS : Type: text".
  std::string last;
  std::size_t start = 0;
  while (start < message.size()) {
    std::size_t end = message.find('\n', start);
    if (end == std::string::npos) end = message.size();
    std::string line = message.substr(start, end - start);
    if (line.compare(0, 2, "0x") == 0 && line.find(" : ") != std::string::npos)
      line = line.substr(line.find(" : ") + 3);
    if (line.find_first_not_of(" \t)") != std::string::npos) last = line;
    start = end + 1;
  }
  return last;
}

// Stores the pcurve of every edge of a plane that has none. OCCT answers BRep_Tool::CurveOnSurface
// for such an edge by projecting its 3D curve onto the plane anew at every call (BRep_Tool::
// CurveOnPlane), which each meshing run asked several times per edge (pcurves, the face's (u,v)
// bounds, edge lines); BRepLib stores that same projection, so every later answer is the same
// curve, looked up. An edge OCCT cannot project is left as it is: a run asks again, and fails
// the face as before.
void StorePlanePcurves(Model* model) {
  for (int f = 1; f <= model->face_count(); ++f) {
    const TopoDS_Face& face = model->face(f);
    if (FaceSurfaceType(face) != SurfaceType::kPlane) continue;
    for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
      try {
        BRepLib::BuildPCurveForEdgeOnPlane(TopoDS::Edge(ex.Current()), face);
      } catch (const Standard_Failure&) {
      }
    }
  }
}

// Model::face_edges and Model::edge_faces.
void MapAdjacency(Model* model) {
  const int nf = model->face_count();
  model->face_edges.assign(nf, {});
  model->edge_faces.assign(model->edge_count(), {});
  for (int f = 1; f <= nf; ++f) {
    std::vector<int>& edges = model->face_edges[f - 1];
    for (TopExp_Explorer ex(model->face(f), TopAbs_EDGE); ex.More(); ex.Next()) {
      const int e = model->edges.FindIndex(ex.Current());
      if (e == 0 || std::find(edges.begin(), edges.end(), e) != edges.end()) continue;
      edges.push_back(e);
      model->edge_faces[e - 1].push_back(f);
    }
  }
}

}  // namespace

Result<std::shared_ptr<const Model>> BuildModel(ReadShape read, ModelFormat format,
                                                const std::string& name,
                                                const std::string& display_name,
                                                const DerivedValues* derived) {
  const auto start = std::chrono::steady_clock::now();
  auto model = std::make_shared<Model>();
  model->shape = read.shape;
  model->doc = read.doc;
  try {
    TopExp::MapShapes(model->shape, TopAbs_FACE, model->faces);
    TopExp::MapShapes(model->shape, TopAbs_EDGE, model->edges);
    TopExp::MapShapes(model->shape, TopAbs_VERTEX, model->vertices);
    if (model->faces.IsEmpty())
      return Status(StatusCode::kEmptyModel, "'" + name + "' holds no faces");
    MapAdjacency(model.get());
    StorePlanePcurves(model.get());
    FindInstances(model.get());
    if (derived != nullptr &&
        derived->face_area.size() != static_cast<std::size_t>(model->face_count())) {
      return Status(StatusCode::kParseError,
                    "cannot read '" + name + "': " + std::to_string(derived->face_area.size()) +
                        " face areas for " + std::to_string(model->face_count()) + " faces");
    }
    read.stages.emplace_back("topology", SecondsSince(start));
    auto step_start = std::chrono::steady_clock::now();
    if (derived != nullptr) {
      model->face_area = derived->face_area;
    } else {
      ComputeFaceAreas(model.get());
    }
    read.stages.emplace_back("areas", SecondsSince(step_start));
    step_start = std::chrono::steady_clock::now();
    for (int id = 1; id <= model->edge_count(); ++id)
      model->max_edge_tolerance =
          std::max(model->max_edge_tolerance, BRep_Tool::Tolerance(model->edge(id)));
    model->info = ComputeModelInfo(*model, /*bounding_box=*/derived == nullptr);
    if (model->doc.IsNull() && read.instances >= 0) {
      model->info.instances = read.instances;
      model->info.part_names = read.part_names;
    }
    read.stages.emplace_back("info", SecondsSince(step_start));
    if (derived != nullptr) {
      model->info.bbox = derived->bbox;
      model->info.diagonal = derived->diagonal;
    }
  } catch (const Standard_Failure& failure) {
    return Status(StatusCode::kParseError, "cannot read '" + name + "': invalid topology (" +
                                               failure.DynamicType()->Name() + ")");
  }
  model->info.name = display_name;
  model->info.format = FormatName(format);
  model->info.length_unit = read.length_unit;
  model->info.unit_scale_mm = read.unit_scale_mm;
  model->info.load_stages = std::move(read.stages);
  model->info.reader = read.reader;
  model->info.reader_note = read.reader_note;
  return std::shared_ptr<const Model>(std::move(model));
}

Result<CanonicalModel> ParseCanonical(const std::string& bytes, ModelFormat format,
                                      const std::string& path, const std::string& name,
                                      const std::string& display_name, Context* context) {
  if (context != nullptr) {
    if (context->ShouldStop()) return context->StopStatus();
    context->ReportProgress(Progress{Progress::Stage::kLoading, 0, 1});
  }
  if (format == ModelFormat::kAuto) format = FormatFromContent(bytes);
  if (format == ModelFormat::kAuto) {
    if (bytes.find_first_not_of(" \t\r\n") == std::string::npos)
      return Status(StatusCode::kParseError, "cannot read '" + name + "': empty file");
    return Status(StatusCode::kParseError,
                  "cannot read '" + name + "': not a STEP, IGES or BREP file");
  }
  Result<ReadShape> read = ReadModelBytes(bytes, format, path, name, context);
  if (!read.ok()) return read.status();
  auto start = std::chrono::steady_clock::now();
  CanonicalModel canonical;
  const PayloadKind kind = PayloadKindOf(*read);
  canonical.kind = kind;
  Result<std::string> payload = WritePayload(*read);
  if (!payload.ok()) {
    return Status(payload.status().code(),
                  "cannot read '" + name + "': " + payload.status().message());
  }
  if (context != nullptr && context->ShouldStop()) return context->StopStatus();
  Result<ReadShape> reread = ReadPayload(*payload, kind);
  if (!reread.ok()) {
    // Seen on fuzzed files with absurd numbers: OCCT transfers them, but a degenerate value
    // (a zero-length direction) does not read back from OCCT's own binary format.
    return Status(StatusCode::kParseError,
                  "cannot read '" + name +
                      "': OCCT cannot store and read back its geometry, which holds degenerate "
                      "or out-of-range values (" +
                      InnermostReason(reread.status().message()) + ")");
  }
  reread->length_unit = read->length_unit;
  reread->instances = read->instances;
  reread->part_names = std::move(read->part_names);
  reread->unit_scale_mm = read->unit_scale_mm;
  reread->stages = std::move(read->stages);
  reread->reader = read->reader;
  reread->reader_note = read->reader_note;
  reread->stages.emplace_back("canonical", SecondsSince(start));
  canonical.payload = std::move(*payload);
  Result<std::shared_ptr<const Model>> model =
      BuildModel(std::move(*reread), format, name, display_name);
  if (!model.ok()) return model.status();
  canonical.model = std::move(*model);
  if (context != nullptr) context->ReportProgress(Progress{Progress::Stage::kLoading, 1, 1});
  return canonical;
}

const TopoDS_Face& Model::face(int id) const { return TopoDS::Face(faces(id)); }

const TopoDS_Edge& Model::edge(int id) const { return TopoDS::Edge(edges(id)); }

Result<std::string> ReadModelFile(const std::string& path) {
  std::error_code error;
  std::filesystem::file_status status = std::filesystem::status(path, error);
  if (!std::filesystem::exists(status))
    return Status(StatusCode::kNotFound, "cannot read '" + path + "': no such file");
  if (std::filesystem::is_directory(status))
    return Status(StatusCode::kIoError, "cannot read '" + path + "': it is a directory");
  std::ifstream file(path, std::ios::binary);
  if (!file) return Status(StatusCode::kIoError, "cannot open '" + path + "' for reading");
  // A regular file in one read of its size (a character at a time cost 15 instructions a byte);
  // whatever else there is (a pipe, a file still growing) after that.
  std::string bytes;
  if (std::filesystem::is_regular_file(status)) {
    const std::uintmax_t size = std::filesystem::file_size(path, error);
    if (!error) bytes.resize(static_cast<size_t>(size));
    file.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    bytes.resize(static_cast<size_t>(file.gcount()));
    file.clear(file.rdstate() & ~(std::ios::eofbit | std::ios::failbit));
  }
  bytes.append(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
  if (file.bad()) return Status(StatusCode::kIoError, "cannot read '" + path + "': read error");
  return bytes;
}

Result<std::shared_ptr<const Model>> LoadModel(const std::string& path, Context* context) {
  Result<std::string> bytes = ReadModelFile(path);
  if (!bytes.ok()) return bytes.status();
  std::string name = std::filesystem::path(path).filename().string();
  Result<CanonicalModel> parsed = ParseCanonical(
      *bytes, ResolveFormat(ModelFormat::kAuto, path, *bytes), path, path, name, context);
  if (!parsed.ok()) return parsed.status();
  return parsed->model;
}

Result<std::shared_ptr<const Model>> LoadModelFromBytes(const std::string& bytes,
                                                        ModelFormat format, const std::string& name,
                                                        Context* context) {
  Result<CanonicalModel> parsed =
      ParseCanonical(bytes, ResolveFormat(format, name, bytes), "", name, name, context);
  if (!parsed.ok()) return parsed.status();
  return parsed->model;
}

ModelInfo GetModelInfo(const Model& model) { return model.info; }

Status LoadDocumentFramework() {
  Result<const XcafApi*> xcaf = Xcaf();
  return xcaf.ok() ? Status::Ok() : xcaf.status();
}

}  // namespace rdmesh
