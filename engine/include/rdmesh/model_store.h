#pragma once
// A directory of parsed models that outlives the process: after the first parse, a model is
// written in OpenCASCADE's own binary format, keyed by the content hash of its source file, so
// that a later load (another process, after a restart, on a replica sharing the volume) reads
// that instead of parsing the STEP file again.

#include <cstdint>
#include <memory>
#include <string>

#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh {

class Model;

/// Parsed models in a directory, one file per model: `<key>.rdm`, a small text header (format
/// version, the model's name, format and units, the payload's size and checksum) followed by the
/// model as an XCAF document in OCCT's binary format (BinXCAF: names, colours and assembly
/// structure survive), or as a BinTools shape for BREP models, which have no document. A model
/// loaded from the store meshes byte-identically to the one parsed from its file.
///
/// Bounded: past `limit_bytes`, the least recently used entries (file modification time, renewed
/// by every load) are deleted. Writes are atomic (a temporary file, fsync, rename), so a crash
/// mid-write never leaves an entry that a later load trusts; a corrupt or truncated entry fails
/// its checksum, is deleted and reported, never crashed on. Several processes may share one
/// directory. Thread-safe.
class ModelStore {
 public:
  /// `dir` is created when missing. `limit_bytes` 0 = no limit.
  ModelStore(std::string dir, uint64_t limit_bytes);

  /// The model stored under `key` (e.g. the sha256 of its file, hex); null when absent, or when
  /// the entry is unusable: it is then deleted and `*problem` says why.
  std::shared_ptr<const Model> Load(const std::string& key, std::string* problem,
                                    Context* context = nullptr) const;

  /// Stores `model` under `key`, replacing any entry, then evicts past the limit.
  Status Save(const std::string& key, const Model& model) const;

  const std::string& dir() const { return dir_; }
  uint64_t limit_bytes() const { return limit_bytes_; }

 private:
  std::string PathOf(const std::string& key) const;
  void Evict(const std::string& keep) const;

  std::string dir_;
  uint64_t limit_bytes_;
};

}  // namespace rdmesh
