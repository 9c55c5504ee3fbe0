#include "server/metrics_http.h"

#include <arpa/inet.h>
#include <microhttpd.h>
#include <netinet/in.h>

#include <cstring>

#include "core/util/host_port.h"

namespace lmd::server {
namespace {

MHD_Result Respond(MHD_Connection* connection, unsigned status, const std::string& body, const char* type) {
  MHD_Response* response =
      MHD_create_response_from_buffer(body.size(), const_cast<char*>(body.data()), MHD_RESPMEM_MUST_COPY);
  MHD_add_response_header(response, "Content-Type", type);
  const MHD_Result result = MHD_queue_response(connection, status, response);
  MHD_destroy_response(response);
  return result;
}

MHD_Result Handle(void* cls, MHD_Connection* connection, const char* url, const char* method, const char*,
                  const char*, size_t*, void**) {
  const auto* render = static_cast<const std::function<std::string()>*>(cls);
  if (std::strcmp(method, "GET") != 0) return Respond(connection, 405, "method not allowed\n", "text/plain");
  if (std::strcmp(url, "/metrics") != 0) return Respond(connection, 404, "not found; try /metrics\n", "text/plain");
  return Respond(connection, 200, (*render)(), "text/plain; version=0.0.4");
}

}  // namespace

Result<std::unique_ptr<MetricsHttpServer>> MetricsHttpServer::Start(const std::string& host_port,
                                                                    std::function<std::string()> render) {
  const Result<HostPort> listen = ParseHostPort(host_port, 0, "metrics_listen");
  if (!listen.ok()) return listen.status();
  sockaddr_in address{};
  address.sin_family = AF_INET;
  const std::string host = listen->host == "localhost" ? "127.0.0.1" : listen->host;
  if (inet_pton(AF_INET, host.c_str(), &address.sin_addr) != 1) {
    return Status::InvalidArgument("metrics_listen must be IPv4:PORT, got '" + host_port + "'");
  }
  address.sin_port = htons(static_cast<uint16_t>(listen->port));

  std::unique_ptr<MetricsHttpServer> server(new MetricsHttpServer());
  server->render_ = std::move(render);
  server->daemon_ = MHD_start_daemon(MHD_USE_INTERNAL_POLLING_THREAD, 0, nullptr, nullptr, &Handle,
                                     &server->render_, MHD_OPTION_SOCK_ADDR, &address, MHD_OPTION_END);
  if (server->daemon_ == nullptr) return Status::Internal("cannot serve metrics on " + host_port);
  const MHD_DaemonInfo* info = MHD_get_daemon_info(server->daemon_, MHD_DAEMON_INFO_BIND_PORT);
  server->port_ = info ? info->port : listen->port;
  return server;
}

MetricsHttpServer::~MetricsHttpServer() {
  if (daemon_ != nullptr) MHD_stop_daemon(daemon_);
}

}  // namespace lmd::server
