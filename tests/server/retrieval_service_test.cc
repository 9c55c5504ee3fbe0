// Retrieve and DetectChanges over gRPC: real results on stored maps, and the
// right status for bad queries.
#include <chrono>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "core/viewpoint/viewpoint.h"
#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

// An L-shaped corridor corner with a doorway: enough structure for a planner
// and descriptor to work on, shifted by (dx, dy) in its own frame.
v1::LocalMap CornerMap(double dx, double dy) {
  v1::LocalMap map;
  auto wall = [&](double x0, double y0, double x1, double y1) {
    const double length = std::hypot(x1 - x0, y1 - y0);
    for (double t = 0; t <= length; t += 0.05) {
      map.add_x(static_cast<float>(x0 + (x1 - x0) * t / length + dx));
      map.add_y(static_cast<float>(y0 + (y1 - y0) * t / length + dy));
    }
  };
  wall(0, 0, 8, 0);
  wall(0, 2, 6, 2);
  wall(6, 2, 6, 8);
  wall(8, 0, 8, 3.5);
  wall(8, 4.5, 8, 8);
  wall(9.5, 3.5, 9.5, 4.5);
  v1::Pose2* pose = map.add_trajectory();
  pose->set_x(1 + dx);
  pose->set_y(1 + dy);
  return map;
}

class RetrievalServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    server_ = std::make_unique<TestServer>(dir_.path());
    v1::InsertMapsRequest request;
    *request.add_maps() = OneMapRequest("site", "corner", CornerMap(0, 0)).maps(0);
    *request.add_maps() = OneMapRequest("site", "room", SquareRoomMap(200)).maps(0);
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(server_->client().InsertMaps(request, &inserted).ok());
  }

  v1::RetrieveRequest Query(const v1::LocalMap& map, uint32_t top_k = 5) {
    v1::RetrieveRequest request;
    request.set_collection("site");
    *request.mutable_map() = map;
    request.set_top_k(top_k);
    return request;
  }

  TempDir dir_;
  std::unique_ptr<TestServer> server_;
};

TEST_F(RetrievalServiceTest, ShiftedCopyFindsItsMapWithThePose) {
  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(Query(CornerMap(3.0, -1.0)), &response).ok());
  ASSERT_GE(response.hits_size(), 1);
  EXPECT_EQ(response.hits(0).map_id(), "corner");
  EXPECT_EQ(response.hits(0).rank(), 1u);
  EXPECT_GT(response.hits(0).score(), 0.0);
  EXPECT_EQ(response.hits(0).metadata().collection(), "site");
  ASSERT_TRUE(response.hits(0).has_pose());
  // The query's frame sits at (-3, +1) in the stored map's frame, unrotated;
  // the default method's scan matcher gets it to centimetres.
  EXPECT_NEAR(response.hits(0).pose().x(), -3.0, 0.05);
  EXPECT_NEAR(response.hits(0).pose().y(), 1.0, 0.05);
  EXPECT_NEAR(std::remainder(response.hits(0).pose().theta(), 2 * M_PI), 0.0, 0.01);
}

TEST_F(RetrievalServiceTest, PaperMethodPoseComesFromThePlannedFrames) {
  v1::RetrieveRequest request = Query(CornerMap(3.0, -1.0));
  request.set_method(ViewpointOptions().planner == Planner::kCoG ? v1::METHOD_LMD_COG : v1::METHOD_LMD_COR);
  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(request, &response).ok());
  ASSERT_GE(response.hits_size(), 1);
  EXPECT_EQ(response.hits(0).map_id(), "corner");
  ASSERT_TRUE(response.hits(0).has_pose());  // coarser: offset bins of the index
  EXPECT_NEAR(response.hits(0).pose().x(), -3.0, 0.5);
  EXPECT_NEAR(response.hits(0).pose().y(), 1.0, 0.5);
}

TEST_F(RetrievalServiceTest, BowHasNoPose) {
  v1::RetrieveRequest request = Query(CornerMap(0, 0));
  request.set_method(v1::METHOD_BOW);
  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(request, &response).ok());
  ASSERT_GE(response.hits_size(), 1);
  EXPECT_FALSE(response.hits(0).has_pose());
}

