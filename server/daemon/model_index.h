#pragma once
// The daemon's side of the model cache: which models it has accepted, their bytes in a spool
// directory (for the workers to read), and what their first parse found. The parsed models
// themselves live in the worker processes (ModelCache); this index never runs OCCT.

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "rdmesh/engine.h"
#include "rdmesh/format_names.h"
#include "rdmesh/v1/rdmesh.pb.h"

namespace rdmesh::server {

/// A model the daemon has accepted. Immutable.
struct StoredModel {
  std::string id;                           ///< sha256 of the file bytes, 64 hex digits
  std::string name;                         ///< the name given at upload
  ModelFormat format = ModelFormat::kAuto;  ///< resolved (name, then content)
  std::string path;                         ///< the spool file holding the bytes
  uint64_t file_bytes = 0;
  ::rdmesh::v1::ModelInfo info;  ///< from the first parse (model_id, file_bytes set)
  double load_seconds = 0.0;     ///< the first parse's time
};

/// Content-addressed, bounded (file bytes), least-recently-used. The newest model is always kept.
/// A model whose parse crashed its worker is remembered and refused at once afterwards, without
/// parsing it again. Thread-safe.
class ModelIndex {
 public:
  /// Parses a spooled model (on a worker) and returns its description; errors are the parse's.
  /// `*refuse` set true means: remember the model as one that crashes the reader.
  using ParseFn =
      std::function<Result<::rdmesh::v1::ModelInfo>(const StoredModel& spooled, bool* refuse)>;

  /// `spool_dir` must exist and be writable; `limit_bytes` bounds the spooled bytes.
  ModelIndex(std::string spool_dir, uint64_t limit_bytes);
  ~ModelIndex();  ///< removes the spool files
  ModelIndex(const ModelIndex&) = delete;
  ModelIndex& operator=(const ModelIndex&) = delete;

  /// The model with this id, now the most recently used; null when absent.
  std::shared_ptr<const StoredModel> Find(const std::string& id);

  /// The model these bytes hold: from the index when present (`*was_cached` = true); otherwise
  /// the bytes are spooled and `parse` runs, once per id even when several requests bring the
  /// same bytes at once; on success the model is indexed. Refused ids fail at once.
  Result<std::shared_ptr<const StoredModel>> GetOrParse(const std::string& bytes,
                                                        const std::string& name, ModelFormat format,
                                                        const ParseFn& parse, bool* was_cached);

  int size() const;
  uint64_t bytes() const;
  uint64_t limit_bytes() const { return limit_bytes_; }
  /// Models refused because their parse crashed a worker.
  int refused() const;

 private:
  using Entry = std::shared_ptr<const StoredModel>;
  struct Parsing {
    bool done = false;
    std::optional<Result<Entry>> result;
  };

  void InsertLocked(Entry entry);
  Result<std::string> Spool(const std::string& id, const std::string& bytes, ModelFormat format);

  const std::string spool_dir_;
  const uint64_t limit_bytes_;
  mutable std::mutex mutex_;
  std::condition_variable parsed_;
  std::list<Entry> lru_;  // most recently used first
  std::map<std::string, std::list<Entry>::iterator> index_;
  std::map<std::string, std::shared_ptr<Parsing>> parsing_;
  std::map<std::string, std::string> refused_;  // id -> why
  uint64_t bytes_ = 0;
};

}  // namespace rdmesh::server
