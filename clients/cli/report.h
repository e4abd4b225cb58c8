#pragma once
// What the command line prints: human-readable summaries and their JSON forms.

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "rdmesh/engine.h"

namespace rdmesh::cli {

/// Timings and paths of one `rdmesh mesh` run, beside what MeshResult holds.
struct RunInfo {
  std::string model_path;
  std::string output_path;
  double load_seconds = 0.0;  ///< reading the model file
  /// The load's stages (ModelInfo::load_stages), reported as --json's load_stages.
  std::vector<std::pair<std::string, double>> load_stages;
  std::string reader;          ///< ModelInfo::reader: "rdmesh", "occt" or ""
  std::string reader_note;     ///< ModelInfo::reader_note
  double write_seconds = 0.0;  ///< writing the output file
  /// CPU time (user + system, all threads) of this process while meshing: the engine's time
  /// without the waits a loaded machine adds to the wall-clock `seconds`. For --lod, all levels.
  double mesh_cpu_seconds = 0.0;
  bool store_used = false;    ///< --cache-dir was given
  bool from_store = false;    ///< the model was read from the store, not parsed
  std::string store_problem;  ///< a discarded or unwritable store entry; "" when none
  bool off_surface = false;   ///< MeshOptions::off_surface: faces report offset, offset_reason
};

/// The load's stages as one JSON object, stage -> seconds, in load order.
nlohmann::ordered_json LoadStagesJson(const RunInfo& run);

/// Adds from_store (and store_problem when there was one) to `json` when the run used a store.
void AddStoreJson(const RunInfo& run, nlohmann::ordered_json* json);

/// ModelInfo as a JSON object with the same field names.
nlohmann::ordered_json ModelInfoJson(const ModelInfo& info);

/// The run as one JSON object: triangles, nodes, seconds (meshing, not loading), load_seconds,
/// write_seconds, mesh_cpu_seconds, from_store (with --cache-dir), requested_deviation,
/// estimated_deviation, mesh_area, exact_area, faces_ok, faces_failed, faces_skipped, model,
/// output, and faces: [{id, surface_type, triangles, deviation, area_error (|area - exact| / exact,
/// null when exact is 0), status, reason}].
nlohmann::ordered_json MeshReportJson(const MeshResult& result, const RunInfo& run);

/// Multi-line human summary of a model.
void PrintModelInfo(const ModelInfo& info, std::ostream& out);

/// Multi-line human summary of a run: model, faces ok/failed (with reasons), triangles, nodes,
/// times, requested and estimated deviation, areas and the output file.
void PrintMeshReport(const ModelInfo& info, const MeshResult& result, const RunInfo& run,
                     std::ostream& out);

}  // namespace rdmesh::cli
