// LmdServer: lmdd as an object — the store, the worker pool, auth, metrics
// and the gRPC service with reflection and grpc.health.v1, started and
// stopped as one. lmdd's main and the in-process tests both use it.
#pragma once

#include <chrono>
#include <memory>
#include <mutex>

#include "core/status.h"
#include "server/config.h"

namespace grpc {
class Server;
}  // namespace grpc

namespace lmd::server {

namespace cluster {
class ClusterNode;
class ReplicaService;
}  // namespace cluster
class CallMetrics;
class CallRunner;
class LmdServiceImpl;
class MapStore;
class MetricsHttpServer;
class TokenAuthorizer;
class WorkerPool;

class LmdServer {
 public:
  // Opens the store in config.data_dir and serves on config.listen.
  // InvalidArgument if the address is not loopback while TLS or tokens are
  // missing (unless allow_insecure_remote), or if a TLS or tokens file is
  // bad; IoError / Corruption if the store cannot be opened; Internal if an
  // address cannot be bound.
  static Result<std::unique_ptr<LmdServer>> Start(const ServerConfig& config);
  ~LmdServer();

  // The bound gRPC port (useful with port 0), and the metrics port (0: off).
  int port() const { return port_; }
  int metrics_port() const;

  // Blocks until Shutdown has completed.
  void Wait();

  // Graceful stop: health turns NOT_SERVING, new calls are refused, calls in
  // flight get up to `grace` to finish (then are cancelled), queued work is
  // drained, and the store is closed. Idempotent.
  void Shutdown(std::chrono::milliseconds grace = std::chrono::seconds(10));

 private:
  LmdServer();

  std::unique_ptr<MapStore> store_;
  std::unique_ptr<cluster::ClusterNode> cluster_;  // with cluster_etcd only
  std::unique_ptr<cluster::ReplicaService> replica_service_;
  std::unique_ptr<TokenAuthorizer> auth_;
  std::unique_ptr<CallMetrics> metrics_;
  std::unique_ptr<WorkerPool> pool_;
  std::unique_ptr<CallRunner> runner_;
  std::unique_ptr<LmdServiceImpl> service_;
  std::unique_ptr<MetricsHttpServer> metrics_http_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  bool stopped_ = false;
  // Health: SERVING once the gRPC server runs and, in a cluster, the node's
  // copies have caught up (whichever comes last sets it).
  std::mutex health_mu_;
  bool health_open_ = false;  // built and not shutting down; guarded by health_mu_
};

}  // namespace lmd::server
