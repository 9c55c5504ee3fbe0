// LmdClient: the C++ API a robot's software calls to reach lmdd.
//
//   lmd::client::ClientOptions options;
//   options.target = "lmd.example:50051";
//   options.token = "robot-7-secret";          // bearer token, if lmdd checks tokens
//   options.tls_root_ca_file = "/etc/lmd/ca.pem";  // TLS, if lmdd serves it
//   auto client = lmd::client::LmdClient::Create(options);   // Result<...>
//   lmd::v1::InsertMapsResponse inserted;
//   grpc::Status status = (*client)->InsertMaps(request, &inserted);
//
// Every call is synchronous and carries the options' deadline, the bearer
// token, and the "x-lmd-collection" header (so a proxy can route the call to
// the shard that holds the collection). A call that fails with UNAVAILABLE
// (lmdd restarting, a shard moving), or that lmdd refused because its queue
// was full (RESOURCE_EXHAUSTED with the "lmd-busy" trailer), is retried with
// exponential backoff and random jitter (so that a fleet does not retry in
// step) up to max_attempts times within the deadline; other errors return at
// once. Only calls that are safe to repeat are retried: an insert always
// (when lmdd is to assign ids, the client gives the request a random
// request_id unless it has one, and lmdd answers a repeat without storing
// the maps twice; explicit ids make a retry replace the same maps), a backup
// never; a retried delete that finds the map
// gone reports success (an earlier attempt deleted it and its answer was
// lost). The returned status is lmdd's: OK,
// INVALID_ARGUMENT with a message saying what is wrong, NOT_FOUND,
// RESOURCE_EXHAUSTED, UNAUTHENTICATED, PERMISSION_DENIED, UNAVAILABLE,
// DEADLINE_EXCEEDED, UNIMPLEMENTED. Thread-safe: share one client.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "client/cluster_routes.h"
#include "core/status.h"
#include "lmd/v1/lmd.grpc.pb.h"

namespace lmd::client {

struct ClientOptions {
  // lmdd's (or the proxy's) address, HOST:PORT (core/util/host_port.h).
  std::string target = "127.0.0.1:50051";
  // Deadline of each call, retries included.
  std::chrono::milliseconds deadline = std::chrono::seconds(30);
  // Largest message sent or received, bytes. Match lmdd's max_message_bytes.
  int max_message_bytes = 64 << 20;
  // Bearer token sent as "authorization: Bearer TOKEN"; empty: none.
  std::string token;
  // TLS: on when tls_root_ca_file is set (PEM of the CA that signed lmdd's
  // certificate). A client certificate and key (PEM) if lmdd requires one:
  // both or neither, and only with the CA file.
  std::string tls_root_ca_file;
  std::string tls_cert_file;
  std::string tls_key_file;
  // Expected name in lmdd's certificate, if it differs from the target host.
  std::string tls_server_name;
  // Attempts per call when lmdd is UNAVAILABLE or busy (1 = no retry), and
  // the first backoff; each further backoff doubles, up to 2 s, and each wait
  // is drawn between half and 1.5 times its backoff.
  int max_attempts = 4;
  std::chrono::milliseconds initial_backoff = std::chrono::milliseconds(100);
  // In a cluster of lmdd nodes: send each collection's calls straight to the
  // node that serves them (writes to its primary, reads to an in-sync copy;
  // client/cluster_routes.h) instead of through `target`, which forwards.
  // Needs a token that may read the cluster (server-wide read); without
  // one, or against a node that runs alone, every call goes to `target`.
  bool route = false;
};

class LmdClient {
 public:
  // InvalidArgument if the target is not HOST:PORT with a port from 1 to
  // 65535, a TLS file cannot be read or holds no PEM block of its kind, a
  // client certificate comes without its key (or either without the CA
  // file), or the token is not printable ASCII.
  static Result<std::unique_ptr<LmdClient>> Create(const ClientOptions& options);

  grpc::Status InsertMaps(const v1::InsertMapsRequest& request, v1::InsertMapsResponse* response) const;
  // Streams the requests as one client stream (lmdd writes and acknowledges
  // them in order; the response lists the stored maps). Retried as a whole
  // like InsertMaps: every map without a map_id gets a random request_id
  // unless it has one, so the maps an interrupted stream stored are replayed,
  // not stored twice. When the stream ends with an error (a bad map, say),
  // the maps before it are stored all the same: the response then lists
  // those requests' metadata as sent (an id lmdd would have assigned is not
  // known then).
  grpc::Status StreamInsertMaps(const std::vector<v1::InsertMapRequest>& requests,
                                v1::InsertMapsResponse* response) const;
  grpc::Status GetMap(const v1::GetMapRequest& request, v1::GetMapResponse* response) const;
  grpc::Status DeleteMap(const v1::DeleteMapRequest& request) const;
  grpc::Status ListMaps(const v1::ListMapsRequest& request, v1::ListMapsResponse* response) const;
  grpc::Status Retrieve(const v1::RetrieveRequest& request, v1::RetrieveResponse* response) const;
  grpc::Status DetectChanges(const v1::DetectChangesRequest& request, v1::DetectChangesResponse* response) const;
  grpc::Status ListCollections(v1::ListCollectionsResponse* response) const;
  grpc::Status Stats(const v1::StatsRequest& request, v1::StatsResponse* response) const;
  grpc::Status Backup(const v1::BackupRequest& request, v1::BackupResponse* response) const;
  // The cluster as the node answering sees it (enabled = false: a single node).
  grpc::Status Cluster(v1::ClusterResponse* response) const;
  grpc::Status SetReplication(const v1::SetReplicationRequest& request, v1::SetReplicationResponse* response) const;

 private:
  explicit LmdClient(const ClientOptions& options) : options_(options) {}

  // A context with the deadline, token and collection header.
  std::unique_ptr<grpc::ClientContext> NewContext(const std::string& collection,
                                                  std::chrono::system_clock::time_point deadline) const;
  using Call = std::function<grpc::Status(grpc::ClientContext*, v1::LmdService::Stub*)>;
  // Runs `call` with a fresh context per attempt, on the node that serves
  // the collection's reads or (`write`) writes when routing, retrying (when
  // `retry`) as the header says; *attempts (optional) receives how many it
  // made.
  grpc::Status WithRetries(const std::string& collection, const Call& call, bool retry = true,
                           int* attempts = nullptr, bool write = false) const;

  ClientOptions options_;
  std::unique_ptr<v1::LmdService::Stub> stub_;  // to options_.target
  std::unique_ptr<ClusterRoutes> routes_;       // with options_.route
};

}  // namespace lmd::client
