#include "model/model_payload.h"

#include <BinTools.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <sstream>

#include "model/xcaf_api.h"

namespace rdmesh {
namespace {

std::string FailureText(const Standard_Failure& failure) {
  const char* what = failure.GetMessageString();
  return std::string(failure.DynamicType()->Name()) +
         (what != nullptr && what[0] != '\0' ? std::string(": ") + what : std::string());
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
    if (PayloadKindOf(read) == PayloadKind::kBinXcaf) {
      Result<const XcafApi*> xcaf = Xcaf();
      if (!xcaf.ok()) return xcaf.status();
      return (*xcaf)->write_document(read.doc);
    }
    BinTools::Write(read.shape, out);
  } catch (const Standard_Failure& failure) {
    return Status(StatusCode::kInternal,
                  "OCCT failed writing the model (" + FailureText(failure) + ")");
  }
  if (!out) return Status(StatusCode::kIoError, "could not serialise the model");
  return out.str();
}

Result<ReadShape> ReadPayload(const std::string& payload, PayloadKind kind) {
  ReadShape read;
  try {
    OCC_CATCH_SIGNALS
    if (kind == PayloadKind::kBinXcaf) {
      Result<const XcafApi*> xcaf = Xcaf();
      if (!xcaf.ok()) return xcaf.status();
      return (*xcaf)->read_document(payload);
    }
    std::istringstream in(payload, std::ios::binary);
    BinTools::Read(read.shape, in);
    if (read.shape.IsNull()) return Status(StatusCode::kParseError, "no shape in the payload");
  } catch (const Standard_Failure& failure) {
    return Status(StatusCode::kParseError,
                  "OCCT failed reading the payload (" + FailureText(failure) + ")");
  }
  return read;
}

}  // namespace rdmesh
