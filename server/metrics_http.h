// MetricsHttpServer: serves GET /metrics (Prometheus text format) on its own
// port, with Debian's libmicrohttpd; every other path is 404.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "core/status.h"

struct MHD_Daemon;

namespace lmd::server {

class MetricsHttpServer {
 public:
  // Serves on HOST:PORT (port 0: a free one); `render` builds the page on each
  // request (from libmicrohttpd's thread). InvalidArgument for a bad address,
  // Internal if it cannot listen.
  static Result<std::unique_ptr<MetricsHttpServer>> Start(const std::string& host_port,
                                                          std::function<std::string()> render);
  ~MetricsHttpServer();
  MetricsHttpServer(const MetricsHttpServer&) = delete;
  MetricsHttpServer& operator=(const MetricsHttpServer&) = delete;

  int port() const { return port_; }

 private:
  MetricsHttpServer() = default;

  std::function<std::string()> render_;
  MHD_Daemon* daemon_ = nullptr;
  int port_ = 0;
};

}  // namespace lmd::server
