#include "wire/status_map.h"

#include <gtest/gtest.h>

#include <utility>
#include <vector>

namespace rdmesh::server {
namespace {

TEST(StatusMapTest, EveryEngineCodeHasItsGrpcCode) {
  const std::vector<std::pair<StatusCode, grpc::StatusCode>> expected = {
      {StatusCode::kOk, grpc::StatusCode::OK},
      {StatusCode::kInvalidArgument, grpc::StatusCode::INVALID_ARGUMENT},
      {StatusCode::kNotFound, grpc::StatusCode::NOT_FOUND},
      {StatusCode::kParseError, grpc::StatusCode::INVALID_ARGUMENT},
      {StatusCode::kEmptyModel, grpc::StatusCode::INVALID_ARGUMENT},
      {StatusCode::kIoError, grpc::StatusCode::INTERNAL},
      {StatusCode::kCancelled, grpc::StatusCode::CANCELLED},
      {StatusCode::kDeadlineExceeded, grpc::StatusCode::DEADLINE_EXCEEDED},
      {StatusCode::kResourceExhausted, grpc::StatusCode::RESOURCE_EXHAUSTED},
      {StatusCode::kPermissionDenied, grpc::StatusCode::PERMISSION_DENIED},
      {StatusCode::kFaceFailed, grpc::StatusCode::FAILED_PRECONDITION},
      {StatusCode::kInternal, grpc::StatusCode::INTERNAL},
  };
  for (const auto& [engine, grpc_code] : expected) {
    EXPECT_EQ(ToGrpcCode(engine), grpc_code) << StatusCodeName(engine);
  }
}

TEST(StatusMapTest, CodesThatMeanTheSameRoundTrip) {
  for (StatusCode code :
       {StatusCode::kOk, StatusCode::kInvalidArgument, StatusCode::kNotFound,
        StatusCode::kCancelled, StatusCode::kDeadlineExceeded, StatusCode::kResourceExhausted,
        StatusCode::kPermissionDenied, StatusCode::kFaceFailed, StatusCode::kInternal}) {
    EXPECT_EQ(FromGrpcCode(ToGrpcCode(code)), code) << StatusCodeName(code);
  }
  EXPECT_EQ(FromGrpcCode(grpc::StatusCode::UNAUTHENTICATED), StatusCode::kPermissionDenied);
  EXPECT_EQ(FromGrpcCode(grpc::StatusCode::UNAVAILABLE), StatusCode::kIoError);
  EXPECT_EQ(FromGrpcCode(grpc::StatusCode::DATA_LOSS), StatusCode::kInternal);
}

TEST(StatusMapTest, KeepsTheMessage) {
  const grpc::Status status =
      ToGrpcStatus(Status(StatusCode::kParseError, "bracket.step: truncated at line 12"));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(), "bracket.step: truncated at line 12");

  const grpc::Status unnamed = ToGrpcStatus(Status(StatusCode::kNotFound, ""));
  EXPECT_EQ(unnamed.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_FALSE(unnamed.error_message().empty());

  EXPECT_TRUE(ToGrpcStatus(Status::Ok()).ok());

  const Status back = FromGrpcStatus(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, "full"));
  EXPECT_EQ(back.code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(back.message(), "full");
  EXPECT_TRUE(FromGrpcStatus(grpc::Status::OK).ok());
}

TEST(StatusMapTest, ServiceOnlyAnswers) {
  EXPECT_EQ(Unauthenticated("no token").error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(Unavailable("shutting down").error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(Unavailable("shutting down").error_message(), "shutting down");
}

}  // namespace
}  // namespace rdmesh::server
