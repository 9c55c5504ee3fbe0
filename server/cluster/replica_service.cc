#include "server/cluster/replica_service.h"

#include "server/grpc_status.h"

namespace lmd::server::cluster {

Status ReplicaService::Allowed(const grpc::ServerContext* context, const std::string& collection) const {
  if (!auth_->enabled()) return Status::Ok();
  const auto& metadata = context->client_metadata();
  const auto it = metadata.find("authorization");
  const std::string token = it == metadata.end() ? std::string() : std::string(it->second.data(), it->second.size());
  return auth_->Check(token, collection, Access::kWrite);
}

grpc::Status ReplicaService::Apply(grpc::ServerContext* context, const internal::ApplyRequest* request,
                                   internal::ApplyResponse* response) {
  Status allowed = Allowed(context, request->collection());
  return ToGrpcStatus(allowed.ok() ? node_->Apply(*request, response) : allowed);
}

grpc::Status ReplicaService::State(grpc::ServerContext* context, const internal::ReplicaStateRequest* request,
                                   internal::ReplicaStateResponse* response) {
  Status allowed = Allowed(context, request->collection());
  if (!allowed.ok()) return ToGrpcStatus(allowed);
  *response = node_->State(request->collection());
  return grpc::Status::OK;
}

grpc::Status ReplicaService::Copy(grpc::ServerContext* context, const internal::CopyRequest* request,
                                  grpc::ServerWriter<internal::CopyChunk>* writer) {
  Status allowed = Allowed(context, request->collection());
  if (!allowed.ok()) return ToGrpcStatus(allowed);
  return ToGrpcStatus(node_->Copy(*request, [&](const internal::CopyChunk& chunk) {
    return !context->IsCancelled() && writer->Write(chunk);
  }));
}

grpc::Status ReplicaService::Join(grpc::ServerContext* context, const internal::JoinRequest* request,
                                  internal::JoinResponse*) {
  Status allowed = Allowed(context, request->collection());
  return ToGrpcStatus(allowed.ok() ? node_->Join(*request) : allowed);
}

}  // namespace lmd::server::cluster
