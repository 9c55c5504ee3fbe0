// The Replica service (lmd.internal.Replica, proto/lmd/internal/cluster.proto):
// what one lmdd node calls on another to copy writes and catch up. A thin
// layer over ClusterNode. With tokens on, every call needs a token that may
// write the collection (nodes send cluster_token).
#pragma once

#include "lmd/internal/cluster.grpc.pb.h"
#include "server/auth.h"
#include "server/cluster/cluster_node.h"

namespace lmd::server::cluster {

class ReplicaService final : public internal::Replica::Service {
 public:
  // Both must outlive the service.
  ReplicaService(ClusterNode* node, const TokenAuthorizer* auth) : node_(node), auth_(auth) {}

  grpc::Status Apply(grpc::ServerContext* context, const internal::ApplyRequest* request,
                     internal::ApplyResponse* response) override;
  grpc::Status State(grpc::ServerContext* context, const internal::ReplicaStateRequest* request,
                     internal::ReplicaStateResponse* response) override;
  grpc::Status Copy(grpc::ServerContext* context, const internal::CopyRequest* request,
                    grpc::ServerWriter<internal::CopyChunk>* writer) override;
  grpc::Status Join(grpc::ServerContext* context, const internal::JoinRequest* request,
                    internal::JoinResponse* response) override;

 private:
  Status Allowed(const grpc::ServerContext* context, const std::string& collection) const;

  ClusterNode* const node_;
  const TokenAuthorizer* const auth_;
};

}  // namespace lmd::server::cluster
