#include "wire/convert.h"

#include <algorithm>
#include <limits>
#include <string>
#include <utility>

namespace rdmesh::server {
namespace {

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

MeshOptions FromProto(const pb::MeshOptions& in) {
  MeshOptions out;
  out.max_deviation = in.max_deviation();
  if (in.has_max_deviation_rel()) out.max_deviation_rel = in.max_deviation_rel();
  out.rd_tolerance = in.rd_tolerance();
  out.max_triangles = in.max_triangles();
  out.min_edge_length = in.min_edge_length();
  out.max_edge_length = in.max_edge_length();
  out.nurbs = in.nurbs();
  out.threads = in.threads();
  out.timeout_seconds = in.timeout_seconds();
  if (in.has_sharp_edge_angle()) out.sharp_edge_angle = in.sharp_edge_angle();
  out.compress = in.compress();
  out.off_surface = in.off_surface();
  out.face_ids.assign(in.face_ids().begin(), in.face_ids().end());
  return out;
}

pb::MeshOptions ToProto(const MeshOptions& in) {
  pb::MeshOptions out;
  out.set_max_deviation(in.max_deviation);
  if (in.max_deviation_rel) out.set_max_deviation_rel(*in.max_deviation_rel);
  out.set_rd_tolerance(in.rd_tolerance);
  out.set_max_triangles(in.max_triangles);
  out.set_min_edge_length(in.min_edge_length);
  out.set_max_edge_length(in.max_edge_length);
  out.set_nurbs(in.nurbs);
  out.set_threads(in.threads);
  out.set_timeout_seconds(in.timeout_seconds);
  out.set_sharp_edge_angle(in.sharp_edge_angle);
  out.set_compress(in.compress);
  out.set_off_surface(in.off_surface);
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

Progress::Stage FromProto(pb::Stage stage) {
  switch (stage) {
    case pb::STAGE_EDGES:
      return Progress::Stage::kEdges;
    case pb::STAGE_FACES:
      return Progress::Stage::kFaces;
    case pb::STAGE_ASSEMBLY:
      return Progress::Stage::kAssembly;
    case pb::STAGE_DONE:
      return Progress::Stage::kDone;
    default:
      return Progress::Stage::kLoading;
  }
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
                                        std::size_t max_bytes, bool with_deviation) {
  const int64_t nodes = face.node_count();
  const int64_t triangles = face.triangle_count();
  with_uv = with_uv && face.uv.size() == static_cast<std::size_t>(2 * nodes);
  with_normals = with_normals && face.normals.size() == static_cast<std::size_t>(3 * nodes);
  with_deviation =
      with_deviation && face.triangle_deviation.size() == static_cast<std::size_t>(triangles);

  // Upper bounds of the encoded size: doubles are 8 bytes and a non-negative int32 varint at
  // most 5. The fixed fields, the reason and the MeshEvent wrapper fit in the reserve.
  const std::size_t node_bytes = 24 + (with_uv ? 16 : 0) + (with_normals ? 24 : 0);
  const std::size_t triangle_bytes = 15 + (with_deviation ? 8 : 0);
  const std::size_t reserve = 512 + face.reason.size() + face.offset_reason.size();
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
  header.set_offset(face.offset);
  header.set_offset_reason(face.offset_reason);

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
    AppendRange(face.triangles, 3 * triangle, 3 * triangle_end, part.mutable_triangles());
    if (with_deviation) {
      AppendRange(face.triangle_deviation, triangle, triangle_end,
                  part.mutable_triangle_deviation());
    }
    parts.push_back(std::move(part));
    node = node_end;
    triangle = triangle_end;
  } while (node < nodes || triangle < triangles);
  for (pb::FaceMesh& part : parts) part.set_chunk_count(static_cast<int32_t>(parts.size()));
  return parts;
}

std::vector<pb::FaceNodeIds> SplitFaceNodeIds(const FaceMesh& face, const Mesh* topology,
                                              std::size_t max_bytes) {
  const int64_t nodes = face.node_count();
  std::vector<pb::FaceNodeIds> parts;
  if (nodes == 0 || face.global_ids.size() != static_cast<std::size_t>(nodes)) return parts;
  const bool with_topology = topology != nullptr &&
                             topology->node_dim.size() == topology->xyz.size() / 3 &&
                             topology->node_entity.size() == topology->node_dim.size() &&
                             topology->node_param.size() == 2 * topology->node_dim.size();
  // Varint upper bounds: 10 bytes per int64 id, 5 per int32; params are 2 doubles.
  const std::size_t node_bytes = 10 + (with_topology ? 5 + 5 + 16 : 0);
  const std::size_t reserve = 256;
  const std::size_t per_part =
      std::max<std::size_t>(1, (max_bytes > reserve ? max_bytes - reserve : 0) / node_bytes);
  for (int64_t node = 0; node < nodes; node += static_cast<int64_t>(per_part)) {
    const int64_t end = std::min<int64_t>(nodes, node + static_cast<int64_t>(per_part));
    pb::FaceNodeIds part;
    part.set_face_id(face.face_id);
    part.set_chunk_index(static_cast<int32_t>(parts.size()));
    part.set_node_offset(node);
    AppendRange(face.global_ids, node, end, part.mutable_global_ids());
    if (with_topology) {
      for (int64_t i = node; i < end; ++i) {
        const int64_t id = face.global_ids[i];
        part.add_node_dim(topology->node_dim[id]);
        part.add_node_entity(topology->node_entity[id]);
        part.add_node_param(topology->node_param[2 * id]);
        part.add_node_param(topology->node_param[2 * id + 1]);
      }
    }
    parts.push_back(std::move(part));
  }
  for (pb::FaceNodeIds& part : parts) part.set_chunk_count(static_cast<int32_t>(parts.size()));
  return parts;
}

std::vector<pb::EdgePolyline> SplitEdgeLine(const EdgeLine& line, std::size_t max_bytes) {
  const auto nodes = static_cast<int64_t>(line.nodes.size());
  // 10 bytes bound a varint int64; the faces (5 bytes each), flags and header fit the reserve.
  const std::size_t reserve = 256 + 5 * line.faces.size();
  const std::size_t per_part =
      std::max<std::size_t>(1, (max_bytes > reserve ? max_bytes - reserve : 0) / 10);
  pb::EdgePolyline header;
  header.set_edge_id(line.edge_id);
  header.set_node_count(nodes);
  for (int32_t f : line.faces) header.add_faces(f);
  header.set_seam(line.seam);
  header.set_degenerate(line.degenerate);
  header.set_sharp(line.sharp);
  header.set_dihedral(line.dihedral);
  std::vector<pb::EdgePolyline> parts;
  int64_t node = 0;
  do {
    const int64_t end = std::min<int64_t>(nodes, node + static_cast<int64_t>(per_part));
    pb::EdgePolyline part = header;
    part.set_chunk_index(static_cast<int32_t>(parts.size()));
    part.set_node_offset(node);
    for (int64_t i = node; i < end; ++i) part.add_nodes(line.nodes[i]);
    parts.push_back(std::move(part));
    node = end;
  } while (node < nodes);
  for (pb::EdgePolyline& part : parts) part.set_chunk_count(static_cast<int32_t>(parts.size()));
  return parts;
}

MeshResultBuilder::PendingFace& MeshResultBuilder::Slot(int face_id) {
  if (faces_.size() < static_cast<std::size_t>(face_id)) faces_.resize(face_id);
  return faces_[face_id - 1];
}

Status MeshResultBuilder::Add(const pb::MeshEvent& event) {
  switch (event.event_case()) {
    case pb::MeshEvent::kStarted:
      started_ = event.started();
      has_started_ = true;
      return Status::Ok();
    case pb::MeshEvent::kFace:
      return AddFace(event.face());
    case pb::MeshEvent::kNodeIds:
      return AddNodeIds(event.node_ids());
    case pb::MeshEvent::kEdge:
      return AddEdge(event.edge());
    case pb::MeshEvent::kSummary:
      summary_ = event.summary();
      has_summary_ = true;
      return Status::Ok();
    default:
      return Status::Ok();  // progress, or an event type newer than this code
  }
}

Status MeshResultBuilder::AddFace(const pb::FaceMesh& part) {
  const int id = part.face_id();
  if (id < 1) return InvalidArgument("FaceMesh with face_id " + std::to_string(id));
  PendingFace& entry = Slot(id);
  const std::string where =
      "face " + std::to_string(id) + " part " + std::to_string(part.chunk_index()) + ": ";
  if (part.chunk_index() != entry.next_chunk) {
    return InvalidArgument(where + "expected part " + std::to_string(entry.next_chunk));
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
    face.offset = part.offset();
    face.offset_reason = part.offset_reason();
    entry.chunk_count = part.chunk_count();
    face.xyz.reserve(3 * part.node_count());
    face.triangles.reserve(3 * part.triangle_count());
  } else if (part.chunk_count() != entry.chunk_count) {
    return InvalidArgument(where + "chunk_count changed");
  }
  if (part.node_offset() != face.node_count() || part.triangle_offset() != face.triangle_count()) {
    return InvalidArgument(where + "offsets do not follow the previous part");
  }
  if (part.xyz_size() % 3 != 0 || part.triangles_size() % 3 != 0) {
    return InvalidArgument(where + "xyz or triangles not a multiple of 3");
  }
  AppendField(part.xyz(), &face.xyz);
  AppendField(part.uv(), &face.uv);
  AppendField(part.normals(), &face.normals);
  AppendField(part.triangles(), &face.triangles);
  AppendField(part.triangle_deviation(), &face.triangle_deviation);
  ++entry.next_chunk;
  if (entry.next_chunk == entry.chunk_count &&
      (face.node_count() != part.node_count() || face.triangle_count() != part.triangle_count())) {
    return InvalidArgument(where + "node or triangle count does not match the parts");
  }
  return Status::Ok();
}

Status MeshResultBuilder::AddNodeIds(const pb::FaceNodeIds& part) {
  const int id = part.face_id();
  if (id < 1 || static_cast<std::size_t>(id) > faces_.size() || faces_[id - 1].chunk_count == 0 ||
      faces_[id - 1].next_chunk != faces_[id - 1].chunk_count) {
    return InvalidArgument("FaceNodeIds for face " + std::to_string(id) + " before its FaceMesh");
  }
  PendingFace& entry = faces_[id - 1];
  if (part.chunk_index() != entry.next_ids_chunk ||
      part.node_offset() != static_cast<int64_t>(entry.face.global_ids.size())) {
    return InvalidArgument("FaceNodeIds of face " + std::to_string(id) + " out of order");
  }
  if (part.chunk_index() == 0) entry.ids_chunk_count = part.chunk_count();
  AppendField(part.global_ids(), &entry.face.global_ids);
  AppendField(part.node_dim(), &entry.node_dim);
  AppendField(part.node_entity(), &entry.node_entity);
  AppendField(part.node_param(), &entry.node_param);
  ++entry.next_ids_chunk;
  if (entry.face.global_ids.size() > static_cast<std::size_t>(entry.face.node_count())) {
    return InvalidArgument("face " + std::to_string(id) + " has more global ids than nodes");
  }
  return Status::Ok();
}

Status MeshResultBuilder::AddEdge(const pb::EdgePolyline& part) {
  const std::string where = "EdgePolyline " + std::to_string(part.edge_id()) + " part " +
                            std::to_string(part.chunk_index()) + ": ";
  if (part.chunk_index() == 0) {
    if (edge_parts_left_ != 0) return InvalidArgument(where + "the previous edge is missing parts");
    if (!edges_.empty() && part.edge_id() <= edges_.back().edge_id)
      return InvalidArgument(where + "not in edge id order");
    EdgeLine line;
    line.edge_id = part.edge_id();
    line.faces.assign(part.faces().begin(), part.faces().end());
    line.seam = part.seam();
    line.degenerate = part.degenerate();
    line.sharp = part.sharp();
    line.dihedral = part.dihedral();
    edges_.push_back(std::move(line));
    edge_parts_left_ = part.chunk_count();
  } else if (edge_parts_left_ == 0 || edges_.back().edge_id != part.edge_id() ||
             part.node_offset() != static_cast<int64_t>(edges_.back().nodes.size())) {
    return InvalidArgument(where + "out of order");
  }
  for (int64_t node : part.nodes()) {
    if (node < 0 || node > std::numeric_limits<int32_t>::max())
      return InvalidArgument(where + "node id out of range");
    edges_.back().nodes.push_back(static_cast<int32_t>(node));
  }
  --edge_parts_left_;
  if (edge_parts_left_ == 0 &&
      static_cast<int64_t>(edges_.back().nodes.size()) != part.node_count())
    return InvalidArgument(where + "node count does not match the parts");
  return Status::Ok();
}

Result<MeshResult> MeshResultBuilder::Finish() {
  if (!has_started_ || !has_summary_) return InvalidArgument("the Mesh stream ended early");
  const int face_total = started_.model().faces();
  if (faces_.size() > static_cast<std::size_t>(face_total)) {
    return InvalidArgument("a FaceMesh names a face id beyond the model's " +
                           std::to_string(face_total));
  }
  faces_.resize(face_total);
  MeshResult result;
  result.summary = FromProto(summary_);
  Mesh& mesh = result.mesh;
  const int64_t nodes = result.summary.nodes;
  mesh.xyz.assign(3 * nodes, 0.0);
  bool topology = true;
  for (const PendingFace& entry : faces_) {
    if (entry.face.status == FaceStatus::kOk &&
        entry.node_dim.size() != entry.face.global_ids.size()) {
      topology = false;
    }
  }
  // Per-triangle deviations when every face came with them (ReturnFields.triangle_deviation).
  bool deviation = true;
  for (const PendingFace& entry : faces_) {
    if (entry.face.status == FaceStatus::kOk &&
        entry.face.triangle_deviation.size() != static_cast<size_t>(entry.face.triangle_count()))
      deviation = false;
  }
  if (topology) {
    mesh.node_dim.assign(nodes, 0);
    mesh.node_entity.assign(nodes, 0);
    mesh.node_param.assign(2 * nodes, 0.0);
  }
  for (int id = 1; id <= face_total; ++id) {
    PendingFace& entry = faces_[id - 1];
    FaceMesh& face = entry.face;
    if (entry.chunk_count == 0) {  // never sent: not requested
      face.face_id = id;
      face.status = FaceStatus::kSkipped;
      face.reason = "not requested";
    } else if (entry.next_chunk != entry.chunk_count) {
      return InvalidArgument("face " + std::to_string(id) + " is missing parts");
    }
    if (face.status != FaceStatus::kOk) continue;
    if (face.global_ids.size() != static_cast<std::size_t>(face.node_count())) {
      return InvalidArgument("face " + std::to_string(id) + " is missing its global node ids");
    }
    for (int64_t i = 0; i < face.node_count(); ++i) {
      const int64_t g = face.global_ids[i];
      if (g < 0 || g >= nodes) return InvalidArgument("global node id out of range");
      for (int k = 0; k < 3; ++k) mesh.xyz[3 * g + k] = face.xyz[3 * i + k];
      if (topology) {
        mesh.node_dim[g] = static_cast<int8_t>(entry.node_dim[i]);
        mesh.node_entity[g] = entry.node_entity[i];
        mesh.node_param[2 * g] = entry.node_param[2 * i];
        mesh.node_param[2 * g + 1] = entry.node_param[2 * i + 1];
      }
    }
    for (int32_t local : face.triangles) {
      if (local < 0 || local >= face.node_count())
        return InvalidArgument("triangle node id out of range");
    }
    // As the engine assembles: face order, triangles that collapse at a pole left out.
    for (std::size_t k = 0; k + 2 < face.triangles.size(); k += 3) {
      const int64_t a = face.global_ids[face.triangles[k]];
      const int64_t b = face.global_ids[face.triangles[k + 1]];
      const int64_t c = face.global_ids[face.triangles[k + 2]];
      if (a == b || b == c || c == a) continue;
      mesh.triangles.insert(mesh.triangles.end(), {static_cast<int32_t>(a), static_cast<int32_t>(b),
                                                   static_cast<int32_t>(c)});
      mesh.triangle_face.push_back(id);
      if (deviation) mesh.triangle_deviation.push_back(face.triangle_deviation[k / 3]);
    }
  }
  if (edge_parts_left_ != 0) return InvalidArgument("an EdgePolyline is missing parts");
  for (const EdgeLine& line : edges_)
    for (int32_t node : line.nodes)
      if (node >= nodes)
        return InvalidArgument("an EdgePolyline node id is beyond the mesh's nodes");
  result.edges = std::move(edges_);
  edges_.clear();
  result.faces.reserve(face_total);
  for (PendingFace& entry : faces_) result.faces.push_back(std::move(entry.face));
  faces_.clear();
  return result;
}

}  // namespace rdmesh::server
