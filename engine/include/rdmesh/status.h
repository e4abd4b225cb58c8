#pragma once

#include <optional>
#include <string>
#include <utility>

namespace rdmesh {

/// Error categories of the engine. The server maps each to one gRPC code
/// (server/wire/status_map.cpp).
enum class StatusCode {
  kOk = 0,
  kInvalidArgument,    ///< bad option values or an unusable request
  kNotFound,           ///< a file or id that does not exist
  kParseError,         ///< a model file that cannot be read (corrupt, truncated, wrong format)
  kEmptyModel,         ///< a model that holds no faces
  kIoError,            ///< a file that cannot be opened or written
  kCancelled,          ///< the caller cancelled the run
  kDeadlineExceeded,   ///< the run's time limit passed
  kResourceExhausted,  ///< a size limit (model bytes, triangles) was hit
  kPermissionDenied,   ///< a path outside the allowed root
  kFaceFailed,         ///< some faces failed to mesh (strict mode)
  kInternal,           ///< a bug or an unexpected exception
};

/// Stable lower-case name of a code, e.g. "invalid_argument".
const char* StatusCodeName(StatusCode code);

/// The result of an operation that can fail: a code and a human-readable message.
/// Exceptions never cross the engine's public API; a Status does.
class Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status Ok() { return Status(); }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  /// "code_name: message", or "ok".
  std::string ToString() const;

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

/// A kInvalidArgument Status: the answer of every option and request check.
inline Status InvalidArgument(std::string message) {
  return Status(StatusCode::kInvalidArgument, std::move(message));
}

/// A value or the Status that explains why there is none.
template <typename T>
class Result {
 public:
  Result(T value) : value_(std::move(value)) {}          // NOLINT(runtime/explicit)
  Result(Status status) : status_(std::move(status)) {}  // NOLINT(runtime/explicit)

  bool ok() const { return status_.ok() && value_.has_value(); }
  const Status& status() const { return status_; }
  T& value() { return *value_; }
  const T& value() const { return *value_; }
  T& operator*() { return *value_; }
  const T& operator*() const { return *value_; }
  T* operator->() { return &*value_; }
  const T* operator->() const { return &*value_; }

 private:
  Status status_;
  std::optional<T> value_;
};

}  // namespace rdmesh
