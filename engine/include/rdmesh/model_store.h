#pragma once
// A directory of parsed models that outlives the process: after the first parse, a model is
// written in OpenCASCADE's own binary format, keyed by the content hash of its source file, so
// that a later load (another process, after a restart, on a replica sharing the volume) reads
// that instead of parsing the STEP file again.

#include <cstdint>
#include <memory>
#include <string>

#include "rdmesh/context.h"
#include "rdmesh/model_info.h"
#include "rdmesh/status.h"

namespace rdmesh {

class Model;
struct CanonicalModel;

/// What ModelStore::LoadOrParse did.
struct StoreOutcome {
  std::string key;          ///< the entry's key (sha256 of the bytes, then the format)
  bool from_store = false;  ///< read from the store (true) or parsed from the file bytes
  /// A discarded entry (corrupt, truncated, another OCCT version) or an entry that could not be
  /// written; "" when none. Never fatal: the model was parsed instead.
  std::string problem;
};

/// Parsed models in a directory, one file per model: `<key>.rdm`, a small text header (format
/// version, OCCT version, the model's format and units, sizes and an FNV-1a checksum of the rest)
/// followed by the payload of model_payload.h: the model as an XCAF document in OCCT's binary
/// format (BinXCAF: names, colours and assembly structure survive), or as a BinTools shape for
/// BREP models, which have no document; then the values that are slow to compute from it (exact
/// face areas, the tight bounding box: DerivedValues in model.h), bit for bit.
///
/// Every load of a model file goes through that payload (see ParseCanonical in model.h), and the
/// store keeps exactly those bytes, so a model read from the store and one parsed from its file
/// are the same bits and mesh byte-identically, whichever process parsed it first.
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

  /// The key of a model file's bytes read as `format` (not kAuto): sha256 hex, '-', the format.
  static std::string KeyOf(const std::string& bytes, ModelFormat format);

  /// The model these bytes hold, as LoadModelFromBytes would return it (`format` kAuto: from
  /// `name`'s extension, else the content): from the store when it has a usable entry, else
  /// parsed, then written to the store. `name` appears in messages and ModelInfo. `*outcome`
  /// (optional) says which, and any problem with the store.
  Result<std::shared_ptr<const Model>> LoadOrParse(const std::string& bytes, ModelFormat format,
                                                   const std::string& name, Context* context,
                                                   StoreOutcome* outcome) const;

  /// LoadOrParse of a file on disk, with LoadModel's errors and names (messages name the path,
  /// ModelInfo the file name).
  Result<std::shared_ptr<const Model>> LoadFile(const std::string& path, Context* context,
                                                StoreOutcome* outcome) const;

  /// The model stored under `key`, named `name` in ModelInfo, read as `format`; null when
  /// absent, or when the entry is unusable: it is then deleted and `*problem` says why.
  std::shared_ptr<const Model> Load(const std::string& key, ModelFormat format,
                                    const std::string& name, std::string* problem,
                                    Context* context = nullptr) const;

  /// Stores `model`'s payload under `key`, replacing any entry, then evicts past the limit.
  Status Save(const std::string& key, const CanonicalModel& model) const;

  const std::string& dir() const { return dir_; }
  uint64_t limit_bytes() const { return limit_bytes_; }

 private:
  std::string PathOf(const std::string& key) const;
  Result<std::shared_ptr<const Model>> LoadOrParseAs(const std::string& bytes, ModelFormat format,
                                                     const std::string& path,
                                                     const std::string& name,
                                                     const std::string& display_name,
                                                     Context* context, StoreOutcome* outcome) const;
  void Evict(const std::string& keep) const;

  std::string dir_;
  uint64_t limit_bytes_;
};

}  // namespace rdmesh
