// Replicated collections end to end: a real etcd and three lmdd nodes in this
// process, on loopback. The kill -9, SIGSTOP and etcd-member checks run
// against separate processes in deploy/test-replication.sh.
#include <chrono>
#include <set>
#include <thread>

#include <grpcpp/grpcpp.h>
#include <grpcpp/impl/client_unary_call.h>
#include <gtest/gtest.h>

#include "grpc/health/v1/health.pb.h"
#include "tests/server/etcd_process.h"
#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

using Clock = std::chrono::steady_clock;

class ClusterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    Result<std::unique_ptr<EtcdCluster>> etcd = EtcdCluster::Start(1);
    ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
    etcd_ = std::move(etcd).value();
    for (int i = 0; i < 3; ++i) ports_.push_back(UnusedLoopbackPort());
    for (int i = 0; i < 3; ++i) dirs_.push_back(std::make_unique<TempDir>());
    nodes_.resize(3);
    for (int i = 0; i < 3; ++i) StartNode(i);
  }

  void StartNode(int i, bool paper_index = true) {
    server::ServerConfig config;
    config.paper_index = paper_index;
    config.listen = Address(i);
    config.data_dir = dirs_[i]->path();
    config.cluster_etcd = etcd_->endpoint(0);
    config.cluster_node_id = "n" + std::to_string(i);
    config.cluster_lease_ttl_s = 1;
    config.cluster_replicate_timeout_ms = 500;
    Result<std::unique_ptr<server::LmdServer>> started = server::LmdServer::Start(config);
    ASSERT_TRUE(started.ok()) << started.status().ToString();
    nodes_[i] = std::move(started).value();
  }

  std::string Address(int i) const { return "127.0.0.1:" + std::to_string(ports_[i]); }
  std::unique_ptr<client::LmdClient> ClientOf(int i) const {
    client::ClientOptions options;
    options.target = Address(i);
    return client::LmdClient::Create(options).value();
  }

  // The write acknowledged by any node, tried in turn for up to 10 s.
  bool Insert(const std::string& id, int first_node) {
    const auto give_up = Clock::now() + std::chrono::seconds(10);
    for (int attempt = 0; Clock::now() < give_up; ++attempt) {
      const int i = (first_node + attempt) % 3;
      if (!nodes_[i]) continue;
      auto stub = v1::LmdService::NewStub(grpc::CreateChannel(Address(i), grpc::InsecureChannelCredentials()));
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(3));
      v1::InsertMapsResponse response;
      if (stub->InsertMaps(&context, OneMapRequest("site", id, SquareRoomMap(12 + attempt % 4)), &response).ok()) {
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
  }

  // grpc.health.v1 says SERVING.
  bool Serving(int i) const {
    auto channel = grpc::CreateChannel(Address(i), grpc::InsecureChannelCredentials());
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
    grpc::health::v1::HealthCheckRequest request;
    grpc::health::v1::HealthCheckResponse answer;
    const grpc::Status status = grpc::internal::BlockingUnaryCall(
        channel.get(), grpc::internal::RpcMethod("/grpc.health.v1.Health/Check", grpc::internal::RpcMethod::NORMAL_RPC),
        &context, request, &answer);
    return status.ok() && answer.status() == grpc::health::v1::HealthCheckResponse::SERVING;
  }

  // Node i's own store holds the collection.
  bool HoldsCopy(int i) const {
    auto stub = v1::LmdService::NewStub(grpc::CreateChannel(Address(i), grpc::InsecureChannelCredentials()));
    grpc::ClientContext context;
    context.AddMetadata("lmd-local", "1");
    v1::ListMapsRequest request;
    request.set_collection("site");
    v1::ListMapsResponse response;
    const grpc::Status listed = stub->ListMaps(&context, request, &response);
    EXPECT_TRUE(listed.ok() || listed.error_code() == grpc::StatusCode::NOT_FOUND) << listed.error_message();
    return listed.ok();
  }

  // The map ids node i's own copy holds.
  std::set<std::string> Held(int i) const {
    auto stub = v1::LmdService::NewStub(grpc::CreateChannel(Address(i), grpc::InsecureChannelCredentials()));
    grpc::ClientContext context;
    context.AddMetadata("lmd-local", "1");
    v1::ListMapsRequest request;
    request.set_collection("site");
    request.set_page_size(1000);
    v1::ListMapsResponse response;
    std::set<std::string> ids;
    if (!stub->ListMaps(&context, request, &response).ok()) return ids;
    for (const v1::MapMetadata& m : response.maps()) ids.insert(m.map_id());
    return ids;
  }

  std::unique_ptr<EtcdCluster> etcd_;
  std::vector<int> ports_;
  std::vector<std::unique_ptr<TempDir>> dirs_;
  std::vector<std::unique_ptr<server::LmdServer>> nodes_;
};

