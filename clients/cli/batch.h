#pragma once
// `rdmesh batch INPUT... -o OUTDIR`: meshes a dataset. Each file runs in a child `rdmesh mesh`
// process of its own (a crash, hang or memory blow-up costs that file only), --jobs at a time;
// the meshes mirror the inputs' paths under OUTDIR and OUTDIR/manifest.jsonl says what became
// of each file. A second run skips the files already done. Manual: docs/BATCH.md.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "mesh_flags.h"

namespace rdmesh::cli {

/// The batch command's flags as parsed.
struct BatchFlags {
  std::vector<std::string> inputs;  ///< files, folders and @lists
  std::string output_dir;
  std::string format = "glb";  ///< output extension without the dot
  int jobs = 0;                ///< children at a time; 0 = all cores
  int64_t memory_limit = -1;   ///< RLIMIT_AS per child in bytes; -1 = memory / jobs, 0 = none
  bool json = false;           ///< the summary as one JSON object, the last stdout line
  bool quiet = false;          ///< no progress, no per-file lines, no human summary
  MeshFlags mesh;              ///< checked here, handed to each child as given
  std::vector<const CLI::Option*> passed_on;  ///< the mesh and cache options, as given
};

/// Adds the `batch` subcommand to `app`, bound to `flags`.
CLI::App* AddBatchCommand(CLI::App* app, BatchFlags* flags);

/// Runs the batch; the exit code: 0 when every file is ok, 1 when any is not, 2 for bad usage,
/// 4 when interrupted before every file was done. `main` is this program's main: each child runs
/// it in a fork of this process, which has loaded the libraries already, instead of executing
/// the binary anew (RDMESH_BATCH_MESHER, another program, is executed).
int RunBatch(const BatchFlags& flags, int (*main)(int argc, char** argv));

}  // namespace rdmesh::cli
