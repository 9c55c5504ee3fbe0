// LmdClient: the C++ API a robot's software calls to reach lmdd.
//
//   lmd::client::LmdClient client({"127.0.0.1:50051"});
//   lmd::v1::InsertMapsResponse inserted;
//   grpc::Status status = client.InsertMaps(request, &inserted);
//
// Every call is synchronous, carries the options' deadline, and returns the
// server's gRPC status (OK, INVALID_ARGUMENT with a message saying what is
// wrong, NOT_FOUND, RESOURCE_EXHAUSTED, UNAVAILABLE when lmdd cannot be
// reached, DEADLINE_EXCEEDED, UNIMPLEMENTED for calls this lmdd lacks).
// Thread-safe: one client may be shared by many threads.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "lmd/v1/lmd.grpc.pb.h"

namespace lmd::client {

struct ClientOptions {
  // lmdd's address, HOST:PORT (any gRPC target string).
  std::string target = "127.0.0.1:50051";
  // Deadline of each call.
  std::chrono::milliseconds deadline = std::chrono::seconds(30);
  // Largest message sent or received, bytes. Match lmdd's max_message_bytes.
  int max_message_bytes = 64 << 20;
};

class LmdClient {
 public:
  explicit LmdClient(const ClientOptions& options);

  grpc::Status InsertMaps(const v1::InsertMapsRequest& request, v1::InsertMapsResponse* response) const;
  // Sends each request as one message of a client stream (lmdd writes and
  // acknowledges them in order); the response lists the stored maps.
  grpc::Status StreamInsertMaps(const std::vector<v1::InsertMapRequest>& requests,
                                v1::InsertMapsResponse* response) const;
  grpc::Status GetMap(const v1::GetMapRequest& request, v1::GetMapResponse* response) const;
  grpc::Status DeleteMap(const v1::DeleteMapRequest& request) const;
  grpc::Status ListMaps(const v1::ListMapsRequest& request, v1::ListMapsResponse* response) const;
  grpc::Status Retrieve(const v1::RetrieveRequest& request, v1::RetrieveResponse* response) const;
  grpc::Status DetectChanges(const v1::DetectChangesRequest& request, v1::DetectChangesResponse* response) const;
  grpc::Status ListCollections(v1::ListCollectionsResponse* response) const;
  grpc::Status Stats(const v1::StatsRequest& request, v1::StatsResponse* response) const;

 private:
  // A context carrying the deadline.
  std::unique_ptr<grpc::ClientContext> NewContext() const;

  ClientOptions options_;
  std::unique_ptr<v1::LmdService::Stub> stub_;
};

}  // namespace lmd::client