TEST_F(RetrievalServiceTest, DeletedMapIsNoLongerRetrieved) {
  v1::DeleteMapRequest del;
  del.set_collection("site");
  del.set_map_id("corner");
  ASSERT_TRUE(server_->client().DeleteMap(del).ok());
  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(Query(CornerMap(0, 0)), &response).ok());
  for (const auto& hit : response.hits()) EXPECT_NE(hit.map_id(), "corner");
}

TEST_F(RetrievalServiceTest, IndexIsRebuiltAfterRestart) {
  v1::RetrieveResponse before;
  ASSERT_TRUE(server_->client().Retrieve(Query(CornerMap(1, 1)), &before).ok());
  server_.reset();
  server_ = std::make_unique<TestServer>(dir_.path());
  v1::RetrieveResponse after;
  ASSERT_TRUE(server_->client().Retrieve(Query(CornerMap(1, 1)), &after).ok());
  ASSERT_EQ(after.hits_size(), before.hits_size());
  for (int i = 0; i < after.hits_size(); ++i) {
    EXPECT_EQ(after.hits(i).map_id(), before.hits(i).map_id());
    EXPECT_DOUBLE_EQ(after.hits(i).score(), before.hits(i).score());
  }
}

TEST_F(RetrievalServiceTest, BadQueriesGetClearErrors) {
  v1::RetrieveResponse response;
  grpc::Status status = server_->client().Retrieve(Query(CornerMap(0, 0), 1000000), &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("max_top_k"), std::string::npos) << status.error_message();

  status = server_->client().Retrieve(Query(v1::LocalMap()), &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("no points"), std::string::npos);

  v1::RetrieveRequest unknown = Query(CornerMap(0, 0));
  unknown.set_collection("nowhere");
  EXPECT_EQ(server_->client().Retrieve(unknown, &response).error_code(), grpc::StatusCode::NOT_FOUND);

  // lmdd indexes the default planner's viewpoints only; the other is refused.
  v1::RetrieveRequest other = Query(CornerMap(0, 0));
  other.set_method(ViewpointOptions().planner == Planner::kCoG ? v1::METHOD_LMD_COR : v1::METHOD_LMD_COG);
  status = server_->client().Retrieve(other, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("not served"), std::string::npos) << status.error_message();
}

// paper_index = false: maps are stored without the paper's descriptor and
// postings; the default method answers as before, the paper's methods are
// refused, and the store reopens with that setting only.
TEST(PaperIndexOffTest, TheDefaultMethodAnswersAndThePapersAreRefused) {
  TempDir dir;
  server::ServerConfig config;
  config.paper_index = false;
  v1::RetrieveRequest query;
  query.set_collection("site");
  *query.mutable_map() = CornerMap(3.0, -1.0);
  {
    TestServer server(dir.path(), config);
    ASSERT_TRUE(server.ok());
    v1::InsertMapsRequest insert;
    *insert.add_maps() = OneMapRequest("site", "corner", CornerMap(0, 0)).maps(0);
    *insert.add_maps() = OneMapRequest("site", "room", SquareRoomMap(200)).maps(0);
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(server.client().InsertMaps(insert, &inserted).ok());
    v1::ListCollectionsResponse collections;
    ASSERT_TRUE(server.client().ListCollections(&collections).ok());
    ASSERT_EQ(collections.collections_size(), 1);
    EXPECT_EQ(collections.collections(0).maps(), 2u);
    EXPECT_EQ(collections.collections(0).postings(), 0u);

    v1::RetrieveResponse response;
    ASSERT_TRUE(server.client().Retrieve(query, &response).ok());
    ASSERT_GE(response.hits_size(), 1);
    EXPECT_EQ(response.hits(0).map_id(), "corner");
    EXPECT_NEAR(response.hits(0).pose().x(), -3.0, 0.05);

    v1::RetrieveRequest paper = query;
    paper.set_method(v1::METHOD_BOW);
    grpc::Status status = server.client().Retrieve(paper, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
    EXPECT_NE(status.error_message().find("paper_index = false"), std::string::npos) << status.error_message();
    v1::DetectChangesRequest changes;
    changes.set_collection("site");
    *changes.mutable_map() = CornerMap(0, 0);
    changes.set_method(ViewpointOptions().planner == Planner::kCoG ? v1::METHOD_LMD_COG : v1::METHOD_LMD_COR);
    v1::DetectChangesResponse detected;
    status = server.client().DetectChanges(changes, &detected);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << status.error_message();
  }
  // An lmdd with the paper's index refuses the store: its maps have no descriptors.
  server::ServerConfig with_paper;
  with_paper.listen = "127.0.0.1:0";
  with_paper.data_dir = dir.path();
  const auto refused = server::LmdServer::Start(with_paper);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("paper_index=0"), std::string::npos) << refused.status().message();
  TestServer restarted(dir.path(), config);
  ASSERT_TRUE(restarted.ok());
  v1::RetrieveResponse response;
  ASSERT_TRUE(restarted.client().Retrieve(query, &response).ok());
  ASSERT_GE(response.hits_size(), 1);
  EXPECT_EQ(response.hits(0).map_id(), "corner");
}