TEST_F(ClusterTest, EveryAcknowledgedWriteIsOnEveryCopyAndOutlivesItsPrimary) {
  std::set<std::string> acked;
  for (int k = 0; k < 8; ++k) {
    const std::string id = "a" + std::to_string(k);
    ASSERT_TRUE(Insert(id, 1)) << id;  // node 1 takes the first write: it becomes the primary
    acked.insert(id);
  }
  for (int i = 0; i < 3; ++i) EXPECT_EQ(Held(i), acked) << "node " << i;

  nodes_[1]->Shutdown(std::chrono::milliseconds(0));  // leaves the cluster: a copy is promoted
  nodes_[1].reset();
  for (int k = 0; k < 8; ++k) {
    const std::string id = "b" + std::to_string(k);
    ASSERT_TRUE(Insert(id, 0)) << id;
    acked.insert(id);
  }
  EXPECT_EQ(Held(0), acked);
  EXPECT_EQ(Held(2), acked);

  v1::ClusterResponse cluster;
  ASSERT_TRUE(ClientOf(0)->Cluster(&cluster).ok());
  ASSERT_EQ(cluster.placements_size(), 1);
  EXPECT_EQ(cluster.placements(0).epoch(), 2u);

  StartNode(1);  // back on its old store: it catches up, then holds every write again
  const auto give_up = Clock::now() + std::chrono::seconds(10);
  while ((Held(1) != acked || !Serving(1)) && Clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(Held(1), acked);
  EXPECT_TRUE(Serving(1));  // readiness: SERVING once its copy caught up
}

TEST_F(ClusterTest, AnInsertRetriedAfterItsPrimaryDiedIsStoredOnce) {
  v1::InsertMapsRequest request = OneMapRequest("site", "", SquareRoomMap(12));  // lmdd assigns the id
  request.set_request_id("robot-7-tick-1");
  v1::InsertMapsResponse first;
  ASSERT_TRUE(ClientOf(1)->InsertMaps(request, &first).ok());  // node 1 becomes the primary
  nodes_[1]->Shutdown(std::chrono::milliseconds(0));  // its answer "lost": the robot retries elsewhere
  nodes_[1].reset();
  v1::InsertMapsResponse again;
  grpc::Status retried;
  const auto give_up = Clock::now() + std::chrono::seconds(10);
  do {
    again.Clear();
    retried = ClientOf(0)->InsertMaps(request, &again);
  } while (!retried.ok() && Clock::now() < give_up);
  ASSERT_TRUE(retried.ok()) << retried.error_message();
  EXPECT_TRUE(again.replayed());
  ASSERT_EQ(again.maps_size(), 1);
  EXPECT_EQ(again.maps(0).map_id(), first.maps(0).map_id());
  EXPECT_EQ(Held(0), std::set<std::string>{first.maps(0).map_id()});
  EXPECT_EQ(Held(2), std::set<std::string>{first.maps(0).map_id()});
}

TEST_F(ClusterTest, ACollectionKeepsTheCopiesItIsSetTo) {
  ASSERT_TRUE(Insert("m1", 0));
  auto client = ClientOf(2);
  v1::SetReplicationRequest request;
  request.set_collection("site");
  request.set_replication_factor(1);
  v1::SetReplicationResponse set;
  ASSERT_TRUE(client->SetReplication(request, &set).ok());
  EXPECT_EQ(set.placement().copies_wanted(), 1u);
  auto copies = [&] {
    v1::ClusterResponse cluster;
    EXPECT_TRUE(client->Cluster(&cluster).ok());
    return cluster.placements_size() == 1 ? cluster.placements(0).copies_size() : -1;
  };
  const auto give_up = Clock::now() + std::chrono::seconds(10);
  while (copies() != 1 && Clock::now() < give_up) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(copies(), 1) << "the controller did not remove the two other copies";
  // The two copies the controller moved off delete their data.
  auto held_by = [&] {
    int holders = 0;
    for (int i = 0; i < 3; ++i) holders += HoldsCopy(i) ? 1 : 0;
    return holders;
  };
  while (held_by() != 1 && Clock::now() < give_up) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(held_by(), 1) << "a node the placement no longer lists kept its copy";
  ASSERT_TRUE(Insert("m2", 1));  // one copy takes writes on its own
  EXPECT_EQ(Held(0), (std::set<std::string>{"m1", "m2"}));

  request.set_replication_factor(3);  // copies again: the dropped nodes copy the collection whole
  ASSERT_TRUE(client->SetReplication(request, &set).ok());
  const std::set<std::string> both{"m1", "m2"};
  const auto copied_by = Clock::now() + std::chrono::seconds(10);
  while ((Held(1) != both || Held(2) != both) && Clock::now() < copied_by) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(Held(1), both);
  EXPECT_EQ(Held(2), both);

  request.set_replication_factor(0);
  EXPECT_EQ(client->SetReplication(request, &set).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  request.set_replication_factor(2);
  request.set_collection("never-written");
  EXPECT_EQ(client->SetReplication(request, &set).error_code(), grpc::StatusCode::NOT_FOUND);
  TempDir alone_dir;
  TestServer alone(alone_dir.path());
  EXPECT_EQ(alone.client().SetReplication(request, &set).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
}

TEST_F(ClusterTest, ARoutingClientReachesTheCopiesWithoutItsEntryNode) {
  ASSERT_TRUE(Insert("m1", 1));  // node 1 is the primary
  client::ClientOptions options;
  options.target = Address(0);
  options.route = true;
  auto routed = client::LmdClient::Create(options).value();
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(routed->InsertMaps(OneMapRequest("site", "m2", SquareRoomMap(14)), &inserted).ok());
  nodes_[0]->Shutdown(std::chrono::milliseconds(0));  // the node the client was given is gone
  nodes_[0].reset();
  const grpc::Status written = routed->InsertMaps(OneMapRequest("site", "m3", SquareRoomMap(16)), &inserted);
  EXPECT_TRUE(written.ok()) << written.error_message();
  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id("m3");
  v1::GetMapResponse got;
  for (int k = 0; k < 4; ++k) {  // reads go to either live copy (or, once, to the dead one: then asked again)
    const grpc::Status read = routed->GetMap(get, &got);
    EXPECT_TRUE(read.ok()) << read.error_message();
  }
}

// A node whose store indexes otherwise (here without the paper's index)
// would hold copies that answer otherwise: it is refused every write and
// copy, and the others acknowledge the writes without it.
TEST_F(ClusterTest, ANodeIndexedOtherwiseNeverHoldsACopy) {
  nodes_[2]->Shutdown(std::chrono::milliseconds(0));
  nodes_[2].reset();
  dirs_[2] = std::make_unique<TempDir>();
  StartNode(2, /*paper_index=*/false);
  const std::set<std::string> written{"m1", "m2", "m3"};
  for (const std::string& id : written) ASSERT_TRUE(Insert(id, 0)) << id;  // node 0 is the primary
  std::this_thread::sleep_for(std::chrono::seconds(2));  // node 2's catch-up tries meanwhile
  EXPECT_EQ(Held(0), written);
  EXPECT_EQ(Held(1), written);
  EXPECT_TRUE(Held(2).empty());
}

TEST_F(ClusterTest, ANodeForwardsWhatItDoesNotServeAndARunningAloneNodeSaysSo) {
  ASSERT_TRUE(Insert("m1", 2));
  // Every node answers reads and writes for the collection, whichever is its primary.
  for (int i = 0; i < 3; ++i) {
    auto client = ClientOf(i);
    v1::GetMapRequest get;
    get.set_collection("site");
    get.set_map_id("m1");
    v1::GetMapResponse got;
    EXPECT_TRUE(client->GetMap(get, &got).ok()) << "node " << i;
    v1::RetrieveRequest retrieve;
    retrieve.set_collection("site");
    *retrieve.mutable_map() = SquareRoomMap(12);
    v1::RetrieveResponse answer;
    EXPECT_TRUE(client->Retrieve(retrieve, &answer).ok()) << "node " << i;
  }
  TempDir alone_dir;
  TestServer alone(alone_dir.path());
  v1::ClusterResponse cluster;
  ASSERT_TRUE(alone.client().Cluster(&cluster).ok());
  EXPECT_FALSE(cluster.enabled());
}

}  // namespace
}  // namespace lmd::testing
