#include "tests/server/test_server.h"

#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

namespace lmd::testing {

TempDir::TempDir() {
  std::random_device random;
  path_ = (std::filesystem::temp_directory_path() / ("lmd-test-" + std::to_string(random()))).string();
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

TestServer::TestServer(const std::string& data_dir, server::ServerConfig config) {
  config.listen = "127.0.0.1:0";
  config.data_dir = data_dir;
  auto started = server::LmdServer::Start(config);
  if (!started.ok()) {
    ADD_FAILURE() << "lmdd did not start: " << started.status().ToString();
    return;
  }
  server_ = std::move(started).value();
  client::ClientOptions options;
  options.target = address();
  options.deadline = std::chrono::seconds(20);
  options.max_message_bytes = 256 << 20;  // above any server limit: the server is what refuses
  client_ = std::move(client::LmdClient::Create(options)).value();
}

TestServer::~TestServer() { Stop(); }

void TestServer::Stop() {
  if (server_) server_->Shutdown(std::chrono::seconds(1));
  server_.reset();
}

v1::LocalMap SquareRoomMap(int n) {
  v1::LocalMap map;
  for (int i = 0; i < n; ++i) {
    const double t = 4.0 * i / n;  // walks the 4 sides of a 4 m square
    const int side = static_cast<int>(t);
    const double f = (t - side) * 4.0;
    const double x[] = {f, 4.0, 4.0 - f, 0.0};
    const double y[] = {0.0, f, 4.0, 4.0 - f};
    map.add_x(static_cast<float>(x[side] - 2.0));
    map.add_y(static_cast<float>(y[side] - 2.0));
  }
  v1::Pose2* pose = map.add_trajectory();
  pose->set_theta(0.0);
  return map;
}

v1::InsertMapsRequest OneMapRequest(const std::string& collection, const std::string& map_id,
                                    const v1::LocalMap& map) {
  v1::InsertMapsRequest request;
  v1::InsertMapRequest* insert = request.add_maps();
  insert->mutable_metadata()->set_collection(collection);
  insert->mutable_metadata()->set_map_id(map_id);
  *insert->mutable_map() = map;
  return request;
}

CliRun RunLmdctl(const std::string& args, const TempDir& dir) {
  const std::string err_path = dir.path() + "/stderr.txt";
  const std::string command = std::string(LMDCTL_PATH) + " " + args + " 2>" + err_path;
  CliRun run;
  FILE* pipe = popen(command.c_str(), "r");
  std::array<char, 4096> buffer;
  while (size_t n = fread(buffer.data(), 1, buffer.size(), pipe)) run.out.append(buffer.data(), n);
  const int status = pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream err(err_path);
  run.err.assign(std::istreambuf_iterator<char>(err), {});
  return run;
}


}  // namespace lmd::testing
