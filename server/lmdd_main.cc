// lmdd: the lmd daemon. Flags override the config file, which overrides the
// defaults of ServerConfig. Stops gracefully on SIGTERM or SIGINT.
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

#include <spdlog/spdlog.h>

#include "server/config.h"
#include "server/server.h"

namespace {

constexpr char kUsage[] =
    "usage: lmdd [--listen HOST:PORT] [--data-dir DIR] [--config FILE] [--log-level LEVEL]\n"
    "            [--set KEY=VALUE]...\n"
    "Serves the lmd gRPC API (with reflection and grpc.health.v1) from a RocksDB store.\n";

// Fills *config from argv; returns false with a message on stderr on error.
bool ParseFlags(int argc, char** argv, lmd::server::ServerConfig* config) {
  // The config file is read first so that flags win wherever they stand.
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::string(argv[i]) == "--config") {
      lmd::Status s = lmd::server::LoadConfigFile(argv[i + 1], config);
      if (!s.ok()) {
        std::fprintf(stderr, "lmdd: %s\n", s.message().c_str());
        return false;
      }
    }
  }
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "-h" || flag == "--help") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "lmdd: %s needs a value\n%s", flag.c_str(), kUsage);
      return false;
    }
    const std::string value = argv[++i];
    lmd::Status s;
    if (flag == "--config") continue;
    if (flag == "--listen") s = lmd::server::SetConfigValue("listen", value, config);
    else if (flag == "--data-dir") s = lmd::server::SetConfigValue("data_dir", value, config);
    else if (flag == "--log-level") s = lmd::server::SetConfigValue("log_level", value, config);
    else if (flag == "--set" && value.find('=') != std::string::npos) {
      s = lmd::server::SetConfigValue(value.substr(0, value.find('=')), value.substr(value.find('=') + 1), config);
    } else {
      s = lmd::Status::InvalidArgument("unknown flag " + flag);
    }
    if (!s.ok()) {
      std::fprintf(stderr, "lmdd: %s\n", s.message().c_str());
      return false;
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  lmd::server::ServerConfig config;
  if (!ParseFlags(argc, argv, &config)) return 2;
  const auto level = spdlog::level::from_str(config.log_level);
  if (level == spdlog::level::off && config.log_level != "off") {
    std::fprintf(stderr, "lmdd: unknown log level '%s'\n", config.log_level.c_str());
    return 2;
  }
  spdlog::set_level(level);

  // Block the stop signals in every thread; one thread waits for them.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGTERM);
  sigaddset(&stop_signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  auto server = lmd::server::LmdServer::Start(config);
  if (!server.ok()) {
    std::fprintf(stderr, "lmdd: %s\n", server.status().message().c_str());
    return 1;
  }
  std::printf("lmdd listening on port %d\n", (*server)->port());
  std::fflush(stdout);

  std::thread stopper([&] {
    int signal = 0;
    sigwait(&stop_signals, &signal);
    spdlog::info("received {}", signal == SIGTERM ? "SIGTERM" : "SIGINT");
    (*server)->Shutdown();
  });
  (*server)->Wait();
  stopper.join();
  server->reset();
  return 0;
}
