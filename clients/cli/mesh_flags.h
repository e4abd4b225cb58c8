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
  MeshOptions options;
  std::string faces;   ///< "1,5,7" or ranges "2-9"; empty = all faces
  WriteOptions write;  ///< how the output file is written
};

/// Adds --max-deviation, --max-deviation-rel, --rd-tolerance, --max-triangles,
/// --min-edge-length, --max-edge-length, --nurbs, --threads, --faces and --timeout, and the
/// output flags --edges/--no-edges and --msh-parametric, to `app`, each bound to `flags` and
/// documented with its unit and default.
void AddMeshFlags(CLI::App* app, MeshFlags* flags);

/// Parses a face list such as "1,5,7" or "2-4,9" into ascending unique ids (1-based).
/// kInvalidArgument with the offending item on a bad list.
Result<std::vector<int>> ParseFaceList(const std::string& text);

/// The MeshOptions the flags ask for, checked with ValidateOptions; kInvalidArgument with a
/// readable message otherwise.
Result<MeshOptions> BuildMeshOptions(const MeshFlags& flags);

}  // namespace rdmesh::cli
