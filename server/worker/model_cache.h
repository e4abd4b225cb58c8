#pragma once

#include <condition_variable>
#include <cstdint>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "rdmesh/engine.h"
#include "rdmesh/model_store.h"

namespace rdmesh::server {

/// A parsed model, shared by every request that uses it. Immutable.
struct CachedModel {
  std::string id;                      ///< sha256 of the file bytes, 64 hex digits
  std::shared_ptr<const Model> model;  ///< never null
  ModelInfo info;
  uint64_t file_bytes = 0;    ///< size of the file, the entry's cost in the cache
  double load_seconds = 0.0;  ///< time the parse (or the read from the store) took
  bool from_store = false;    ///< read from the persistent store, not parsed
  std::string store_problem;  ///< a discarded or unwritable store entry; "" when none
};

/// Content-addressed, bounded, least-recently-used cache of parsed models. Costs are file bytes
/// (a parsed model takes a few times that in memory). The newest entry is always kept, even when
/// it alone passes the limit. The same bytes loaded by two requests at once are parsed once.
/// Thread-safe.
class ModelCache {
 public:
  /// `limit_bytes`: total file bytes kept before the least recently used models are dropped.
  /// `store` (optional): the persistent store that models missing here are read from before
  /// they are parsed, and written to after.
  explicit ModelCache(uint64_t limit_bytes, std::shared_ptr<const ModelStore> store = nullptr);
  ModelCache(const ModelCache&) = delete;
  ModelCache& operator=(const ModelCache&) = delete;

  /// The model with this id, now the most recently used; null when absent (never uploaded or
  /// evicted).
  std::shared_ptr<const CachedModel> Find(const std::string& id);

  /// The model these bytes hold: from the cache when present (`*was_cached` = true), else from
  /// the store when it has it, else parsed (format from `format`, else from `name`'s extension,
  /// else from the content) and cached (and stored).
  /// Parse errors are the engine's (kParseError, kEmptyModel, ...).
  Result<std::shared_ptr<const CachedModel>> GetOrLoad(const std::string& bytes,
                                                       const std::string& name, ModelFormat format,
                                                       bool* was_cached);

  int size() const;
  uint64_t bytes() const;
  uint64_t limit_bytes() const { return limit_bytes_; }

 private:
  using Entry = std::shared_ptr<const CachedModel>;
  using LoadResult = Result<Entry>;
  struct Loading {
    bool done = false;
    std::optional<LoadResult> result;
  };

  void InsertLocked(Entry entry);

  const uint64_t limit_bytes_;
  const std::shared_ptr<const ModelStore> store_;
  mutable std::mutex mutex_;
  std::condition_variable loaded_;
  std::list<Entry> lru_;  // most recently used first
  std::map<std::string, std::list<Entry>::iterator> index_;
  std::map<std::string, std::shared_ptr<Loading>> loading_;
  uint64_t bytes_ = 0;
};

}  // namespace rdmesh::server