// Thousands of points scattered over 180 m: within every limit, but the
// worst case of scan matching (nothing to prune), which ran for seconds to
// minutes. max_query_seconds ends it with DEADLINE_EXCEEDED.
TEST(QueryBudgetTest, AQueryPastMaxQuerySecondsIsGivenUp) {
  v1::LocalMap scattered;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> coordinate(-90.0f, 90.0f);
  for (int i = 0; i < 5000; ++i) scattered.add_x(coordinate(rng)), scattered.add_y(coordinate(rng));
  TempDir dir;
  server::ServerConfig config;
  config.max_query_seconds = 0.2;
  TestServer server(dir.path(), config);
  ASSERT_TRUE(server.ok());
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "scattered", scattered), &inserted).ok());
  v1::RetrieveRequest request;
  request.set_collection("site");
  *request.mutable_map() = scattered;
  v1::RetrieveResponse response;
  const grpc::Status status = server.client().Retrieve(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << status.error_message();
  EXPECT_NE(status.error_message().find("max_query_seconds (0.2 s)"), std::string::npos) << status.error_message();
  // The worker it held answers the next call.
  v1::StatsResponse stats;
  EXPECT_TRUE(server.client().Stats(v1::StatsRequest(), &stats).ok());
}

TEST_F(RetrievalServiceTest, AnInfiniteThresholdIsRejected) {
  v1::DetectChangesRequest request;
  request.set_collection("site");
  *request.mutable_map() = CornerMap(0, 0);
  request.set_threshold(std::numeric_limits<double>::infinity());
  v1::DetectChangesResponse response;
  const grpc::Status status = server_->client().DetectChanges(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("finite"), std::string::npos) << status.error_message();
}

// A room's 200 points and 100k copies of one of them: the method sees the 200
// (as lmd builds its maps), so a scan match costs what any does. Before, the
// copies made every nearest-point search scan them all (minutes per call).
TEST_F(RetrievalServiceTest, AMapOfRepeatedPointsIsAnsweredLikeItsDistinctPoints) {
  v1::LocalMap dense = SquareRoomMap(200);
  for (int copy = 0; copy < 100000; ++copy) {
    dense.add_x(dense.x(0));
    dense.add_y(dense.y(0));
  }
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server_->client().InsertMaps(OneMapRequest("site", "dense", dense), &inserted).ok());
  EXPECT_EQ(inserted.maps(0).point_count(), 100200u);  // stored as sent
  client::ClientOptions options;
  options.target = server_->address();
  options.deadline = std::chrono::seconds(10);  // generous: the call takes a fraction of a second
  auto client = std::move(client::LmdClient::Create(options)).value();
  v1::DetectChangesRequest request;
  request.set_collection("site");
  *request.mutable_map() = dense;
  v1::DetectChangesResponse response;
  const grpc::Status status = client->DetectChanges(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_GT(response.hits_size(), 0);
  EXPECT_TRUE(response.hits(0).hit().verified());
}

TEST_F(RetrievalServiceTest, ExcludedMapsAreNeverReturned) {
  v1::RetrieveRequest request = Query(CornerMap(1.0, 0.5));
  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(request, &response).ok());
  ASSERT_GE(response.hits_size(), 1);
  EXPECT_EQ(response.hits(0).map_id(), "corner");
  request.add_exclude_map_ids("corner");
  request.add_exclude_map_ids("no-such-map");  // unknown ids are harmless
  response.Clear();
  ASSERT_TRUE(server_->client().Retrieve(request, &response).ok());
  for (const v1::MapHit& hit : response.hits()) EXPECT_NE(hit.map_id(), "corner");

  v1::DetectChangesRequest changes;
  changes.set_collection("site");
  *changes.mutable_map() = CornerMap(1.0, 0.5);
  changes.add_exclude_map_ids("corner");
  v1::DetectChangesResponse detected;
  ASSERT_TRUE(server_->client().DetectChanges(changes, &detected).ok());
  for (const v1::ChangeHit& hit : detected.hits()) EXPECT_NE(hit.hit().map_id(), "corner");

  // More ids than max_top_k: refused, naming the limit.
  for (int i = 0; i < 1001; ++i) request.add_exclude_map_ids("m" + std::to_string(i));
  const grpc::Status status = server_->client().Retrieve(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("exclude_map_ids"), std::string::npos) << status.error_message();
}

