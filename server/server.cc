#include "server/server.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/server.h>
#include <grpcpp/server_builder.h>
#include <spdlog/spdlog.h>

#include "grpc/health/v1/health.pb.h"
#include "server/lmd_service.h"
#include "server/map_store.h"

namespace lmd::server {

Result<std::unique_ptr<LmdServer>> LmdServer::Start(const ServerConfig& config) {
  if (!IsLoopbackAddress(config.listen) && !config.allow_insecure_remote) {
    return Status::InvalidArgument("refusing to serve on " + config.listen +
                                   " without TLS and tokens; listen on loopback or set allow_insecure_remote");
  }
  Result<std::unique_ptr<MapStore>> store = MapStore::Open({config.data_dir, config.sync_writes});
  if (!store.ok()) return store.status();

  std::unique_ptr<LmdServer> server(new LmdServer());
  server->store_ = std::move(store).value();
  server->service_ = std::make_unique<LmdServiceImpl>(config, server->store_.get());

  // Reflection serves descriptors from the generated pool; the built-in health
  // service has none, so its messages are linked in from lmd_proto here.
  grpc::health::v1::HealthCheckRequest::descriptor();
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();

  grpc::ServerBuilder builder;
  builder.AddListeningPort(config.listen, grpc::InsecureServerCredentials(), &server->port_);
  builder.SetMaxReceiveMessageSize(config.max_message_bytes);
  builder.SetMaxSendMessageSize(config.max_message_bytes);
  builder.RegisterService(server->service_.get());
  server->server_ = builder.BuildAndStart();
  if (!server->server_ || server->port_ == 0) {
    server->store_->Close();
    return Status::Internal("cannot listen on " + config.listen);
  }
  server->server_->GetHealthCheckService()->SetServingStatus(true);
  spdlog::info("lmdd serving on port {} (data dir {})", server->port_, config.data_dir);
  return server;
}

LmdServer::~LmdServer() { Shutdown(); }

void LmdServer::Wait() { server_->Wait(); }

void LmdServer::Shutdown(std::chrono::milliseconds grace) {
  if (stopped_) return;
  stopped_ = true;
  spdlog::info("lmdd shutting down (grace {} ms)", grace.count());
  server_->GetHealthCheckService()->SetServingStatus(false);
  server_->Shutdown(std::chrono::system_clock::now() + grace);
  Status closed = store_->Close();
  if (!closed.ok()) spdlog::error("{}", closed.ToString());
  spdlog::info("lmdd stopped");
}

}  // namespace lmd::server
