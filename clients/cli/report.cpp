#include "report.h"

#include <cmath>
#include <cstdio>
#include <string>

namespace rdmesh::cli {

namespace {

// Coordinates are millimetres for STEP and IGES (OCCT converts); BREP files carry no unit.
std::string LengthUnit(const ModelInfo& info) { return info.format == "brep" ? "" : " mm"; }

std::string Format(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

nlohmann::ordered_json AreaError(double area, double exact) {
  if (!(exact > 0.0)) return nullptr;
  return std::abs(area - exact) / exact;
}

// Meshed faces whose mesh misses the criteria: their reason says why (the triangle cap, folds
// refinement could not get past, or the B-rep's own edge tolerance).
bool OverCriteria(const FaceMesh& face) {
  return face.status == FaceStatus::kOk && !face.reason.empty();
}

}  // namespace

nlohmann::ordered_json ModelInfoJson(const ModelInfo& info) {
  return {
      {"name", info.name},
      {"format", info.format},
      {"length_unit", info.length_unit},
      {"unit_scale_mm", info.unit_scale_mm},
      {"faces", info.faces},
      {"edges", info.edges},
      {"vertices", info.vertices},
      {"solids", info.solids},
      {"shells", info.shells},
      {"unique_faces", info.unique_faces},
      {"instances", info.instances},
      {"bbox", info.bbox},
      {"diagonal", info.diagonal},
      {"surface_types", info.surface_types},
      {"part_names", info.part_names},
      {"closed", info.closed},
      {"reader", info.reader},
      {"reader_note", info.reader_note},
  };
}

nlohmann::ordered_json LoadStagesJson(const RunInfo& run) {
  nlohmann::ordered_json stages = nlohmann::ordered_json::object();
  for (const auto& [stage, seconds] : run.load_stages) stages[stage] = seconds;
  return stages;
}

void AddStoreJson(const RunInfo& run, nlohmann::ordered_json* json) {
  if (!run.store_used) return;
  (*json)["from_store"] = run.from_store;
  if (!run.store_problem.empty()) (*json)["store_problem"] = run.store_problem;
}

nlohmann::ordered_json MeshReportJson(const MeshResult& result, const RunInfo& run) {
  const MeshSummary& s = result.summary;
  int64_t over = 0;
  for (const FaceMesh& face : result.faces) over += OverCriteria(face);
  nlohmann::ordered_json faces = nlohmann::ordered_json::array();
  const bool off_surface = run.off_surface;
  for (const FaceMesh& face : result.faces) {
    faces.push_back({
        {"id", face.face_id},
        {"surface_type", SurfaceTypeName(face.surface_type)},
        {"triangles", face.triangle_count()},
        {"deviation", face.max_deviation},
        {"area_error", face.status == FaceStatus::kOk ? AreaError(face.area, face.exact_area)
                                                      : nlohmann::ordered_json(nullptr)},
        {"status", FaceStatusName(face.status)},
        {"reason", face.reason},
        {"seconds", face.seconds},
    });
    if (off_surface) {
      faces.back()["offset"] = face.offset;
      faces.back()["offset_reason"] = face.offset_reason;
    }
  }
  nlohmann::ordered_json json = {
      {"model", run.model_path},
      {"output", run.output_path},
      {"triangles", result.mesh.triangle_count()},
      {"nodes", result.mesh.node_count()},
      {"seconds", s.seconds},
      {"edge_seconds", s.edge_seconds},
      {"face_seconds", s.face_seconds},
      {"load_seconds", run.load_seconds},
      {"load_stages", LoadStagesJson(run)},
      {"reader", run.reader},
      {"reader_note", run.reader_note},
      {"write_seconds", run.write_seconds},
      {"mesh_cpu_seconds", run.mesh_cpu_seconds},
      {"requested_deviation", s.requested_deviation},
      {"estimated_deviation", s.estimated_deviation},
      {"mesh_area", s.mesh_area},
      {"exact_area", s.exact_area},
      {"area_error", AreaError(s.mesh_area, s.exact_area)},
      {"faces_ok", s.faces_ok},
      {"faces_failed", s.faces_failed},
      {"faces_skipped", s.faces_skipped},
      {"faces_over_criteria", over},
      {"faces", faces},
  };
  AddStoreJson(run, &json);
  return json;
}

void PrintModelInfo(const ModelInfo& info, std::ostream& out) {
  std::string unit = LengthUnit(info);
  out << "model      " << info.name << " (" << info.format;
  if (!info.length_unit.empty())
    out << ", file unit " << info.length_unit << (unit.empty() ? "" : ", coordinates in mm");
  out << ")\n";
  out << "topology   " << info.faces << " faces (" << info.unique_faces << " unique), "
      << info.edges << " edges, " << info.vertices << " vertices, " << info.shells << " shells, "
      << info.solids << " solids, " << (info.closed ? "closed" : "open") << "\n";
  out << "parts      " << info.instances << " placed instance" << (info.instances == 1 ? "" : "s");
  if (!info.part_names.empty()) {
    out << " of " << info.part_names.size() << " named part"
        << (info.part_names.size() == 1 ? "" : "s") << ":";
    for (const std::string& name : info.part_names) out << " '" << name << "'";
  }
  out << "\n";
  out << "bbox       [" << info.bbox[0] << ", " << info.bbox[1] << ", " << info.bbox[2] << "] - ["
      << info.bbox[3] << ", " << info.bbox[4] << ", " << info.bbox[5] << "]" << unit
      << ", diagonal " << info.diagonal << unit << "\n";
  out << "surfaces  ";
  for (const auto& [type, count] : info.surface_types) out << " " << type << " " << count;
  out << "\n";
}

void PrintMeshReport(const ModelInfo& info, const MeshResult& result, const RunInfo& run,
                     std::ostream& out) {
  const MeshSummary& s = result.summary;
  std::string unit = LengthUnit(info);
  out << "model      " << run.model_path << " (" << info.faces << " faces)\n";
  out << "faces      " << s.faces_ok << " ok, " << s.faces_failed << " failed, " << s.faces_skipped
      << " skipped\n";
  out << "mesh       " << result.mesh.triangle_count() << " triangles, " << result.mesh.node_count()
      << " nodes\n";
  out << "deviation  requested "
      << (s.requested_deviation > 0 ? Format("%.4g", s.requested_deviation) + unit : "none")
      << ", estimated " << Format("%.4g", s.estimated_deviation) << unit << "\n";
  if (s.exact_area > 0)
    out << "area       mesh " << Format("%.6g", s.mesh_area) << ", exact "
        << Format("%.6g", s.exact_area) << " (error "
        << Format("%.3g", 100.0 * std::abs(s.mesh_area - s.exact_area) / s.exact_area) << "%)\n";
  out << "time       load " << Format("%.2f", run.load_seconds)
      << (run.from_store ? " s (from the store), mesh " : " s, mesh ") << Format("%.2f", s.seconds)
      << " s, write " << Format("%.2f", run.write_seconds) << " s\n";
  out << "output     " << run.output_path << "\n";
  auto list = [&](const char* title, bool (*pick)(const FaceMesh&)) {
    bool first = true;
    for (const FaceMesh& face : result.faces) {
      if (!pick(face)) continue;
      if (first) out << title << "\n", first = false;
      out << "  face " << face.face_id << " (" << SurfaceTypeName(face.surface_type)
          << "): " << (face.reason.empty() ? "no reason given" : face.reason) << "\n";
    }
  };
  list("failed faces:", [](const FaceMesh& face) { return face.status == FaceStatus::kFailed; });
  list("faces meshed over the criteria:", OverCriteria);
}

}  // namespace rdmesh::cli
