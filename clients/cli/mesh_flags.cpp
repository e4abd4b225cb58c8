#include "mesh_flags.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <sstream>

namespace rdmesh::cli {

namespace {

Status BadFaces(const std::string& item) {
  return Status(StatusCode::kInvalidArgument,
                "--faces: '" + item + "' is not a face id or a range like 2-5 (ids start at 1)");
}

// A positive int, or 0 when the text is not one.
int ParseId(const std::string& text) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) return 0;
  errno = 0;
  long value = std::strtol(text.c_str(), nullptr, 10);
  return errno == 0 && value >= 1 && value <= 100000000 ? static_cast<int>(value) : 0;
}

// Names MeshOptions fields as the flags that set them: "max_deviation" -> "--max-deviation".
std::string FlagNames(std::string message) {
  static const std::regex kField(
      "\\b(max_deviation_rel|max_deviation|rd_tolerance|max_triangles|min_edge_length|"
      "max_edge_length|threads|timeout_seconds|lod|compress)\\b");
  std::string result;
  auto begin = std::sregex_iterator(message.begin(), message.end(), kField);
  size_t last = 0;
  for (auto it = begin; it != std::sregex_iterator(); ++it) {
    result += message.substr(last, it->position() - last);
    std::string flag = it->str() == "timeout_seconds" ? "timeout" : it->str();
    std::replace(flag.begin(), flag.end(), '_', '-');
    result += "--" + flag;
    last = it->position() + it->length();
  }
  return result + message.substr(last);
}

}  // namespace

void AddMeshFlags(CLI::App* app, MeshFlags* flags) {
  MeshOptions& o = flags->options;
  app->add_option("--max-deviation", o.max_deviation,
                  "Largest mesh-to-surface distance, in model units (mm for STEP/IGES); "
                  "0 = use --max-deviation-rel")
      ->capture_default_str()
      ->group("Meshing");
  flags->deviation_rel_flag =
      app->add_option("--max-deviation-rel", flags->max_deviation_rel,
                      "Largest distance as a fraction of the bounding-box diagonal (used when "
                      "--max-deviation is 0)")
          ->capture_default_str()
          ->group("Meshing");
  app->add_option("--lod", flags->lod,
                  "Levels of detail: relative deviations (as --max-deviation-rel), e.g. "
                  "1e-2,1e-3,1e-4; the model is read once and meshed once per level, coarsest "
                  "first, each level written to OUT.lodN.EXT (N = 0 the coarsest) and equal to "
                  "a run at --max-deviation-rel of that level")
      ->group("Meshing");
  app->add_option("--rd-tolerance", o.rd_tolerance,
                  "Representation-deficit tolerance, scale free (a segment turning by theta "
                  "has RD ~ theta^2/24); 0 = off")
      ->capture_default_str()
      ->group("Meshing");
  app->add_option("--max-triangles", o.max_triangles,
                  "Triangle budget for the whole model: the smallest deviation that fits; "
                  "0 = no budget")
      ->capture_default_str()
      ->group("Meshing");
  app->add_option("--min-edge-length", o.min_edge_length,
                  "Never split below this 3D edge length, in model units; 0 = off")
      ->capture_default_str()
      ->group("Meshing");
  app->add_option("--max-edge-length", o.max_edge_length,
                  "Split every edge longer than this, in model units; 0 = off")
      ->capture_default_str()
      ->group("Meshing");
  app->add_flag("--nurbs", o.nurbs,
                "Convert every face to a B-spline surface before meshing (default: exact "
                "surfaces)")
      ->group("Meshing");
  app->add_flag(
         "--off-surface", o.off_surface,
         "Let the nodes leave the surface: on faces that bend one way, the triangles lie on "
         "both sides of it within the deviation, with about half as many (docs/METHOD.md); "
         "normals stay the surface's; planes and saddles stay on it (a face that bends one way "
         "in parts moves there only)")
      ->group("Meshing");
  app->add_option("--threads", o.threads, "Worker threads; 0 = all cores")
      ->capture_default_str()
      ->group("Meshing");
  app->add_option("--faces", flags->faces,
                  "Mesh only these face ids, e.g. 1,5,7 or 2-9 (default: all faces)")
      ->group("Meshing");
  app->add_option("--timeout", o.timeout_seconds,
                  "Stop with exit code 4 after this many seconds (loading and meshing); "
                  "0 = no limit")
      ->capture_default_str()
      ->group("Meshing");
  app->add_flag("--edges,!--no-edges", flags->write.edges,
                "Also write every B-rep edge as line elements along its shared edge grid "
                "(.msh: type-1 lines on the edge's curve entity; .obj: `l` records in group "
                "'edges'; .glb: LINES primitives with _EDGE_ID under the node 'edges'); "
                "default on")
      ->group("Output");
  app->add_flag("--msh-parametric", flags->write.msh_parametric,
                ".msh: also write each node's curve parameter t or surface (u,v) (parametric "
                "nodes; Gmsh reads them, meshio 5 does not)")
      ->group("Output");
  app->add_flag("--compress", flags->write.compress,
                ".glb only: compress it (EXT_meshopt_compression + KHR_mesh_quantization; "
                "three.js reads it with its meshopt decoder): positions rounded by at most 1.5% "
                "of the deviation, which the mesh leaves free (it is meshed to 98.5%), octahedral "
                "normals, ids and edge tables compressed too (docs/GLB.md)")
      ->group("Output");
}

