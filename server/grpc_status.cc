#include "server/grpc_status.h"

#include <string>

namespace lmd::server {

grpc::Status ToGrpcStatus(const Status& status) {
  switch (status.code()) {
    case Status::Code::kOk: return grpc::Status::OK;
    case Status::Code::kInvalidArgument: return {grpc::StatusCode::INVALID_ARGUMENT, status.message()};
    case Status::Code::kNotFound: return {grpc::StatusCode::NOT_FOUND, status.message()};
    case Status::Code::kAlreadyExists: return {grpc::StatusCode::ALREADY_EXISTS, status.message()};
    case Status::Code::kResourceExhausted: return {grpc::StatusCode::RESOURCE_EXHAUSTED, status.message()};
    case Status::Code::kUnauthenticated: return {grpc::StatusCode::UNAUTHENTICATED, status.message()};
    case Status::Code::kPermissionDenied: return {grpc::StatusCode::PERMISSION_DENIED, status.message()};
    case Status::Code::kCancelled: return {grpc::StatusCode::CANCELLED, status.message()};
    case Status::Code::kDeadlineExceeded: return {grpc::StatusCode::DEADLINE_EXCEEDED, status.message()};
    case Status::Code::kFailedPrecondition: return {grpc::StatusCode::FAILED_PRECONDITION, status.message()};
    case Status::Code::kUnavailable: return {grpc::StatusCode::UNAVAILABLE, status.message()};
    case Status::Code::kCorruption:
    case Status::Code::kIoError:
    case Status::Code::kInternal: return {grpc::StatusCode::INTERNAL, status.ToString()};
  }
  return {grpc::StatusCode::UNKNOWN, status.ToString()};
}

Status FromGrpcStatus(const grpc::Status& status) {
  const std::string& m = status.error_message();
  switch (status.error_code()) {
    case grpc::StatusCode::OK: return Status::Ok();
    case grpc::StatusCode::INVALID_ARGUMENT: return Status::InvalidArgument(m);
    case grpc::StatusCode::NOT_FOUND: return Status::NotFound(m);
    case grpc::StatusCode::ALREADY_EXISTS: return Status::AlreadyExists(m);
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return Status::ResourceExhausted(m);
    case grpc::StatusCode::UNAUTHENTICATED: return Status::Unauthenticated(m);
    case grpc::StatusCode::PERMISSION_DENIED: return Status::PermissionDenied(m);
    case grpc::StatusCode::CANCELLED: return Status::Cancelled(m);
    case grpc::StatusCode::DEADLINE_EXCEEDED: return Status::DeadlineExceeded(m);
    case grpc::StatusCode::FAILED_PRECONDITION: return Status::FailedPrecondition(m);
    case grpc::StatusCode::UNAVAILABLE: return Status::Unavailable(m);
    default:  // codes lmdd never answers itself (UNIMPLEMENTED: a peer without the method)
      return Status::Internal("the node called answered gRPC code " + std::to_string(status.error_code()) +
                              (m.empty() ? " with no message" : ": " + m));
  }
}

}  // namespace lmd::server
