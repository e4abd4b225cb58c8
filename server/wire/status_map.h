#pragma once
// The one place where engine status codes and gRPC status codes meet.

#include <grpcpp/support/status.h>

#include <string>

#include "rdmesh/status.h"

namespace rdmesh::server {

/// The gRPC code that answers an engine error. Model errors the caller can fix (a corrupt,
/// truncated or empty file, bad options) are INVALID_ARGUMENT; size limits are
/// RESOURCE_EXHAUSTED.
grpc::StatusCode ToGrpcCode(StatusCode code);

/// The engine code a gRPC code stands for (clients use it to report a remote error the way a
/// local run would). Codes with no engine meaning become kInternal.
StatusCode FromGrpcCode(grpc::StatusCode code);

/// A gRPC status with the engine's message (or the code's name when the message is empty).
grpc::Status ToGrpcStatus(const Status& status);

/// An engine status from a gRPC one (message kept).
Status FromGrpcStatus(const grpc::Status& status);

/// The two answers of the service that no engine error stands for: a missing or wrong bearer
/// token (UNAUTHENTICATED) and a server that is shutting down (UNAVAILABLE).
grpc::Status Unauthenticated(const std::string& message);
grpc::Status Unavailable(const std::string& message);

}  // namespace rdmesh::server
