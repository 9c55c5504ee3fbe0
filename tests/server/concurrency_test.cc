// Many robots at once: concurrent inserts and queries give the results a
// serial replay gives, and every query sees the maps its robot already stored.
#include <thread>

#include <gtest/gtest.h>

#include "core/sim/simulate.h"
#include "proto/convert.h"
#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

constexpr int kRobots = 6;
constexpr int kMapsPerRobot = 12;

std::vector<LocalMap> DemoMaps() {
  std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  maps.resize(std::min<size_t>(maps.size(), kRobots * kMapsPerRobot));
  return maps;
}

v1::RetrieveRequest QueryFor(const LocalMap& map) {
  v1::RetrieveRequest request;
  request.set_collection("fleet");
  *request.mutable_map() = ToProto(map);
  request.set_top_k(5);
  return request;
}

TEST(ConcurrencyTest, ConcurrentRobotsMatchASerialReplay) {
  const std::vector<LocalMap> maps = DemoMaps();
  ASSERT_EQ(maps.size(), static_cast<size_t>(kRobots * kMapsPerRobot));
  TempDir concurrent_dir, serial_dir;
  TestServer concurrent(concurrent_dir.path());

  std::vector<std::string> failures[kRobots];
  std::vector<std::thread> robots;
  for (int r = 0; r < kRobots; ++r) {
    robots.emplace_back([&, r] {
      for (int k = 0; k < kMapsPerRobot; ++k) {
        const LocalMap& map = maps[r + kRobots * k];  // robots interleave along the route
        v1::InsertMapsResponse inserted;
        grpc::Status status = concurrent.client().InsertMaps(OneMapRequest("fleet", map.id, ToProto(map)), &inserted);
        if (!status.ok()) {
          failures[r].push_back("insert " + map.id + ": " + status.error_message());
          continue;
        }
        v1::RetrieveResponse found;
        status = concurrent.client().Retrieve(QueryFor(map), &found);
        if (!status.ok() || found.hits_size() == 0 || found.hits(0).map_id() != map.id) {
          failures[r].push_back("query " + map.id + " did not find itself first: " + (found.hits_size() ? found.hits(0).map_id() + " " + std::to_string(found.hits(0).score()) : std::string("no hit")) + (found.hits_size() > 1 ? " / " + found.hits(1).map_id() + " " + std::to_string(found.hits(1).score()) : std::string()));
        }
      }
    });
  }
  for (auto& robot : robots) robot.join();
  for (const auto& robot_failures : failures) EXPECT_TRUE(robot_failures.empty()) << robot_failures[0];

  TestServer serial(serial_dir.path());
  for (const LocalMap& map : maps) {
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(serial.client().InsertMaps(OneMapRequest("fleet", map.id, ToProto(map)), &inserted).ok());
  }
  for (size_t i = 0; i < maps.size(); i += 7) {
    v1::RetrieveResponse a, b;
    ASSERT_TRUE(concurrent.client().Retrieve(QueryFor(maps[i]), &a).ok());
    ASSERT_TRUE(serial.client().Retrieve(QueryFor(maps[i]), &b).ok());
    ASSERT_EQ(a.hits_size(), b.hits_size());
    for (int h = 0; h < a.hits_size(); ++h) {
      EXPECT_DOUBLE_EQ(a.hits(h).score(), b.hits(h).score()) << "query " << maps[i].id << " hit " << h << ": "
                                                            << a.ShortDebugString() << "\n vs " << b.ShortDebugString();
      // Equal scores are ordered by internal index ids, which follow insertion
      // order, and the last hit may tie with maps beyond top_k; hits with a
      // score of their own above the last one must be the same map.
      int ties = 0;
      for (int o = 0; o < a.hits_size(); ++o) ties += a.hits(o).score() == a.hits(h).score();
      if (ties == 1 && a.hits(h).score() > a.hits(a.hits_size() - 1).score()) {
        EXPECT_EQ(a.hits(h).map_id(), b.hits(h).map_id()) << "query " << maps[i].id << " hit " << h;
      }
    }
  }
}

TEST(ConcurrencyTest, ExpiredDeadlineIsReportedAndTheServerKeepsServing) {
  TempDir dir;
  server::ServerConfig config;
  config.worker_threads = 1;
  TestServer server(dir.path(), config);
  client::ClientOptions options;
  options.target = server.address();
  options.deadline = std::chrono::milliseconds(1);  // expires while queued or running
  options.max_attempts = 1;
  auto hurried = std::move(client::LmdClient::Create(options)).value();
  const std::vector<LocalMap> maps = DemoMaps();
  v1::InsertMapsRequest big;
  for (int i = 0; i < 40; ++i) *big.add_maps() = OneMapRequest("fleet", maps[i].id, ToProto(maps[i])).maps(0);
  v1::InsertMapsResponse ignored;
  const grpc::Status status = hurried->InsertMaps(big, &ignored);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  // The server stays healthy and serves the next call.
  EXPECT_TRUE(server.client().InsertMaps(OneMapRequest("fleet", "after", SquareRoomMap()), &ignored).ok());
}