TEST_F(RetrievalServiceTest, RequestChoosesHowManyMapsAreVerified) {
  v1::InsertMapsRequest insert;
  for (int i = 0; i < 24; ++i) {  // shifted copies of one place
    *insert.add_maps() = OneMapRequest("site", "copy" + std::to_string(i), CornerMap(0.3 * i, -0.2 * i)).maps(0);
  }
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server_->client().InsertMaps(insert, &inserted).ok());
  auto hits = [&](uint32_t verify_candidates) {
    v1::RetrieveRequest request = Query(CornerMap(1.0, 1.0), 20);
    request.set_verify_candidates(verify_candidates);
    v1::RetrieveResponse response;
    const grpc::Status status = server_->client().Retrieve(request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    for (const v1::MapHit& hit : response.hits()) EXPECT_TRUE(hit.verified()) << hit.map_id();
    return response.hits_size();
  };
  // Every hit of the default method was scan matched: verify_candidates bounds them.
  EXPECT_EQ(hits(3), 3);
  EXPECT_EQ(hits(1), 1);
  EXPECT_GT(hits(0), 3);  // the server's default, 20
  EXPECT_LE(hits(0), static_cast<int>(server::ServerConfig().verify_candidates));

  v1::RetrieveRequest too_many = Query(CornerMap(1.0, 1.0));
  too_many.set_verify_candidates(server::ServerConfig().max_verify_candidates + 1);
  v1::RetrieveResponse response;
  const grpc::Status status = server_->client().Retrieve(too_many, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("max_verify_candidates"), std::string::npos) << status.error_message();
}

// Seventy shifted copies of one map: the search looks at the first maps by
// votes and not at the rest, so the answer says by how much its map leads
// them, and is sure only with a lead of two votes (the rule itself:
// LocalizerTest.AnAnswerIsNotSureWhereAMapNotLookedAtHasAsManyVotes). With
// two maps stored every map is looked at and the lead is absent.
TEST_F(RetrievalServiceTest, AGlobalAnswerSaysItsLeadOverTheMapsItDidNotLookAt) {
  v1::RetrieveResponse few;
  ASSERT_TRUE(server_->client().Retrieve(Query(CornerMap(1.0, 1.0)), &few).ok());
  ASSERT_GT(few.hits_size(), 0);
  EXPECT_FALSE(few.localization().has_vote_lead());

  v1::InsertMapsRequest insert;
  for (int i = 0; i < 70; ++i) {
    *insert.add_maps() = OneMapRequest("site", "copy" + std::to_string(i), CornerMap(0.1 * i, -0.1 * i)).maps(0);
  }
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server_->client().InsertMaps(insert, &inserted).ok());
  v1::RetrieveResponse many;
  ASSERT_TRUE(server_->client().Retrieve(Query(CornerMap(1.0, 1.0)), &many).ok());
  ASSERT_GT(many.hits_size(), 0);
  ASSERT_TRUE(many.localization().has_vote_lead());
  EXPECT_TRUE(!many.localization().localized() || many.localization().vote_lead() >= 2.0);
}

TEST_F(RetrievalServiceTest, TopKZeroMeansTheDefault) {
  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(Query(CornerMap(0, 0), 0), &response).ok());
  EXPECT_GE(response.hits_size(), 1);
  EXPECT_LE(response.hits_size(), 10);
}

