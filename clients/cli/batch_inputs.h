#pragma once
// The inputs of `rdmesh batch`: files, folders walked for model files, and @lists, each mapped to
// the output path that mirrors it under OUTDIR.

#include <string>
#include <vector>

#include "rdmesh/status.h"

namespace rdmesh::cli {

/// One model file to mesh.
struct BatchInput {
  std::string path;     ///< absolute, lexically normal (symlinks kept as named)
  std::string output;   ///< where its mesh goes, relative to OUTDIR ('/' separated)
  bool listed = false;  ///< named by an @list (a missing one is reported, not refused)
};

/// True for the extensions a folder walk picks up: .step .stp .iges .igs .brep (any case).
bool IsModelFile(const std::string& path);

/// Collects the inputs of `args` in order, each folder's files sorted by path:
/// - a folder: every model file below it (IsModelFile), mirrored relative to the folder;
/// - a file: itself, mirrored as its file name;
/// - @FILE: one path per line (blank lines and lines starting with # skipped), relative ones
///   taken from FILE's folder; each is a file or a folder as above, mirrored relative to FILE's
///   folder, or when some lie outside it, to the deepest folder that holds them all.
/// The output is the mirrored path with its extension replaced by `extension` (".glb"); inputs
/// that differ only in their extension keep it ("a.step.glb", "a.stp.glb"). A file named twice
/// counts once; `output_dir` is not walked. kInvalidArgument for an argument that does not exist,
/// an unreadable list, an empty result, or two inputs that would still write one output.
Result<std::vector<BatchInput>> CollectInputs(const std::vector<std::string>& args,
                                              const std::string& extension,
                                              const std::string& output_dir);

}  // namespace rdmesh::cli
