#include "rdmesh/model_store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Standard_Version.hxx>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <vector>

#include "model/model.h"
#include "model/model_payload.h"
#include "model/model_readers.h"
#include "rdmesh/atomic_file.h"
#include "rdmesh/sha256.h"

namespace rdmesh {
namespace {

/// The entry format: the header's first line. Bump it when the payload or the header changes.
constexpr const char* kMagic = "RDMESH-PARSED-MODEL 3";
/// Temporary files of writers that died are removed after this long.
constexpr auto kStaleTemporary = std::chrono::hours(1);

/// 64-bit FNV-1a: detects a truncated or damaged entry (the directory is the service's own, so
/// nothing adversarial is expected of it).
uint64_t Checksum(const std::string& bytes) {
  uint64_t hash = 1469598103934665603ull;
  for (unsigned char c : bytes) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  return hash;
}

/// DerivedValues as bytes: the face count, the face areas, bbox and diagonal, every number as 8
/// little-endian bytes (doubles bit for bit, so the values read back are the same).
void PutWord(uint64_t word, std::string* out) {
  for (int i = 0; i < 8; ++i) out->push_back(static_cast<char>((word >> (8 * i)) & 0xff));
}

void PutDouble(double value, std::string* out) {
  uint64_t word;
  std::memcpy(&word, &value, sizeof(word));
  PutWord(word, out);
}

std::string EncodeDerived(const DerivedValues& derived) {
  std::string out;
  PutWord(derived.face_area.size(), &out);
  for (double area : derived.face_area) PutDouble(area, &out);
  for (double bound : derived.bbox) PutDouble(bound, &out);
  PutDouble(derived.diagonal, &out);
  return out;
}

/// The inverse of EncodeDerived; false when the bytes do not hold one.
bool DecodeDerived(const std::string& bytes, DerivedValues* derived) {
  std::size_t at = 0;
  const auto word = [&](uint64_t* value) {
    if (bytes.size() - at < 8) return false;
    *value = 0;
    for (int i = 0; i < 8; ++i)
      *value |= static_cast<uint64_t>(static_cast<unsigned char>(bytes[at + i])) << (8 * i);
    at += 8;
    return true;
  };
  const auto real = [&](double* value) {
    uint64_t bits;
    if (!word(&bits)) return false;
    std::memcpy(value, &bits, sizeof(bits));
    return true;
  };
  uint64_t faces = 0;
  if (!word(&faces) || faces != (bytes.size() - 8) / 8 - 7) return false;
  derived->face_area.resize(faces);
  for (double& area : derived->face_area)
    if (!real(&area)) return false;
  for (double& bound : derived->bbox)
    if (!real(&bound)) return false;
  return real(&derived->diagonal) && at == bytes.size();
}

}  // namespace

ModelStore::ModelStore(std::string dir, uint64_t limit_bytes)
    : dir_(std::move(dir)), limit_bytes_(limit_bytes) {
  std::error_code ignored;
  std::filesystem::create_directories(dir_, ignored);
}

std::string ModelStore::KeyOf(const std::string& bytes, ModelFormat format) {
  return Sha256Hex(bytes) + "-" + FormatName(format);
}

std::string ModelStore::PathOf(const std::string& key) const { return dir_ + "/" + key + ".rdm"; }

Result<std::shared_ptr<const Model>> ModelStore::LoadOrParse(const std::string& bytes,
                                                             ModelFormat format,
                                                             const std::string& name,
                                                             Context* context,
                                                             StoreOutcome* outcome) const {
  return LoadOrParseAs(bytes, ResolveFormat(format, name, bytes), "", name, name, context, outcome);
}

Result<std::shared_ptr<const Model>> ModelStore::LoadFile(const std::string& path, Context* context,
                                                          StoreOutcome* outcome) const {
  Result<std::string> bytes = ReadModelFile(path);
  if (!bytes.ok()) return bytes.status();
  const std::string name = std::filesystem::path(path).filename().string();
  return LoadOrParseAs(*bytes, ResolveFormat(ModelFormat::kAuto, path, *bytes), path, path, name,
                       context, outcome);
}

Result<std::shared_ptr<const Model>> ModelStore::LoadOrParseAs(
    const std::string& bytes, ModelFormat format, const std::string& path, const std::string& name,
    const std::string& display_name, Context* context, StoreOutcome* outcome) const {
  StoreOutcome ignored;
  if (outcome == nullptr) outcome = &ignored;
  *outcome = StoreOutcome();
  if (format != ModelFormat::kAuto) {
    outcome->key = KeyOf(bytes, format);
    std::shared_ptr<const Model> stored =
        Load(outcome->key, format, display_name, &outcome->problem, context);
    if (stored != nullptr) {
      outcome->from_store = true;
      return stored;
    }
  }
  Result<CanonicalModel> parsed = ParseCanonical(bytes, format, path, name, display_name, context);
  if (!parsed.ok()) return parsed.status();
  if (!outcome->key.empty()) {
    Status saved = Save(outcome->key, *parsed);
    if (!saved.ok()) {
      outcome->problem += (outcome->problem.empty() ? "" : "; ") + saved.message();
    }
  }
  return parsed->model;
}

std::shared_ptr<const Model> ModelStore::Load(const std::string& key, ModelFormat format,
                                              const std::string& name, std::string* problem,
                                              Context* context) const {
  problem->clear();
  const std::string path = PathOf(key);
  std::ifstream file(path, std::ios::binary);
  if (!file) return nullptr;
  std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const auto discard = [&](const std::string& why) -> std::shared_ptr<const Model> {
    *problem = "parsed model " + path + " discarded: " + why;
    unlink(path.c_str());
    return nullptr;
  };
  // Header: lines "key=value" after the magic line, up to an empty line.
  std::istringstream header(bytes);
  std::string line;
  if (!std::getline(header, line) || line != kMagic) return discard("not an rdmesh entry");
  std::string format_name, unit, kind_name, occt;
  double scale = 1.0;
  uint64_t size = 0, derived_size = 0, checksum = 0;
  while (std::getline(header, line) && !line.empty()) {
    const std::size_t eq = line.find('=');
    if (eq == std::string::npos) return discard("a damaged header");
    const std::string field = line.substr(0, eq);
    const std::string value = line.substr(eq + 1);
    if (field == "format") format_name = value;
    if (field == "occt") occt = value;
    if (field == "length_unit") unit = value;
    if (field == "unit_scale_mm") scale = std::strtod(value.c_str(), nullptr);
    if (field == "payload") kind_name = value;
    if (field == "payload_bytes") size = std::strtoull(value.c_str(), nullptr, 10);
    if (field == "derived_bytes") derived_size = std::strtoull(value.c_str(), nullptr, 10);
    if (field == "body_fnv1a64") checksum = std::strtoull(value.c_str(), nullptr, 16);
  }
  if (!header) return discard("a truncated header");
  const std::size_t start = static_cast<std::size_t>(header.tellg());
  if (bytes.size() - start != size + derived_size) {
    return discard("truncated (" + std::to_string(bytes.size() - start) +
                   " bytes after the header, " + std::to_string(size + derived_size) +
                   " expected)");
  }
  const std::string body = bytes.substr(start);
  if (Checksum(body) != checksum) return discard("corrupt (checksum differs)");
  DerivedValues derived;
  if (!DecodeDerived(body.substr(size), &derived)) return discard("damaged derived values");
  // Another OCCT may read the payload into other bits than the parse here would give.
  if (occt != OCC_VERSION_COMPLETE) return discard("written by OCCT " + occt);
  if (format_name != FormatName(format)) return discard("a " + format_name + " model");
  PayloadKind kind;
  if (!PayloadKindFromName(kind_name, &kind)) return discard("an unknown payload " + kind_name);

  Result<ReadShape> read = ReadPayload(body.substr(0, size), kind);
  if (!read.ok()) return discard(read.status().message());
  read->length_unit = unit;
  read->unit_scale_mm = scale;
  Result<std::shared_ptr<const Model>> model =
      BuildModel(std::move(*read), format, name, name, &derived);
  if (!model.ok()) return discard(model.status().message());
  if (context != nullptr && context->ShouldStop()) return nullptr;
  utimensat(AT_FDCWD, path.c_str(), nullptr, 0);  // most recently used now
  return *model;
}

Status ModelStore::Save(const std::string& key, const CanonicalModel& model) const {
  const ModelInfo& info = model.model->info;
  const std::string derived = EncodeDerived(DerivedValuesOf(*model.model));
  std::string body;
  body.reserve(model.payload.size() + derived.size());
  body.append(model.payload).append(derived);
  std::ostringstream entry;
  char scale[64];
  std::snprintf(scale, sizeof(scale), "%.17g", info.unit_scale_mm);
  char checksum[32];
  std::snprintf(checksum, sizeof(checksum), "%016llx",
                static_cast<unsigned long long>(Checksum(body)));
  entry << kMagic << "\nformat=" << info.format << "\nocct=" << OCC_VERSION_COMPLETE
        << "\nlength_unit=" << info.length_unit << "\nunit_scale_mm=" << scale
        << "\npayload=" << PayloadKindName(model.kind) << "\npayload_bytes=" << model.payload.size()
        << "\nderived_bytes=" << derived.size() << "\nbody_fnv1a64=" << checksum << "\n\n";
  const std::string path = PathOf(key);
  const std::string partial = path + ".tmp." + std::to_string(getpid()) + "." +
                              std::to_string(reinterpret_cast<uintptr_t>(&body));
  Status written = WriteFileAtomically(path, partial, entry.str() + body, 0644, /*durable=*/true);
  if (!written.ok()) {
    return Status(StatusCode::kIoError,
                  "cannot write the parsed model " + path + ": " + written.message());
  }
  Evict(key);
  return Status::Ok();
}

void ModelStore::Evict(const std::string& keep) const {
  struct Entry {
    std::filesystem::path path;
    uint64_t bytes;
    std::filesystem::file_time_type used;
  };
  std::vector<Entry> entries;
  uint64_t total = 0;
  const auto now = std::filesystem::file_time_type::clock::now();
  std::error_code error;
  for (const auto& item : std::filesystem::directory_iterator(dir_, error)) {
    std::error_code stat_error;
    const uint64_t bytes = item.file_size(stat_error);
    const auto used = item.last_write_time(stat_error);
    if (stat_error) continue;
    const std::string file = item.path().filename().string();
    if (file.find(".rdm.tmp.") != std::string::npos) {
      // A writer that died mid-write (a live one renames its file within seconds).
      std::error_code ignored;
      if (now - used > kStaleTemporary) std::filesystem::remove(item.path(), ignored);
      continue;
    }
    if (item.path().extension() != ".rdm") continue;
    entries.push_back({item.path(), bytes, used});
    total += bytes;
  }
  if (limit_bytes_ == 0) return;
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.used < b.used; });
  for (const Entry& entry : entries) {
    if (total <= limit_bytes_) break;
    if (entry.path.stem() == keep) continue;
    std::error_code ignored;
    if (std::filesystem::remove(entry.path, ignored)) total -= entry.bytes;
  }
}

}  // namespace rdmesh
