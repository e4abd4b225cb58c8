#pragma once
// A read model as bytes in OCCT's own binary formats, and back: the persistent store's payload,
// and the canonical form every load goes through (see ParseCanonical in model.h). Internal to
// the engine.

#include <string>

#include "model/read_shape.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// How a payload is encoded: an XCAF document (BinXCAF: names, colours and assembly structure
/// survive), or a bare shape (BinTools) for BREP models, which have no document.
enum class PayloadKind { kBinXcaf, kBinTools };

/// "binxcaf" or "bintools"; PayloadKindFromName is its inverse (false for other names).
const char* PayloadKindName(PayloadKind kind);
bool PayloadKindFromName(const std::string& name, PayloadKind* kind);

/// The kind WritePayload uses for `read`: BinXCAF when it has a document, else BinTools.
PayloadKind PayloadKindOf(const ReadShape& read);

/// `read`'s document (or shape) in its payload kind. Opens the document on OCCT's XCAF
/// application (which registers nothing). kIoError or kInternal when OCCT cannot write it.
/// Thread-safe (OCCT's binary drivers are shared: their use is serialised).
Result<std::string> WritePayload(const ReadShape& read);

/// The document (or shape) in `payload`, with the free shapes' compound as its shape; the length
/// unit is left for the caller to set. kParseError when OCCT cannot read it (OCCT's exceptions
/// are caught). Thread-safe.
Result<ReadShape> ReadPayload(const std::string& payload, PayloadKind kind);

}  // namespace rdmesh
