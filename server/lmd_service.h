// The gRPC service: one handler per RPC, each translating the wire message,
// calling the store (and, later, the method in core), and translating back.
#pragma once

#include <chrono>
#include <string>

#include "lmd/v1/lmd.grpc.pb.h"
#include "server/config.h"
#include "server/map_store.h"

namespace lmd::server {

class LmdServiceImpl final : public v1::LmdService::Service {
 public:
  // `store` must outlive the service.
  LmdServiceImpl(const ServerConfig& config, MapStore* store);

  grpc::Status InsertMaps(grpc::ServerContext* context, const v1::InsertMapsRequest* request,
                          v1::InsertMapsResponse* response) override;
  grpc::Status StreamInsertMaps(grpc::ServerContext* context, grpc::ServerReader<v1::InsertMapRequest>* reader,
                                v1::InsertMapsResponse* response) override;
  grpc::Status GetMap(grpc::ServerContext* context, const v1::GetMapRequest* request,
                      v1::GetMapResponse* response) override;
  grpc::Status DeleteMap(grpc::ServerContext* context, const v1::DeleteMapRequest* request,
                         v1::DeleteMapResponse* response) override;
  grpc::Status ListMaps(grpc::ServerContext* context, const v1::ListMapsRequest* request,
                        v1::ListMapsResponse* response) override;
  grpc::Status ListCollections(grpc::ServerContext* context, const v1::ListCollectionsRequest* request,
                               v1::ListCollectionsResponse* response) override;
  grpc::Status Stats(grpc::ServerContext* context, const v1::StatsRequest* request,
                     v1::StatsResponse* response) override;
  // Retrieve, DetectChanges and Backup answer UNIMPLEMENTED (the base class)
  // until the index lands.

 private:
  const ServerConfig config_;
  MapStore* const store_;
  const std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
};

}  // namespace lmd::server
