#pragma once
// OUTDIR/manifest.jsonl of `rdmesh batch`: one JSON object per input file, keyed by its path.

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rdmesh/status.h"

namespace rdmesh::cli {

/// The manifest file. A run appends one line per finished file as it goes (so a killed run keeps
/// what it finished), and at its end rewrites the file with one line per input, the latest.
class Manifest {
 public:
  explicit Manifest(std::string path) : path_(std::move(path)) {}
  ~Manifest();
  Manifest(const Manifest&) = delete;
  Manifest& operator=(const Manifest&) = delete;

  /// Reads the file; a missing file is an empty manifest. Lines that are not a JSON object with a
  /// "path" (the torn last line of a killed run) are skipped; `skipped` gets their count.
  Status Load(int* skipped);

  /// The latest entry for the input `path`, or nullptr.
  const nlohmann::ordered_json* Find(const std::string& path) const;

  /// Drops the entry of `path` (an input of an earlier run whose output a new input takes).
  void Forget(const std::string& path);

  /// Every entry, path -> entry.
  const std::map<std::string, nlohmann::ordered_json>& entries() const { return entries_; }

  /// Records `entry` (its "path" replaces an older entry) and appends it as one line, written
  /// with one write(2) so that a killed run leaves whole lines.
  Status Append(const nlohmann::ordered_json& entry);

  /// Rewrites the file with one line per entry: the paths of `order` first, then the others in
  /// the order they were first seen. Written to a partial file, then renamed over the old one.
  Status Rewrite(const std::vector<std::string>& order);

 private:
  std::string path_;
  std::map<std::string, nlohmann::ordered_json> entries_;
  std::vector<std::string> seen_;  ///< paths in the order first seen
  int fd_ = -1;                    ///< open for appending once the first line is written
};

}  // namespace rdmesh::cli
