// Forwarding: a call on a collection this node does not serve goes, as the
// client sent it (its token and request id), to the node that does. A
// forwarded call carries "lmd-forwarded: 1", and a node never forwards such a
// call again: when the nodes' views of a placement disagree for a moment,
// the client gets UNAVAILABLE and retries, instead of a loop.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include <grpcpp/client_context.h>
#include <grpcpp/channel.h>
#include <grpcpp/support/server_callback.h>

#include "lmd/v1/lmd.grpc.pb.h"
#include "server/grpc_status.h"

namespace lmd::server::cluster {

// Whether a call came from another node (then it is never forwarded again).
inline bool WasForwarded(const grpc::CallbackServerContext* context) {
  return context->client_metadata().count("lmd-forwarded") != 0;
}

// A read that asks for this node's own copy ("lmd-local" metadata: checks
// and operators), whatever the placement says.
inline bool WantsLocal(const grpc::CallbackServerContext* context) {
  return context->client_metadata().count("lmd-local") != 0;
}

// Calls `method` over `channel` (ClusterNode::ChannelTo) with `request` and
// the client's metadata; its status as the client should see it.
template <typename Request, typename Response>
Status Forward(const std::shared_ptr<grpc::Channel>& channel, const grpc::CallbackServerContext* from,
               grpc::Status (v1::LmdService::Stub::*method)(grpc::ClientContext*, const Request&, Response*),
               const Request& request, Response* response) {
  if (WasForwarded(from)) {
    return Status::Unavailable("this node does not serve the collection now (its placement is changing); retry");
  }
  grpc::ClientContext context;
  for (const char* key : {"authorization", "x-request-id"}) {
    const auto it = from->client_metadata().find(key);
    if (it != from->client_metadata().end()) context.AddMetadata(key, std::string(it->second.data(), it->second.size()));
  }
  context.AddMetadata("lmd-forwarded", "1");
  const auto deadline = from->deadline();
  const auto fallback = std::chrono::system_clock::now() + std::chrono::seconds(30);
  context.set_deadline(deadline < fallback ? deadline : fallback);
  v1::LmdService::Stub stub(channel);
  return FromGrpcStatus((stub.*method)(&context, request, response));
}

}  // namespace lmd::server::cluster
