// Requests whose bytes do not parse as their method's message. gRPC 1.51's
// callback API answers those itself, before lmdd sees the call, with
// UNIMPLEMENTED and no message, as if the method did not exist. This server
// interceptor turns that answer, on a method the server knows, into
// INVALID_ARGUMENT naming the message the bytes should have been. lmdd's
// own handlers never answer UNIMPLEMENTED, so nothing else is rewritten.
// Such a call never reaches a handler, so the interceptor reports it as
// finished itself (a log line and the method's metrics, as any call).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include <grpcpp/support/server_interceptor.h>

namespace lmd::server {

// Called once per rewritten call: the method's name ("Retrieve"), the status
// sent and the call's time, ms.
using ParseErrorReport = std::function<void(const std::string& method, const grpc::Status& status, double ms)>;

// For ServerBuilder::experimental().SetInterceptorCreators.
std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> ParseErrorInterceptors(ParseErrorReport report);

}  // namespace lmd::server
