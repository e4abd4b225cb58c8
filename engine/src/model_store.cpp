#include "rdmesh/model_store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <BinTools.hxx>
#include <BinXCAFDrivers.hxx>
#include <PCDM_ReadWriter.hxx>
#include <PCDM_Reader.hxx>
#include <PCDM_StorageDriver.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <Storage_Data.hxx>
#include <TCollection_AsciiString.hxx>
#include <TDocStd_Document.hxx>
#include <XCAFApp_Application.hxx>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <sstream>
#include <vector>

#include "model.h"
#include "model_readers.h"

namespace rdmesh {
namespace {

constexpr const char* kMagic = "RDMESH-PARSED-MODEL 1";
constexpr const char* kXcafFormat = "BinXCAF";

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

const char* FormatKey(ModelFormat format) {
  switch (format) {
    case ModelFormat::kStep:
      return "step";
    case ModelFormat::kIges:
      return "iges";
    case ModelFormat::kBrep:
      return "brep";
    case ModelFormat::kAuto:
      break;
  }
  return "unknown";
}

ModelFormat FormatOfKey(const std::string& key) {
  if (key == "step") return ModelFormat::kStep;
  if (key == "iges") return ModelFormat::kIges;
  if (key == "brep") return ModelFormat::kBrep;
  return ModelFormat::kAuto;
}

/// The XCAF application with the binary formats defined (once per process). OCCT's application
/// is a process-wide singleton; its drivers are shared, so their use is serialised.
Handle(TDocStd_Application) BinaryApplication() {
  static std::once_flag once;
  Handle(TDocStd_Application) app = XCAFApp_Application::GetApplication();
  std::call_once(once, [&] { BinXCAFDrivers::DefineFormat(app); });
  return app;
}

std::mutex& DriverMutex() {
  static std::mutex mutex;
  return mutex;
}

Result<std::string> WritePayload(const Model& model, std::string* kind) {
  std::ostringstream out(std::ios::binary);
  if (model.doc.IsNull()) {
    *kind = "bintools";
    BinTools::Write(model.shape, out);
  } else {
    *kind = "binxcaf";
    Handle(TDocStd_Application) app = BinaryApplication();
    std::lock_guard<std::mutex> lock(DriverMutex());
    Handle(PCDM_StorageDriver) writer = app->WriterFromFormat(kXcafFormat);
    if (writer.IsNull()) return Status(StatusCode::kInternal, "OCCT has no BinXCAF writer");
    // The writer wants a document opened by an application; ours are not registered in OCCT's
    // session (see NewXcafDocument), so open this one, which registers nothing.
    if (!model.doc->IsOpened()) model.doc->Open(app);
    // The file names the document's storage format, which picks the reader; readers made by our
    // STEP and IGES loads say "MDTV-XCAF". Name BinXCAF for the write only.
    const TCollection_ExtendedString previous = model.doc->StorageFormat();
    model.doc->ChangeStorageFormat(kXcafFormat);
    writer->Write(model.doc, out);
    model.doc->ChangeStorageFormat(previous);
    if (writer->GetStoreStatus() != PCDM_SS_OK) {
      return Status(StatusCode::kIoError, "OCCT could not write the XCAF document (status " +
                                              std::to_string(writer->GetStoreStatus()) + ")");
    }
  }
  if (!out) return Status(StatusCode::kIoError, "could not serialise the model");
  return out.str();
}

Result<ReadShape> ReadPayload(const std::string& payload, const std::string& kind) {
  ReadShape read;
  std::istringstream in(payload, std::ios::binary);
  if (kind == "bintools") {
    BinTools::Read(read.shape, in);
    if (read.shape.IsNull()) return Status(StatusCode::kParseError, "no shape in the entry");
    return read;
  }
  if (kind != "binxcaf") return Status(StatusCode::kParseError, "unknown payload " + kind);
  Handle(TDocStd_Application) app = BinaryApplication();
  std::lock_guard<std::mutex> lock(DriverMutex());
  Handle(Storage_Data) data;
  const TCollection_ExtendedString format = PCDM_ReadWriter::FileFormat(in, data);
  if (!(format == TCollection_ExtendedString(kXcafFormat))) {
    return Status(StatusCode::kParseError,
                  "the entry holds a '" + std::string(TCollection_AsciiString(format).ToCString()) +
                      "' document, not " + kXcafFormat);
  }
  Handle(PCDM_Reader) reader = app->ReaderFromFormat(format);
  if (reader.IsNull()) return Status(StatusCode::kParseError, "no OCCT reader for the entry");
  // Read into a document of our own, not through the application's Open(): that would register
  // the document in OCCT's session for good.
  Handle(TDocStd_Document) doc = new TDocStd_Document(kXcafFormat);
  reader->Read(in, data, doc, app);
  if (reader->GetStatus() != PCDM_RS_OK) {
    return Status(StatusCode::kParseError,
                  "OCCT could not read the XCAF document (status " +
                      std::to_string(static_cast<int>(reader->GetStatus())) + ")");
  }
  read.doc = doc;
  read.shape = FreeShapesCompound(doc);
  return read;
}

/// Writes `bytes` to `path` atomically: a temporary file in the same directory, fsync, rename.
Status WriteAtomically(const std::string& path, const std::string& bytes) {
  const std::string partial = path + ".tmp." + std::to_string(getpid()) + "." +
                              std::to_string(reinterpret_cast<uintptr_t>(&bytes));
  const int fd = open(partial.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  bool ok = fd >= 0;
  std::size_t written = 0;
  while (ok && written < bytes.size()) {
    const ssize_t n = write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) written += static_cast<std::size_t>(n);
  }
  const int error = errno;
  if (fd >= 0) {
    ok = ok && fsync(fd) == 0;
    ok = close(fd) == 0 && ok;
  }
  if (ok) ok = std::rename(partial.c_str(), path.c_str()) == 0;
  if (!ok) {
    unlink(partial.c_str());
    return Status(StatusCode::kIoError,
                  "cannot write the parsed model " + path + ": " + std::strerror(error));
  }
  return Status::Ok();
}

}  // namespace

ModelStore::ModelStore(std::string dir, uint64_t limit_bytes)
    : dir_(std::move(dir)), limit_bytes_(limit_bytes) {
  std::error_code ignored;
  std::filesystem::create_directories(dir_, ignored);
}

std::string ModelStore::PathOf(const std::string& key) const { return dir_ + "/" + key + ".rdm"; }

std::shared_ptr<const Model> ModelStore::Load(const std::string& key, std::string* problem,
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
  std::string name, format, unit, kind;
  double scale = 1.0;
  uint64_t size = 0, checksum = 0;
  while (std::getline(header, line) && !line.empty()) {
    const std::size_t eq = line.find('=');
    if (eq == std::string::npos) return discard("a damaged header");
    const std::string field = line.substr(0, eq);
    const std::string value = line.substr(eq + 1);
    if (field == "name") name = value;
    if (field == "format") format = value;
    if (field == "length_unit") unit = value;
    if (field == "unit_scale_mm") scale = std::strtod(value.c_str(), nullptr);
    if (field == "payload") kind = value;
    if (field == "payload_bytes") size = std::strtoull(value.c_str(), nullptr, 10);
    if (field == "payload_fnv1a64") checksum = std::strtoull(value.c_str(), nullptr, 16);
  }
  if (!header) return discard("a truncated header");
  const std::size_t start = static_cast<std::size_t>(header.tellg());
  if (bytes.size() - start != size) return discard("truncated (payload size differs)");
  const std::string payload = bytes.substr(start);
  if (Checksum(payload) != checksum) return discard("corrupt (checksum differs)");

  Result<ReadShape> read = Status(StatusCode::kInternal, "");
  try {
    OCC_CATCH_SIGNALS
    read = ReadPayload(payload, kind);
  } catch (const Standard_Failure& failure) {
    return discard(std::string("OCCT failed reading it (") + failure.DynamicType()->Name() + ")");
  }
  if (!read.ok()) return discard(read.status().message());
  read->length_unit = unit;
  read->unit_scale_mm = scale;
  Result<std::shared_ptr<const Model>> model =
      BuildModel(std::move(*read), FormatOfKey(format), name, name);
  if (!model.ok()) return discard(model.status().message());
  if (context != nullptr && context->ShouldStop()) return nullptr;
  utimensat(AT_FDCWD, path.c_str(), nullptr, 0);  // most recently used now
  return *model;
}

Status ModelStore::Save(const std::string& key, const Model& model) const {
  std::string kind;
  Result<std::string> payload = Status(StatusCode::kInternal, "");
  try {
    OCC_CATCH_SIGNALS
    payload = WritePayload(model, &kind);
  } catch (const Standard_Failure& failure) {
    return Status(StatusCode::kInternal, std::string("OCCT failed writing the model (") +
                                             failure.DynamicType()->Name() + ": " +
                                             failure.GetMessageString() + ")");
  }
  if (!payload.ok()) return payload.status();
  std::ostringstream entry;
  char scale[64];
  std::snprintf(scale, sizeof(scale), "%.17g", model.info.unit_scale_mm);
  char checksum[32];
  std::snprintf(checksum, sizeof(checksum), "%016llx",
                static_cast<unsigned long long>(Checksum(*payload)));
  std::string name = model.info.name;
  std::replace(name.begin(), name.end(), '\n', ' ');
  entry << kMagic << "\nname=" << name << "\nformat=" << model.info.format
        << "\nlength_unit=" << model.info.length_unit << "\nunit_scale_mm=" << scale
        << "\npayload=" << kind << "\npayload_bytes=" << payload->size()
        << "\npayload_fnv1a64=" << checksum << "\n\n";
  Status written = WriteAtomically(PathOf(key), entry.str() + *payload);
  if (!written.ok()) return written;
  Evict(key);
  return Status::Ok();
}

void ModelStore::Evict(const std::string& keep) const {
  if (limit_bytes_ == 0) return;
  struct Entry {
    std::filesystem::path path;
    uint64_t bytes;
    std::filesystem::file_time_type used;
  };
  std::vector<Entry> entries;
  uint64_t total = 0;
  std::error_code error;
  for (const auto& item : std::filesystem::directory_iterator(dir_, error)) {
    if (item.path().extension() != ".rdm") continue;
    std::error_code stat_error;
    const uint64_t bytes = item.file_size(stat_error);
    const auto used = item.last_write_time(stat_error);
    if (stat_error) continue;
    entries.push_back({item.path(), bytes, used});
    total += bytes;
  }
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