Result<std::vector<int>> ParseFaceList(const std::string& text) {
  std::vector<int> ids;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    item.erase(std::remove_if(item.begin(), item.end(), ::isspace), item.end());
    size_t dash = item.find('-');
    if (dash == std::string::npos) {
      int id = ParseId(item);
      if (id == 0) return BadFaces(item);
      ids.push_back(id);
      continue;
    }
    int first = ParseId(item.substr(0, dash));
    int last = ParseId(item.substr(dash + 1));
    if (first == 0 || last < first || last - first > 10000000) return BadFaces(item);
    for (int id = first; id <= last; ++id) ids.push_back(id);
  }
  if (ids.empty()) return BadFaces(text);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

Result<MeshOptions> BuildMeshOptions(const MeshFlags& flags) {
  MeshOptions options = flags.options;
  if (flags.deviation_rel_flag != nullptr && flags.deviation_rel_flag->count() > 0)
    options.max_deviation_rel = flags.max_deviation_rel;
  options.compress = flags.write.compress;
  if (!flags.faces.empty()) {
    Result<std::vector<int>> ids = ParseFaceList(flags.faces);
    if (!ids.ok()) return ids.status();
    options.face_ids = *ids;
  }
  Status valid = ValidateOptions(options);
  if (!valid.ok()) return Status(valid.code(), FlagNames(valid.message()));
  return options;
}

Result<std::vector<double>> BuildLevels(const MeshFlags& flags, const MeshOptions& options) {
  if (flags.lod.empty()) return std::vector<double>();
  std::vector<double> levels;
  std::stringstream items(flags.lod);
  std::string item;
  while (std::getline(items, item, ',')) {
    item.erase(std::remove_if(item.begin(), item.end(), ::isspace), item.end());
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(item.c_str(), &end);
    if (item.empty() || errno != 0 || end != item.c_str() + item.size())
      return Status(StatusCode::kInvalidArgument,
                    "--lod: '" + item +
                        "' is not a number (give relative deviations like "
                        "1e-2,1e-3,1e-4)");
    levels.push_back(value);
  }
  Result<std::vector<double>> resolved = ResolveLevels(levels, options);
  if (!resolved.ok())
    return Status(resolved.status().code(), FlagNames(resolved.status().message()));
  return resolved;
}

std::string LevelPath(const std::string& output, int level) {
  const std::filesystem::path path(output);
  std::filesystem::path level_path = path;
  level_path.replace_extension(".lod" + std::to_string(level) + path.extension().string());
  return level_path.string();
}

}  // namespace rdmesh::cli
