#include "daemon/model_index.h"

#include <unistd.h>

#include <cstdio>
#include <utility>

#include "rdmesh/atomic_file.h"
#include "rdmesh/model_info.h"
#include "rdmesh/sha256.h"

namespace rdmesh::server {
namespace {

/// At most this many refused ids are remembered (past it, the lowest ids are forgotten).
constexpr std::size_t kMaxRefused = 100000;

const char* Extension(ModelFormat format) {
  switch (format) {
    case ModelFormat::kStep:
      return ".step";
    case ModelFormat::kIges:
      return ".iges";
    case ModelFormat::kBrep:
      return ".brep";
    case ModelFormat::kAuto:
      break;
  }
  return ".model";
}

}  // namespace

ModelIndex::ModelIndex(std::string spool_dir, uint64_t limit_bytes)
    : spool_dir_(std::move(spool_dir)), limit_bytes_(limit_bytes) {}

ModelIndex::~ModelIndex() {
  for (const Entry& entry : lru_) unlink(entry->path.c_str());
}

std::shared_ptr<const StoredModel> ModelIndex::Find(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = index_.find(id);
  if (it == index_.end()) return nullptr;
  lru_.splice(lru_.begin(), lru_, it->second);
  return *it->second;
}

Result<std::string> ModelIndex::Spool(const std::string& id, const std::string& bytes,
                                      ModelFormat format) {
  const std::string path = spool_dir_ + "/" + id + Extension(format);
  Status written = WriteFileAtomically(path, path + ".part", bytes, 0600, /*durable=*/false);
  if (!written.ok()) {
    return Status(StatusCode::kIoError, "cannot store the model in the server's spool directory " +
                                            spool_dir_ + ": " + written.message());
  }
  return path;
}

Result<std::shared_ptr<const StoredModel>> ModelIndex::GetOrParse(const std::string& bytes,
                                                                  const std::string& name,
                                                                  ModelFormat format,
                                                                  const ParseFn& parse,
                                                                  bool* was_cached) {
  *was_cached = false;
  if (bytes.empty()) return Status(StatusCode::kParseError, "the model file is empty (0 bytes)");
  const std::string id = Sha256Hex(bytes);
  format = ResolveFormat(format, name, bytes);  // the engine's rule, as the worker will read it
  std::shared_ptr<Parsing> parsing;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (auto refused = refused_.find(id); refused != refused_.end()) {
      return Status(StatusCode::kParseError,
                    refused->second + " before; refused without parsing it again");
    }
    auto it = index_.find(id);
    if (it != index_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second);
      *was_cached = true;
      return *it->second;
    }
    auto pending = parsing_.find(id);
    if (pending != parsing_.end()) {  // another request is parsing the same bytes: wait for it
      std::shared_ptr<Parsing> other = pending->second;
      parsed_.wait(lock, [&] { return other->done; });
      *was_cached = other->result->ok();
      return *other->result;
    }
    parsing = std::make_shared<Parsing>();
    parsing_[id] = parsing;
  }

  Result<Entry> result = Status(StatusCode::kInternal, "not parsed");
  bool refuse = false;
  auto stored = std::make_shared<StoredModel>();
  stored->id = id;
  stored->name = name;
  stored->format = format;
  stored->file_bytes = bytes.size();
  Result<std::string> path = Spool(id, bytes, format);
  if (!path.ok()) {
    result = path.status();
  } else {
    stored->path = *path;
    Result<::rdmesh::v1::ModelInfo> info = parse(*stored, &refuse);
    if (info.ok()) {
      stored->info = std::move(*info);
      stored->load_seconds = stored->info.load_seconds();
      result = Entry(std::move(stored));
    } else {
      unlink(stored->path.c_str());
      result = info.status();
    }
  }

  std::lock_guard<std::mutex> lock(mutex_);
  if (result.ok()) InsertLocked(*result);
  if (refuse) {
    if (refused_.size() >= kMaxRefused) refused_.erase(refused_.begin());
    refused_[id] = result.status().message();
  }
  parsing->result = result;
  parsing->done = true;
  parsing_.erase(id);
  parsed_.notify_all();
  return result;
}

void ModelIndex::InsertLocked(Entry entry) {
  bytes_ += entry->file_bytes;
  lru_.push_front(entry);
  index_[entry->id] = lru_.begin();
  while (bytes_ > limit_bytes_ && lru_.size() > 1) {
    const Entry& oldest = lru_.back();
    bytes_ -= oldest->file_bytes;
    unlink(oldest->path.c_str());
    index_.erase(oldest->id);
    lru_.pop_back();
  }
}

int ModelIndex::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(lru_.size());
}

uint64_t ModelIndex::bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}

int ModelIndex::refused() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(refused_.size());
}

}  // namespace rdmesh::server
