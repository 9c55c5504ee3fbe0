#include "server/grpc_status.h"

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
    case Status::Code::kCorruption:
    case Status::Code::kIoError:
    case Status::Code::kInternal: return {grpc::StatusCode::INTERNAL, status.ToString()};
  }
  return {grpc::StatusCode::UNKNOWN, status.ToString()};
}

}  // namespace lmd::server
