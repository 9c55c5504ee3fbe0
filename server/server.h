// LmdServer: lmdd as an object — the store, the gRPC service with reflection
// and grpc.health.v1, started and stopped as one. lmdd's main and the
// in-process tests both use it.
#pragma once

#include <chrono>
#include <memory>

#include "core/status.h"
#include "server/config.h"

namespace grpc {
class Server;
}  // namespace grpc

namespace lmd::server {

class LmdServiceImpl;
class MapStore;

class LmdServer {
 public:
  // Opens the store in config.data_dir and serves on config.listen.
  // InvalidArgument if the address is not loopback and insecure remote
  // serving was not allowed; IoError / Corruption if the store cannot be
  // opened; Internal if the address cannot be bound.
  static Result<std::unique_ptr<LmdServer>> Start(const ServerConfig& config);
  ~LmdServer();

  // The bound port (useful with port 0).
  int port() const { return port_; }

  // Blocks until Shutdown has completed.
  void Wait();

  // Graceful stop: health turns NOT_SERVING, new calls are refused, calls in
  // flight get up to `grace` to finish (then are cancelled), and the store is
  // closed. Idempotent.
  void Shutdown(std::chrono::milliseconds grace = std::chrono::seconds(10));

 private:
  LmdServer() = default;

  std::unique_ptr<MapStore> store_;
  std::unique_ptr<LmdServiceImpl> service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  bool stopped_ = false;
};

}  // namespace lmd::server
