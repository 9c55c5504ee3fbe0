// Requests whose bytes do not parse as their method's message. gRPC 1.51's
// callback API answers those itself, before lmdd sees the call, with
// UNIMPLEMENTED and no message, as if the method did not exist. This server
// interceptor turns that answer, on a method the server knows, into
// INVALID_ARGUMENT naming the message the bytes should have been. lmdd's
// own handlers never answer UNIMPLEMENTED, so nothing else is rewritten.
#pragma once

#include <memory>

#include <grpcpp/support/server_interceptor.h>

namespace lmd::server {

// For ServerBuilder::experimental().SetInterceptorCreators.
std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> ParseErrorInterceptors();

}  // namespace lmd::server