// The paper's detector (descriptor masks) names a new object even where the
// stored map recorded no free space; the default method does not, since
// nothing shows that the space was empty before.
TEST_F(RetrievalServiceTest, PaperDetectorFindsAnAddedObject) {
  v1::LocalMap changed = CornerMap(0, 0);
  for (double x = 2.0; x <= 3.0; x += 0.05) {  // a 1 m x 0.6 m box in the corridor
    for (double y : {0.7, 1.3}) {
      changed.add_x(static_cast<float>(x));
      changed.add_y(static_cast<float>(y));
    }
  }
  v1::DetectChangesRequest request;
  request.set_collection("site");
  *request.mutable_map() = changed;
  request.set_top_k(1);
  v1::DetectChangesResponse response;
  ASSERT_TRUE(server_->client().DetectChanges(request, &response).ok());
  ASSERT_EQ(response.hits_size(), 1);
  EXPECT_EQ(response.hits(0).hit().map_id(), "corner");
  EXPECT_TRUE(response.localization().localized());
  EXPECT_EQ(response.hits(0).masks_size(), 0);  // one pose of trajectory: no free space recorded

  request.set_method(v1::METHOD_LMD_COG);
  ASSERT_TRUE(server_->client().DetectChanges(request, &response).ok());
  ASSERT_EQ(response.hits_size(), 1);
  EXPECT_EQ(response.hits(0).hit().map_id(), "corner");
  ASSERT_GE(response.hits(0).masks_size(), 1);
  EXPECT_EQ(response.hits(0).masks(0).source(), v1::MASK_SOURCE_DESCRIPTOR);
  const v1::ChangeMask& top = response.hits(0).masks(0);
  EXPECT_EQ(top.rank(), 1u);
  bool near_box = false;
  for (int i = 0; i < top.x_size(); ++i) near_box |= std::hypot(top.x(i) - 2.5, top.y(i) - 1.0) < 1.5;
  EXPECT_TRUE(near_box) << "top mask at (" << top.x(0) << ", " << top.y(0) << ")";

  request.set_threshold(-1);
  EXPECT_EQ(server_->client().DetectChanges(request, &response).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

// The corner map walked along its corridor: the trajectory gives free space.
v1::LocalMap WalkedCornerMap() {
  v1::LocalMap map = CornerMap(0, 0);
  map.clear_trajectory();
  for (double x = 0.5; x <= 7.0; x += 0.25) {
    v1::Pose2* pose = map.add_trajectory();
    pose->set_x(x);
    pose->set_y(1.0);
  }
  return map;
}

TEST_F(RetrievalServiceTest, DetectChangesNamesAnObjectInObservedFreeSpaceGeometrically) {
  v1::InsertMapsRequest insert = OneMapRequest("walked", "corner", WalkedCornerMap());
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server_->client().InsertMaps(insert, &inserted).ok());
  v1::DetectChangesRequest request;
  request.set_collection("walked");
  *request.mutable_map() = WalkedCornerMap();
  v1::DetectChangesResponse response;
  ASSERT_TRUE(server_->client().DetectChanges(request, &response).ok());
  ASSERT_EQ(response.hits_size(), 1);
  for (const auto& mask : response.hits(0).masks()) EXPECT_NE(mask.source(), v1::MASK_SOURCE_GEOMETRIC);

  v1::LocalMap changed = WalkedCornerMap();
  for (double x = 3.0; x <= 3.6; x += 0.05) {  // a box standing in the walked corridor
    for (double y : {0.8, 1.2}) {
      changed.add_x(static_cast<float>(x));
      changed.add_y(static_cast<float>(y));
    }
  }
  *request.mutable_map() = changed;
  ASSERT_TRUE(server_->client().DetectChanges(request, &response).ok());
  ASSERT_EQ(response.hits_size(), 1);
  ASSERT_GE(response.hits(0).masks_size(), 1);
  const v1::ChangeMask& top = response.hits(0).masks(0);
  EXPECT_EQ(top.rank(), 1u);
  EXPECT_EQ(top.source(), v1::MASK_SOURCE_GEOMETRIC);
  ASSERT_GE(top.x_size(), 3);
  for (int i = 0; i < top.x_size(); ++i) {
    EXPECT_LT(std::hypot(top.x(i) - 3.3, top.y(i) - 1.0), 0.6) << top.x(i) << ", " << top.y(i);
  }
  // Evidence (core/change/geometric_changes.h): each point weighted down by
  // its range from the robot's trajectory (here about 0.2 m), so below the count.
  EXPECT_GT(top.score(), 0.0);
  EXPECT_LT(top.score(), top.x_size());
}

}  // namespace
}  // namespace lmd::testing
