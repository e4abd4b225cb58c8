#include "worker/model_cache.h"

#include <chrono>
#include <utility>

#include "rdmesh/model_info.h"
#include "rdmesh/sha256.h"

namespace rdmesh::server {

ModelCache::ModelCache(uint64_t limit_bytes, std::shared_ptr<const ModelStore> store)
    : limit_bytes_(limit_bytes), store_(std::move(store)) {}

std::shared_ptr<const CachedModel> ModelCache::Find(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = index_.find(id);
  if (it == index_.end()) return nullptr;
  lru_.splice(lru_.begin(), lru_, it->second);
  return *it->second;
}

Result<std::shared_ptr<const CachedModel>> ModelCache::GetOrLoad(const std::string& bytes,
                                                                 const std::string& name,
                                                                 ModelFormat format,
                                                                 bool* was_cached) {
  *was_cached = false;
  if (bytes.empty()) return Status(StatusCode::kParseError, "the model file is empty (0 bytes)");
  const std::string id = Sha256Hex(bytes);
  std::shared_ptr<Loading> loading;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    auto it = index_.find(id);
    if (it != index_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second);
      *was_cached = true;
      return *it->second;
    }
    auto pending = loading_.find(id);
    if (pending != loading_.end()) {  // another request is parsing the same bytes: wait for it
      std::shared_ptr<Loading> other = pending->second;
      loaded_.wait(lock, [&] { return other->done; });
      *was_cached = other->result->ok();
      return *other->result;
    }
    loading = std::make_shared<Loading>();
    loading_[id] = loading;
  }

  // The engine resolves kAuto (ResolveFormat: the name's extension, then the content).
  const auto start = std::chrono::steady_clock::now();
  StoreOutcome outcome;
  Result<std::shared_ptr<const Model>> model =
      store_ != nullptr ? store_->LoadOrParse(bytes, format, name, nullptr, &outcome)
                        : LoadModelFromBytes(bytes, format, name);
  LoadResult result = model.status();
  if (model.ok()) {
    auto entry = std::make_shared<CachedModel>();
    entry->from_store = outcome.from_store;
    entry->store_problem = outcome.problem;
    entry->id = id;
    entry->model = *model;
    entry->info = GetModelInfo(**model);
    if (entry->info.name.empty()) entry->info.name = name;
    entry->file_bytes = bytes.size();
    entry->load_seconds = SecondsSince(start);
    if (entry->info.faces == 0) {
      result = Status(StatusCode::kEmptyModel, "the model '" + name + "' holds no faces");
    } else {
      result = Entry(std::move(entry));
    }
  }

  std::lock_guard<std::mutex> lock(mutex_);
  if (result.ok()) InsertLocked(*result);
  loading->result = result;
  loading->done = true;
  loading_.erase(id);
  loaded_.notify_all();
  return result;
}

void ModelCache::InsertLocked(Entry entry) {
  bytes_ += entry->file_bytes;
  lru_.push_front(entry);
  index_[entry->id] = lru_.begin();
  while (bytes_ > limit_bytes_ && lru_.size() > 1) {
    const Entry& oldest = lru_.back();
    bytes_ -= oldest->file_bytes;
    index_.erase(oldest->id);
    lru_.pop_back();
  }
}

int ModelCache::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(lru_.size());
}

uint64_t ModelCache::bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}

}  // namespace rdmesh::server
