#pragma once
// Process exit codes of the rdmesh command line tool.

namespace rdmesh::cli {

enum ExitCode : int {
  kExitOk = 0,
  kExitMeshFailed = 1,   ///< meshing failed, or --strict and some face failed
  kExitUsage = 2,        ///< bad command line or option values
  kExitBadModel = 3,     ///< the model cannot be read
  kExitStopped = 4,      ///< --timeout passed or the run was interrupted
  kExitWriteFailed = 5,  ///< the output cannot be written
};

}  // namespace rdmesh::cli
