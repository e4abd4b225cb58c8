#pragma once
// Whole-file writes that a reader never sees half done: the persistent model store's entries and
// the daemon's spooled uploads.

#include <sys/types.h>

#include <string>

#include "rdmesh/status.h"

namespace rdmesh {

/// Writes `bytes` to `partial` (created with `mode`, truncated if it exists), then renames it to
/// `path`, so that `path` is either its old file or the complete new one. With `durable`, the data
/// is fsync'ed before the rename, so that a crash of the machine cannot leave a renamed file with
/// missing data. On failure `partial` is removed, `path` is untouched, and the status is
/// kIoError with the system's error text (callers say what they were writing).
Status WriteFileAtomically(const std::string& path, const std::string& partial,
                           const std::string& bytes, mode_t mode, bool durable);

}  // namespace rdmesh
