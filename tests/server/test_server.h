// An lmdd started in-process for tests: a fresh data directory, 127.0.0.1 on a
// free port, and a client connected to it.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "client/lmd_client.h"
#include "server/server.h"

namespace lmd::testing {

// A fresh, empty directory under the system temp dir, removed at destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

class TestServer {
 public:
  // Starts lmdd on `data_dir` with `config` (listen and data_dir are set here).
  explicit TestServer(const std::string& data_dir, server::ServerConfig config = {});
  ~TestServer();

  bool ok() const { return server_ != nullptr; }
  std::string address() const { return "127.0.0.1:" + std::to_string(server_->port()); }
  const client::LmdClient& client() const { return *client_; }
  void Stop();

 private:
  std::unique_ptr<server::LmdServer> server_;
  std::unique_ptr<client::LmdClient> client_;
};

// What an lmdctl run printed and returned.
struct CliRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

// Runs lmdctl (LMDCTL_PATH) with `args` (shell words), capturing stdout and
// stderr (through a file in `dir`).
CliRun RunLmdctl(const std::string& args, const TempDir& dir);

// A small valid local map: a square room outline, `n` points.
v1::LocalMap SquareRoomMap(int n = 40);

// An InsertMapsRequest with one map.
v1::InsertMapsRequest OneMapRequest(const std::string& collection, const std::string& map_id,
                                    const v1::LocalMap& map);

}  // namespace lmd::testing
