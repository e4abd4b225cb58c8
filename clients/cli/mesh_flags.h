#pragma once
// The meshing options of the command line, kept apart from main() so every subcommand (and the
// --remote client) builds its MeshOptions the same way.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "rdmesh/engine.h"
#include "rdmesh/options.h"
#include "rdmesh/status.h"

namespace rdmesh::cli {

/// Raw flag values as parsed; defaults are MeshOptions' defaults.
struct MeshFlags {
  MeshOptions options;  ///< max_deviation_rel stays unset: it comes from the flag below
  /// --max-deviation-rel; MeshOptions::max_deviation_rel only when the flag is given.
  double max_deviation_rel = kDefaultMaxDeviationRel;
  std::string faces;   ///< "1,5,7" or ranges "2-9"; empty = all faces
  WriteOptions write;  ///< how the output file is written
  std::string lod;     ///< --lod: relative deviations "1e-2,1e-3,1e-4"; empty = one mesh
  const CLI::Option* deviation_rel_flag = nullptr;  ///< --max-deviation-rel, to see if given
};

/// Adds --max-deviation, --max-deviation-rel, --rd-tolerance, --max-triangles,
/// --min-edge-length, --max-edge-length, --nurbs, --threads, --faces and --timeout, and the
/// output flags --edges/--no-edges, --msh-parametric and --compress (which also sets
/// MeshOptions::compress), to `app`, each bound to `flags` and
/// documented with its unit and default.
void AddMeshFlags(CLI::App* app, MeshFlags* flags);

/// Parses a face list such as "1,5,7" or "2-4,9" into ascending unique ids (1-based).
/// kInvalidArgument with the offending item on a bad list.
Result<std::vector<int>> ParseFaceList(const std::string& text);

/// The MeshOptions the flags ask for (max_deviation_rel set only by --max-deviation-rel), checked
/// with ValidateOptions; kInvalidArgument with a readable message otherwise.
Result<MeshOptions> BuildMeshOptions(const MeshFlags& flags);

/// The levels of detail --lod asks for (ResolveLevels: coarsest first), empty without --lod.
/// kInvalidArgument for a bad list, or (ResolveLevels' refusal) --lod with --max-deviation-rel,
/// --max-deviation or --max-triangles.
Result<std::vector<double>> BuildLevels(const MeshFlags& flags, const MeshOptions& options);

/// Where level `level` of a --lod run is written: OUT.EXT -> OUT.lodN.EXT (N = 0 the coarsest).
std::string LevelPath(const std::string& output, int level);

}  // namespace rdmesh::cli