// Eight clients send overlapping batches (~50 ms of describing each) to one
// worker with room for one queued call; returns how many batches were stored
// and how many refused as busy.
std::pair<int, int> EightOverlappingBatches(const TestServer& server, int max_attempts) {
  client::ClientOptions options;
  options.target = server.address();
  options.max_attempts = max_attempts;
  options.initial_backoff = std::chrono::milliseconds(20);
  auto client = std::move(client::LmdClient::Create(options)).value();
  const std::vector<LocalMap> maps = DemoMaps();
  std::atomic<int> exhausted{0}, ok{0};
  std::vector<std::thread> clients;
  for (int c = 0; c < 8; ++c) {
    clients.emplace_back([&, c] {
      v1::InsertMapsRequest batch;
      for (int i = 0; i < 16; ++i) {
        *batch.add_maps() = OneMapRequest("fleet", "c" + std::to_string(c) + "-" + std::to_string(i),
                                          ToProto(maps[(c * 16 + i) % maps.size()])).maps(0);
      }
      v1::InsertMapsResponse ignored;
      const grpc::Status status = client->InsertMaps(batch, &ignored);
      if (status.ok()) ++ok;
      if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) {
        EXPECT_NE(status.error_message().find("max_queued_calls"), std::string::npos);
        ++exhausted;
      }
    });
  }
  for (auto& thread : clients) thread.join();
  return {ok.load(), exhausted.load()};
}

server::ServerConfig OneWorkerOneQueued() {
  server::ServerConfig config;
  config.worker_threads = 1;
  config.max_queued_calls = 1;
  return config;
}

TEST(ConcurrencyTest, FullQueueIsRefusedWithResourceExhausted) {
  TempDir dir;
  TestServer server(dir.path(), OneWorkerOneQueued());
  const auto [ok, exhausted] = EightOverlappingBatches(server, /*max_attempts=*/1);
  EXPECT_GT(ok, 0);
  EXPECT_GT(exhausted, 0) << "8 concurrent batches never overflowed a queue of 1";
  EXPECT_EQ(ok + exhausted, 8);
}

TEST(ConcurrencyTest, TheClientRetriesCallsRefusedAsBusy) {
  TempDir dir;
  TestServer server(dir.path(), OneWorkerOneQueued());
  const auto [ok, exhausted] = EightOverlappingBatches(server, /*max_attempts=*/20);
  EXPECT_EQ(ok, 8) << exhausted << " batches still refused after 20 attempts";
}

// Sixteen robots ask at once of one worker: the queries that start while
// others wait are answered at the busy depth (one verified hit) and say so;
// a request that names its depth, and a query on an idle server, are not.
TEST(ConcurrencyTest, QueriesStartedWhileCallsWaitAreAnsweredAtTheBusyDepth) {
  TempDir dir;
  server::ServerConfig config;
  config.worker_threads = 1;
  config.busy_queued_calls = 1;
  config.busy_verify_candidates = 1;
  TestServer server(dir.path(), config);
  const std::vector<LocalMap> maps = DemoMaps();
  for (const LocalMap& map : maps) {
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("fleet", map.id, ToProto(map)), &inserted).ok());
  }
  auto verified_hits = [](const v1::RetrieveResponse& response) {
    int verified = 0;
    for (const v1::MapHit& hit : response.hits()) verified += hit.verified();
    return verified;
  };

  std::atomic<int> reduced{0}, named_depth_reduced{0};
  std::vector<std::string> failures[16];
  std::vector<std::thread> robots;
  for (int r = 0; r < 16; ++r) {
    robots.emplace_back([&, r] {
      v1::RetrieveRequest request = QueryFor(maps[(r * 5) % maps.size()]);
      const bool names_depth = r % 4 == 3;
      if (names_depth) request.set_verify_candidates(10);
      v1::RetrieveResponse response;
      const grpc::Status status = server.client().Retrieve(request, &response);
      if (!status.ok()) return failures[r].push_back(status.error_message());
      if (names_depth) {
        named_depth_reduced += response.reduced_depth();
      } else if (response.reduced_depth()) {
        ++reduced;
        if (verified_hits(response) > 1) failures[r].push_back("a busy answer verified more than one hit");
      } else {
        if (verified_hits(response) < 2) failures[r].push_back("a full answer verified fewer than two hits");
      }
    });
  }
  for (auto& robot : robots) robot.join();
  for (const auto& robot_failures : failures) EXPECT_TRUE(robot_failures.empty()) << robot_failures[0];
  EXPECT_GT(reduced, 0) << "no query of 12 sent at once to one worker saw another waiting";
  EXPECT_EQ(named_depth_reduced, 0);

  v1::RetrieveResponse alone;
  ASSERT_TRUE(server.client().Retrieve(QueryFor(maps[0]), &alone).ok());
  EXPECT_FALSE(alone.reduced_depth());
  EXPECT_GE(verified_hits(alone), 2);
}

}  // namespace
}  // namespace lmd::testing
