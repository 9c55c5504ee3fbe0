#include "server/grpc_status.h"

#include <gtest/gtest.h>

namespace lmd::server {
namespace {

TEST(GrpcStatusTest, EveryLmdCodeComesBackFromItsGrpcStatus) {
  for (const Status& status :
       {Status::InvalidArgument("bad"), Status::NotFound("gone"), Status::AlreadyExists("twice"),
        Status::ResourceExhausted("full"), Status::Unauthenticated("who"), Status::PermissionDenied("no"),
        Status::Cancelled("stop"), Status::DeadlineExceeded("late"), Status::FailedPrecondition("first"),
        Status::Unavailable("away")}) {
    const Status back = FromGrpcStatus(ToGrpcStatus(status));
    EXPECT_EQ(back.code(), status.code()) << status.ToString();
    EXPECT_EQ(back.message(), status.message()) << status.ToString();
  }
  EXPECT_TRUE(FromGrpcStatus(ToGrpcStatus(Status::Ok())).ok());
}

TEST(GrpcStatusTest, APeersUnimplementedWithNoMessageNamesItsCode) {
  const Status status = FromGrpcStatus(grpc::Status(grpc::StatusCode::UNIMPLEMENTED, ""));
  EXPECT_EQ(status.code(), Status::Code::kInternal);
  EXPECT_EQ(status.message(), "the node called answered gRPC code 12 with no message");
  const grpc::Status sent = ToGrpcStatus(status);
  EXPECT_EQ(sent.error_code(), grpc::StatusCode::INTERNAL);
  EXPECT_NE(sent.error_message().find("gRPC code 12"), std::string::npos);
}

TEST(GrpcStatusTest, AnUnmappedCodeKeepsItsMessage) {
  const Status status = FromGrpcStatus(grpc::Status(grpc::StatusCode::ABORTED, "conflict"));
  EXPECT_EQ(status.code(), Status::Code::kInternal);
  EXPECT_EQ(status.message(), "the node called answered gRPC code 10: conflict");
}

}  // namespace
}  // namespace lmd::server
