#include "model/model_payload.h"

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
#include <mutex>
#include <sstream>

namespace rdmesh {
namespace {

constexpr const char* kXcafFormat = "BinXCAF";

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

std::string FailureText(const Standard_Failure& failure) {
  const char* what = failure.GetMessageString();
  return std::string(failure.DynamicType()->Name()) +
         (what != nullptr && what[0] != '\0' ? std::string(": ") + what : std::string());
}

Status WriteDocument(const Handle(TDocStd_Document) & doc, std::ostream& out) {
  Handle(TDocStd_Application) app = BinaryApplication();
  std::lock_guard<std::mutex> lock(DriverMutex());
  Handle(PCDM_StorageDriver) writer = app->WriterFromFormat(kXcafFormat);
  if (writer.IsNull()) return Status(StatusCode::kInternal, "OCCT has no BinXCAF writer");
  // The writer wants a document opened by an application; ours are not registered in OCCT's
  // session (see NewXcafDocument), so open this one, which registers nothing.
  if (!doc->IsOpened()) doc->Open(app);
  // The file names the document's storage format, which picks the reader; readers made by our
  // STEP and IGES loads say "MDTV-XCAF". Name BinXCAF for the write only.
  const TCollection_ExtendedString previous = doc->StorageFormat();
  doc->ChangeStorageFormat(kXcafFormat);
  writer->Write(doc, out);
  doc->ChangeStorageFormat(previous);
  if (writer->GetStoreStatus() != PCDM_SS_OK) {
    return Status(StatusCode::kIoError, "OCCT could not write the XCAF document (status " +
                                            std::to_string(writer->GetStoreStatus()) + ")");
  }
  return Status::Ok();
}

Result<Handle(TDocStd_Document)> ReadDocument(std::istream& in) {
  Handle(TDocStd_Application) app = BinaryApplication();
  std::lock_guard<std::mutex> lock(DriverMutex());
  Handle(Storage_Data) data;
  const TCollection_ExtendedString format = PCDM_ReadWriter::FileFormat(in, data);
  if (!(format == TCollection_ExtendedString(kXcafFormat))) {
    return Status(StatusCode::kParseError,
                  "the payload holds a '" +
                      std::string(TCollection_AsciiString(format).ToCString()) +
                      "' document, not " + kXcafFormat);
  }
  Handle(PCDM_Reader) reader = app->ReaderFromFormat(format);
  if (reader.IsNull()) return Status(StatusCode::kParseError, "no OCCT reader for the payload");
  // Read into a document of our own, not through the application's Open(): that would register
  // the document in OCCT's session for good.
  Handle(TDocStd_Document) doc = new TDocStd_Document(kXcafFormat);
  reader->Read(in, data, doc, app);
  if (reader->GetStatus() != PCDM_RS_OK) {
    return Status(StatusCode::kParseError,
                  "OCCT could not read the XCAF document (status " +
                      std::to_string(static_cast<int>(reader->GetStatus())) + ")");
  }
  return doc;
}

}  // namespace

const char* PayloadKindName(PayloadKind kind) {
  return kind == PayloadKind::kBinXcaf ? "binxcaf" : "bintools";
}

bool PayloadKindFromName(const std::string& name, PayloadKind* kind) {
  for (PayloadKind candidate : {PayloadKind::kBinXcaf, PayloadKind::kBinTools}) {
    if (name == PayloadKindName(candidate)) {
      *kind = candidate;
      return true;
    }
  }
  return false;
}

PayloadKind PayloadKindOf(const ReadShape& read) {
  return read.doc.IsNull() ? PayloadKind::kBinTools : PayloadKind::kBinXcaf;
}

Result<std::string> WritePayload(const ReadShape& read) {
  std::ostringstream out(std::ios::binary);
  try {
    OCC_CATCH_SIGNALS
    if (PayloadKindOf(read) == PayloadKind::kBinTools) {
      BinTools::Write(read.shape, out);
    } else if (Status written = WriteDocument(read.doc, out); !written.ok()) {
      return written;
    }
  } catch (const Standard_Failure& failure) {
    return Status(StatusCode::kInternal,
                  "OCCT failed writing the model (" + FailureText(failure) + ")");
  }
  if (!out) return Status(StatusCode::kIoError, "could not serialise the model");
  return out.str();
}

Result<ReadShape> ReadPayload(const std::string& payload, PayloadKind kind) {
  ReadShape read;
  std::istringstream in(payload, std::ios::binary);
  try {
    OCC_CATCH_SIGNALS
    if (kind == PayloadKind::kBinTools) {
      BinTools::Read(read.shape, in);
      if (read.shape.IsNull()) return Status(StatusCode::kParseError, "no shape in the payload");
      return read;
    }
    Result<Handle(TDocStd_Document)> doc = ReadDocument(in);
    if (!doc.ok()) return doc.status();
    read.doc = *doc;
    read.shape = FreeShapesCompound(read.doc);
  } catch (const Standard_Failure& failure) {
    return Status(StatusCode::kParseError,
                  "OCCT failed reading the payload (" + FailureText(failure) + ")");
  }
  return read;
}

}  // namespace rdmesh
