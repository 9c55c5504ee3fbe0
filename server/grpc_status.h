// The one place where lmd's Status becomes a gRPC status.
#pragma once

#include <grpcpp/support/status.h>

#include "core/status.h"

namespace lmd::server {

// InvalidArgument -> INVALID_ARGUMENT, NotFound -> NOT_FOUND, AlreadyExists ->
// ALREADY_EXISTS, ResourceExhausted -> RESOURCE_EXHAUSTED, Unauthenticated,
// PermissionDenied, Cancelled, DeadlineExceeded -> the same, Corruption /
// IoError / Internal -> INTERNAL (the message is kept), Ok -> OK.
// Unavailable -> UNAVAILABLE.
grpc::Status ToGrpcStatus(const Status& status);

// The reverse, for a call lmdd forwarded to another node: its answer goes
// back to the client as it came. Codes without an lmd equivalent become
// Internal naming the code, so that a peer's UNIMPLEMENTED with no message
// (a node without the method) reaches the client as what it is, not as an
// empty error.
Status FromGrpcStatus(const grpc::Status& status);

}  // namespace lmd::server
