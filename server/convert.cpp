#include "convert.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>
#include <utility>

namespace rdmesh::server {
namespace {

Status Invalid(const std::string& message) { return Status(StatusCode::kInvalidArgument, message); }

/// Non-negative finite, or a readable error naming the field.
Status CheckLength(const char* name, double value) {
  if (!std::isfinite(value)) return Invalid(std::string(name) + " must be a finite number");
  if (value < 0.0) {
    return Invalid(std::string(name) + " must be >= 0 (got " + std::to_string(value) + ")");
  }
  return Status::Ok();
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

template <typename T, typename Field>
void AppendRange(const std::vector<T>& from, int64_t begin, int64_t end, Field* to) {
  to->Reserve(static_cast<int>(end - begin));
  for (int64_t i = begin; i < end; ++i) to->AddAlreadyReserved(from[i]);
}

template <typename T, typename Field>
void AppendField(const Field& from, std::vector<T>* to) {
  to->insert(to->end(), from.begin(), from.end());
}

}  // namespace

Result<MeshOptions> FromProto(const pb::MeshOptions& in) {
  MeshOptions out;
  for (const auto& [name, value] :
       {std::pair<const char*, double>{"max_deviation", in.max_deviation()},
        {"max_deviation_rel", in.has_max_deviation_rel() ? in.max_deviation_rel() : 0.0},
        {"rd_tolerance", in.rd_tolerance()},
        {"min_edge_length", in.min_edge_length()},
        {"max_edge_length", in.max_edge_length()},
        {"timeout_seconds", in.timeout_seconds()}}) {
    Status status = CheckLength(name, value);
    if (!status.ok()) return status;
  }
  if (in.max_triangles() < 0) return Invalid("max_triangles must be >= 0 (0 = no budget)");
  if (in.threads() < 0) return Invalid("threads must be >= 0 (0 = the server's default)");
  out.max_deviation = in.max_deviation();
  if (in.has_max_deviation_rel()) out.max_deviation_rel = in.max_deviation_rel();
  out.rd_tolerance = in.rd_tolerance();
  out.max_triangles = in.max_triangles();
  out.min_edge_length = in.min_edge_length();
  out.max_edge_length = in.max_edge_length();
  out.nurbs = in.nurbs();
  out.threads = in.threads();
  out.timeout_seconds = in.timeout_seconds();
  for (int id : in.face_ids()) {
    if (id < 1) return Invalid("face_ids are 1-based (got " + std::to_string(id) + ")");
    out.face_ids.push_back(id);
  }
  return out;
}

pb::MeshOptions ToProto(const MeshOptions& in) {
  pb::MeshOptions out;
  out.set_max_deviation(in.max_deviation);
  out.set_max_deviation_rel(in.max_deviation_rel);
  out.set_rd_tolerance(in.rd_tolerance);
  out.set_max_triangles(in.max_triangles);
  out.set_min_edge_length(in.min_edge_length);
  out.set_max_edge_length(in.max_edge_length);
  out.set_nurbs(in.nurbs);
  out.set_threads(in.threads);
  out.set_timeout_seconds(in.timeout_seconds);
  for (int id : in.face_ids) out.add_face_ids(id);
  return out;
}

pb::ModelInfo ToProto(const ModelInfo& in) {
  pb::ModelInfo out;
  out.set_name(in.name);
  out.set_format(in.format);
  out.set_length_unit(in.length_unit);
  out.set_unit_scale_mm(in.unit_scale_mm);
  out.set_faces(in.faces);
  out.set_edges(in.edges);
  out.set_vertices(in.vertices);
  out.set_solids(in.solids);
  out.set_shells(in.shells);
  out.set_unique_faces(in.unique_faces);
  out.set_instances(in.instances);
  for (double v : in.bbox) out.add_bbox(v);
  out.set_diagonal(in.diagonal);
  for (const auto& [type, count] : in.surface_types) {
    pb::SurfaceTypeCount* entry = out.add_surface_types();
    entry->set_surface_type(type);
    entry->set_faces(count);
  }
  for (const std::string& name : in.part_names) out.add_part_names(name);
  out.set_closed(in.closed);
  return out;
}

ModelInfo FromProto(const pb::ModelInfo& in) {
  ModelInfo out;
  out.name = in.name();
  out.format = in.format();
  out.length_unit = in.length_unit();
  out.unit_scale_mm = in.unit_scale_mm();
  out.faces = in.faces();
  out.edges = in.edges();
  out.vertices = in.vertices();
  out.solids = in.solids();
  out.shells = in.shells();
  out.unique_faces = in.unique_faces();
  out.instances = in.instances();
  for (int i = 0; i < in.bbox_size() && i < 6; ++i) out.bbox[i] = in.bbox(i);
  out.diagonal = in.diagonal();
  for (const pb::SurfaceTypeCount& entry : in.surface_types()) {
    out.surface_types[entry.surface_type()] = entry.faces();
  }
  out.part_names.assign(in.part_names().begin(), in.part_names().end());
  out.closed = in.closed();
  return out;
}

ModelFormat FromProto(pb::ModelFormat format) {
  switch (format) {
    case pb::MODEL_FORMAT_STEP:
      return ModelFormat::kStep;
    case pb::MODEL_FORMAT_IGES:
      return ModelFormat::kIges;
    case pb::MODEL_FORMAT_BREP:
      return ModelFormat::kBrep;
    default:
      return ModelFormat::kAuto;
  }
}

pb::ModelFormat ToProto(ModelFormat format) {
  switch (format) {
    case ModelFormat::kStep:
      return pb::MODEL_FORMAT_STEP;
    case ModelFormat::kIges:
      return pb::MODEL_FORMAT_IGES;
    case ModelFormat::kBrep:
      return pb::MODEL_FORMAT_BREP;
    case ModelFormat::kAuto:
      break;
  }
  return pb::MODEL_FORMAT_UNSPECIFIED;
}

ModelFormat FormatFromName(const std::string& name) {
  const std::size_t dot = name.rfind('.');
  if (dot == std::string::npos) return ModelFormat::kAuto;
  const std::string ext = Lower(name.substr(dot + 1));
  if (ext == "step" || ext == "stp") return ModelFormat::kStep;
  if (ext == "iges" || ext == "igs") return ModelFormat::kIges;
  if (ext == "brep" || ext == "brp") return ModelFormat::kBrep;
  return ModelFormat::kAuto;
}

pb::FaceStatus ToProto(FaceStatus status) {
  switch (status) {
    case FaceStatus::kOk:
      return pb::FACE_STATUS_OK;
    case FaceStatus::kFailed:
      return pb::FACE_STATUS_FAILED;
    case FaceStatus::kSkipped:
      return pb::FACE_STATUS_SKIPPED;
  }
  return pb::FACE_STATUS_UNSPECIFIED;
}

FaceStatus FromProto(pb::FaceStatus status) {
  switch (status) {
    case pb::FACE_STATUS_OK:
      return FaceStatus::kOk;
    case pb::FACE_STATUS_FAILED:
      return FaceStatus::kFailed;
    default:
      return FaceStatus::kSkipped;
  }
}

pb::Stage ToProto(Progress::Stage stage) {
  switch (stage) {
    case Progress::Stage::kLoading:
      return pb::STAGE_LOADING;
    case Progress::Stage::kEdges:
      return pb::STAGE_EDGES;
    case Progress::Stage::kFaces:
      return pb::STAGE_FACES;
    case Progress::Stage::kAssembly:
      return pb::STAGE_ASSEMBLY;
    case Progress::Stage::kDone:
      return pb::STAGE_DONE;
  }
  return pb::STAGE_UNSPECIFIED;
}

SurfaceType SurfaceTypeFromName(const std::string& name) {
  for (int t = static_cast<int>(SurfaceType::kPlane); t <= static_cast<int>(SurfaceType::kOther);
       ++t) {
    if (name == SurfaceTypeName(static_cast<SurfaceType>(t))) return static_cast<SurfaceType>(t);
  }
  return SurfaceType::kOther;
}

pb::Summary ToProto(const MeshSummary& in) {
  pb::Summary out;
  out.set_triangles(in.triangles);
  out.set_nodes(in.nodes);
  out.set_faces_ok(in.faces_ok);
  out.set_faces_failed(in.faces_failed);
  out.set_faces_skipped(in.faces_skipped);
  out.set_requested_deviation(in.requested_deviation);
  out.set_estimated_deviation(in.estimated_deviation);
  out.set_mesh_area(in.mesh_area);
  out.set_exact_area(in.exact_area);
  out.set_edge_seconds(in.edge_seconds);
  out.set_face_seconds(in.face_seconds);
  out.set_mesh_seconds(in.seconds);
  out.set_edges(in.edges);
  out.set_edge_segments(in.edge_segments);
  return out;
}

MeshSummary FromProto(const pb::Summary& in) {
  MeshSummary out;
  out.triangles = in.triangles();
  out.nodes = in.nodes();
  out.faces_ok = in.faces_ok();
  out.faces_failed = in.faces_failed();
  out.faces_skipped = in.faces_skipped();
  out.requested_deviation = in.requested_deviation();
  out.estimated_deviation = in.estimated_deviation();
  out.mesh_area = in.mesh_area();
  out.exact_area = in.exact_area();
  out.edge_seconds = in.edge_seconds();
  out.face_seconds = in.face_seconds();
  out.seconds = in.mesh_seconds();
  out.edges = in.edges();
  out.edge_segments = in.edge_segments();
  return out;
}

std::vector<pb::FaceMesh> SplitFaceMesh(const FaceMesh& face, bool with_uv, bool with_normals,
                                        std::size_t max_bytes) {
  const int64_t nodes = face.node_count();
  const int64_t triangles = face.triangle_count();
  with_uv = with_uv && face.uv.size() == static_cast<std::size_t>(2 * nodes);
  with_normals = with_normals && face.normals.size() == static_cast<std::size_t>(3 * nodes);
  const bool with_ids = face.global_ids.size() == static_cast<std::size_t>(nodes);

  // Upper bounds of the encoded size: doubles are 8 bytes, a non-negative int64 varint at most
  // 10 and an int32 varint at most 5. The fixed fields, the reason and the MeshEvent wrapper
  // fit in the reserve.
  const std::size_t node_bytes =
      24 + (with_uv ? 16 : 0) + (with_normals ? 24 : 0) + (with_ids ? 10 : 0);
  const std::size_t triangle_bytes = 15;
  const std::size_t reserve = 512 + face.reason.size();
  const std::size_t budget =
      max_bytes > reserve + node_bytes ? max_bytes - reserve : node_bytes;  // always progress

  pb::FaceMesh header;
  header.set_face_id(face.face_id);
  header.set_surface_type(SurfaceTypeName(face.surface_type));
  header.set_status(ToProto(face.status));
  header.set_reason(face.reason);
  header.set_node_count(nodes);
  header.set_triangle_count(triangles);
  header.set_max_deviation(face.max_deviation);
  header.set_area(face.area);
  header.set_exact_area(face.exact_area);
  header.set_seconds(face.seconds);

  std::vector<pb::FaceMesh> parts;
  int64_t node = 0;
  int64_t triangle = 0;
  do {
    const int64_t node_end =
        node + std::min<int64_t>(nodes - node, static_cast<int64_t>(budget / node_bytes));
    const std::size_t left = budget - static_cast<std::size_t>(node_end - node) * node_bytes;
    const int64_t triangle_end =
        triangle +
        std::min<int64_t>(triangles - triangle, static_cast<int64_t>(left / triangle_bytes));
    pb::FaceMesh part = header;
    part.set_chunk_index(static_cast<int32_t>(parts.size()));
    part.set_node_offset(node);
    part.set_triangle_offset(triangle);
    AppendRange(face.xyz, 3 * node, 3 * node_end, part.mutable_xyz());
    if (with_uv) AppendRange(face.uv, 2 * node, 2 * node_end, part.mutable_uv());
    if (with_normals) AppendRange(face.normals, 3 * node, 3 * node_end, part.mutable_normals());
    if (with_ids) AppendRange(face.global_ids, node, node_end, part.mutable_global_ids());
    AppendRange(face.triangles, 3 * triangle, 3 * triangle_end, part.mutable_triangles());
    parts.push_back(std::move(part));
    node = node_end;
    triangle = triangle_end;
  } while (node < nodes || triangle < triangles);
  for (pb::FaceMesh& part : parts) part.set_chunk_count(static_cast<int32_t>(parts.size()));
  return parts;
}

Status FaceMeshJoiner::Add(const pb::FaceMesh& part) {
  const int id = part.face_id();
  if (id < 1) return Invalid("FaceMesh with face_id " + std::to_string(id));
  if (pending_.size() < static_cast<std::size_t>(id)) pending_.resize(id);
  Pending& entry = pending_[id - 1];
  const std::string where =
      "face " + std::to_string(id) + " part " + std::to_string(part.chunk_index()) + ": ";
  if (part.chunk_index() != entry.next_chunk) {
    return Invalid(where + "expected part " + std::to_string(entry.next_chunk));
  }
  FaceMesh& face = entry.face;
  if (part.chunk_index() == 0) {
    face.face_id = id;
    face.surface_type = SurfaceTypeFromName(part.surface_type());
    face.status = FromProto(part.status());
    face.reason = part.reason();
    face.max_deviation = part.max_deviation();
    face.area = part.area();
    face.exact_area = part.exact_area();
    face.seconds = part.seconds();
    entry.chunk_count = part.chunk_count();
    face.xyz.reserve(3 * part.node_count());
    face.triangles.reserve(3 * part.triangle_count());
  } else if (part.chunk_count() != entry.chunk_count) {
    return Invalid(where + "chunk_count changed");
  }
  if (part.node_offset() != face.node_count() || part.triangle_offset() != face.triangle_count()) {
    return Invalid(where + "offsets do not follow the previous part");
  }
  if (part.xyz_size() % 3 != 0 || part.triangles_size() % 3 != 0) {
    return Invalid(where + "xyz or triangles not a multiple of 3");
  }
  AppendField(part.xyz(), &face.xyz);
  AppendField(part.uv(), &face.uv);
  AppendField(part.normals(), &face.normals);
  AppendField(part.global_ids(), &face.global_ids);
  AppendField(part.triangles(), &face.triangles);
  ++entry.next_chunk;
  if (entry.next_chunk == entry.chunk_count &&
      (face.node_count() != part.node_count() || face.triangle_count() != part.triangle_count())) {
    return Invalid(where + "node or triangle count does not match the parts");
  }
  return Status::Ok();
}

bool FaceMeshJoiner::complete() const {
  for (const Pending& entry : pending_) {
    if (entry.next_chunk != entry.chunk_count) return false;
  }
  return true;
}

std::vector<FaceMesh> FaceMeshJoiner::TakeFaces() {
  std::vector<FaceMesh> faces;
  for (Pending& entry : pending_) {
    if (entry.chunk_count > 0 && entry.next_chunk == entry.chunk_count) {
      faces.push_back(std::move(entry.face));
    }
  }
  pending_.clear();
  return faces;
}

}  // namespace rdmesh::server
