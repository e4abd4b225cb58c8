#pragma once
// What a loaded model is: its summary (ModelInfo) and its file format (ModelFormat). Kept apart
// from the facade engine.h so that the engine's loading stages need not include it.

#include <array>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace rdmesh {

/// What a model holds, for `rdmesh info` and the service's ModelInfo.
struct ModelInfo {
  std::string name;            ///< file name, or the name given at upload
  std::string format;          ///< "step", "iges" or "brep"
  std::string length_unit;     ///< the file's own length unit, e.g. "mm", "inch"
  double unit_scale_mm = 1.0;  ///< how many mm one file unit is (coordinates are always in mm)
  int faces = 0;               ///< face ids 1..faces
  int edges = 0;               ///< edge ids 1..edges
  int vertices = 0;
  int solids = 0;
  int shells = 0;
  int unique_faces = 0;                      ///< faces after instancing (each meshed once)
  int instances = 0;                         ///< placed part instances
  std::array<double, 6> bbox{};              ///< xmin ymin zmin xmax ymax zmax, model units
  double diagonal = 0.0;                     ///< bbox diagonal, model units
  std::map<std::string, int> surface_types;  ///< SurfaceTypeName -> face count
  std::vector<std::string> part_names;       ///< names of the parts (XCAF labels)
  bool closed = false;                       ///< every edge bounds exactly two faces (seams aside)
  /// Where the load's time went, in order (stage, seconds): the reader's stages (e.g.
  /// occt_parse, occt_transfer), canonical (the round trip through the stored form), then the
  /// model's: topology (ids, adjacency, instances), areas, info (the tight box and the counts).
  /// A model read from the store has only the model's stages.
  std::vector<std::pair<std::string, double>> load_stages;
  /// The STEP reader that built the model: "rdmesh" (its own) or "occt" (OCCT's, for files the
  /// own reader does not cover; reader_note says why). "" for other formats and stored models.
  std::string reader;
  std::string reader_note;
};

/// Model file formats.
enum class ModelFormat { kAuto, kStep, kIges, kBrep };

/// The format named by a path's extension (.step/.stp, .iges/.igs, .brep/.brp, any case), or
/// kAuto when the extension is none of these.
ModelFormat FormatFromExtension(const std::string& path);

/// The format a file's first bytes show, or kAuto when none matches: STEP starts with
/// "ISO-10303-21" (after white space and a UTF-8 byte order mark), BREP holds "CASCADE Topology"
/// or "DBRep_DrawableShape" in its first 512 bytes, IGES starts with an 80-column line (73 to 82
/// characters) with 'S' in column 73.
ModelFormat FormatFromContent(const std::string& bytes);

/// The format a model is read as: `format` unless kAuto, else the one `name`'s extension names,
/// else the one `bytes` show; kAuto when none fits. The one rule of LoadModel,
/// LoadModelFromBytes, the model store and the service.
ModelFormat ResolveFormat(ModelFormat format, const std::string& name, const std::string& bytes);

}  // namespace rdmesh
