#include "batch_manifest.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

#include "rdmesh/atomic_file.h"

namespace rdmesh::cli {

namespace {

Status IoError(const std::string& what, const std::string& path) {
  return Status(StatusCode::kIoError,
                "cannot " + what + " '" + path + "': " + std::strerror(errno));
}

// Writes all of `text` to `fd`, retrying short writes.
bool WriteAll(int fd, const std::string& text) {
  size_t done = 0;
  while (done < text.size()) {
    ssize_t count = write(fd, text.data() + done, text.size() - done);
    if (count < 0 && errno == EINTR) continue;
    if (count <= 0) return false;
    done += static_cast<size_t>(count);
  }
  return true;
}

}  // namespace

Manifest::~Manifest() {
  if (fd_ >= 0) close(fd_);
}

Status Manifest::Load(int* skipped) {
  *skipped = 0;
  std::error_code error;
  if (!std::filesystem::exists(path_, error)) return Status::Ok();
  std::ifstream in(path_);
  if (!in) return IoError("read", path_);
  std::string line;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    nlohmann::ordered_json entry = nlohmann::ordered_json::parse(line, nullptr, false);
    if (entry.is_discarded() || !entry.is_object() || !entry.contains("path") ||
        !entry["path"].is_string()) {
      ++*skipped;
      continue;
    }
    const std::string path = entry["path"];
    if (entries_.find(path) == entries_.end()) seen_.push_back(path);
    entries_[path] = std::move(entry);
  }
  return Status::Ok();
}

const nlohmann::ordered_json* Manifest::Find(const std::string& path) const {
  auto it = entries_.find(path);
  return it == entries_.end() ? nullptr : &it->second;
}

void Manifest::Forget(const std::string& path) { entries_.erase(path); }

Status Manifest::Append(const nlohmann::ordered_json& entry) {
  const std::string path = entry["path"];
  if (entries_.find(path) == entries_.end()) seen_.push_back(path);
  entries_[path] = entry;
  if (fd_ < 0) {
    fd_ = open(path_.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) return IoError("write", path_);
    // A killed run may have left a torn last line: start on a line of our own.
    char last = '\n';
    const off_t size = lseek(fd_, 0, SEEK_END);
    if (size > 0 && pread(fd_, &last, 1, size - 1) == 1 && last != '\n' && !WriteAll(fd_, "\n"))
      return IoError("write", path_);
  }
  if (!WriteAll(fd_, entry.dump() + "\n")) return IoError("write", path_);
  return Status::Ok();
}

Status Manifest::Rewrite(const std::vector<std::string>& order) {
  std::string text;
  std::set<std::string> written;
  auto add = [&](const std::string& path) {
    auto it = entries_.find(path);
    if (it == entries_.end() || !written.insert(path).second) return;
    text += it->second.dump() + "\n";
  };
  for (const std::string& path : order) add(path);
  for (const std::string& path : seen_) add(path);
  if (fd_ >= 0) {
    close(fd_);
    fd_ = -1;
  }
  Status status = WriteFileAtomically(path_, path_ + ".partial", text, 0644, true);
  if (!status.ok()) return Status(status.code(), "cannot write the manifest: " + status.message());
  return Status::Ok();
}

}  // namespace rdmesh::cli
