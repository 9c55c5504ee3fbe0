// Storing maps through lmdd over gRPC: round trips, durability across a
// restart, and clear errors for bad input.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

class MapServiceTest : public ::testing::Test {
 protected:
  TempDir dir_;
};

TEST_F(MapServiceTest, InsertedMapReadsBackIdentically) {
  TestServer server(dir_.path());
  ASSERT_TRUE(server.ok());
  const v1::LocalMap map = SquareRoomMap();
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "m1", map), &inserted).ok());
  ASSERT_EQ(inserted.maps_size(), 1);
  EXPECT_EQ(inserted.maps(0).point_count(), 40u);

  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id("m1");
  v1::GetMapResponse got;
  ASSERT_TRUE(server.client().GetMap(get, &got).ok());
  EXPECT_EQ(got.map().map().SerializeAsString(), map.SerializeAsString());
  EXPECT_EQ(got.map().metadata().collection(), "site");
}

TEST_F(MapServiceTest, ServerAssignsIncreasingIdsWhenNoneGiven) {
  TestServer server(dir_.path());
  v1::InsertMapsRequest request = OneMapRequest("site", "", SquareRoomMap());
  *request.add_maps() = request.maps(0);
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server.client().InsertMaps(request, &inserted).ok());
  ASSERT_EQ(inserted.maps_size(), 2);
  EXPECT_FALSE(inserted.maps(0).map_id().empty());
  EXPECT_LT(inserted.maps(0).map_id(), inserted.maps(1).map_id());
}

TEST_F(MapServiceTest, AnAssignedIdNeverReplacesAMapItsClientNamed) {
  TestServer server(dir_.path());
  v1::InsertMapsResponse inserted;
  // A client picks the id lmdd would assign first, then sends a map without id.
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "m000000000001", SquareRoomMap(12)), &inserted).ok());
  v1::InsertMapsRequest unnamed = OneMapRequest("site", "", SquareRoomMap(16));
  // ... and in one batch, an unnamed map before a named one that takes the next id.
  *unnamed.add_maps() = OneMapRequest("site", "m000000000003", SquareRoomMap(20)).maps(0);
  ASSERT_TRUE(server.client().InsertMaps(unnamed, &inserted).ok());
  ASSERT_EQ(inserted.maps_size(), 2);
  EXPECT_NE(inserted.maps(0).map_id(), "m000000000001");
  EXPECT_NE(inserted.maps(0).map_id(), "m000000000003");
  v1::ListMapsRequest list;
  list.set_collection("site");
  v1::ListMapsResponse listed;
  ASSERT_TRUE(server.client().ListMaps(list, &listed).ok());
  ASSERT_EQ(listed.maps_size(), 3);
  for (const auto& meta : listed.maps()) {
    if (meta.map_id() == "m000000000001") {
      EXPECT_EQ(meta.point_count(), 12u);
    }
  }
}

TEST_F(MapServiceTest, ABatchNamingOneMapTwiceIsRefusedAndStoresNothing) {
  TestServer server(dir_.path());
  v1::InsertMapsRequest request = OneMapRequest("site", "a", SquareRoomMap(12));
  *request.add_maps() = OneMapRequest("site", "b", SquareRoomMap(16)).maps(0);
  *request.add_maps() = OneMapRequest("site", "a", SquareRoomMap(20)).maps(0);
  *request.add_maps() = OneMapRequest("other", "b", SquareRoomMap(20)).maps(0);  // another collection: fine
  v1::InsertMapsResponse inserted;
  const grpc::Status status = server.client().InsertMaps(request, &inserted);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("maps[0] and maps[2] have the same id 'a'"), std::string::npos)
      << status.error_message();
  v1::ListCollectionsResponse collections;
  ASSERT_TRUE(server.client().ListCollections(&collections).ok());
  EXPECT_EQ(collections.collections_size(), 0);
}

std::vector<std::string> ListedIds(const TestServer& server, const std::string& collection) {
  v1::ListMapsRequest list;
  list.set_collection(collection);
  v1::ListMapsResponse listed;
  EXPECT_TRUE(server.client().ListMaps(list, &listed).ok());
  std::vector<std::string> ids;
  for (const auto& meta : listed.maps()) ids.push_back(meta.map_id());
  return ids;
}

TEST_F(MapServiceTest, ACappedCollectionEvictsItsOldestMapsAndSaysWhich) {
  server::ServerConfig config;
  config.retain_maps_per_collection = 3;
  {
    TestServer server(dir_.path(), config);
    v1::InsertMapsResponse inserted;
    for (const char* id : {"d", "c", "b"}) {  // insertion order, not id order, decides
      ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", id, SquareRoomMap()), &inserted).ok());
      EXPECT_EQ(inserted.evicted_size(), 0);
    }
    // Replacing a kept map adds none, so evicts none.
    ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "c", SquareRoomMap(24)), &inserted).ok());
    EXPECT_EQ(inserted.evicted_size(), 0);
    v1::InsertMapsRequest two = OneMapRequest("site", "a", SquareRoomMap());
    *two.add_maps() = OneMapRequest("site", "e", SquareRoomMap()).maps(0);
    ASSERT_TRUE(server.client().InsertMaps(two, &inserted).ok());
    ASSERT_EQ(inserted.evicted_size(), 2);
    EXPECT_EQ(inserted.evicted(0).map_id(), "d");  // the oldest
    EXPECT_EQ(inserted.evicted(1).map_id(), "b");  // "c" was rewritten after "b"
    EXPECT_EQ(ListedIds(server, "site"), (std::vector<std::string>{"a", "c", "e"}));

    v1::RetrieveRequest query;
    query.set_collection("site");
    *query.mutable_map() = SquareRoomMap();
    query.set_top_k(10);
    v1::RetrieveResponse found;
    ASSERT_TRUE(server.client().Retrieve(query, &found).ok());
    for (const auto& hit : found.hits()) EXPECT_TRUE(hit.map_id() != "d" && hit.map_id() != "b") << hit.map_id();

    // A batch that rewrites the oldest map keeps it (it is now the newest)
    // and evicts the next oldest.
    v1::InsertMapsRequest rewrite = OneMapRequest("site", "c", SquareRoomMap(28));
    *rewrite.add_maps() = OneMapRequest("site", "f", SquareRoomMap()).maps(0);
    ASSERT_TRUE(server.client().InsertMaps(rewrite, &inserted).ok());
    ASSERT_EQ(inserted.evicted_size(), 1);
    EXPECT_EQ(inserted.evicted(0).map_id(), "a");
    EXPECT_EQ(ListedIds(server, "site"), (std::vector<std::string>{"c", "e", "f"}));

    // A batch that alone exceeds the cap is refused whole.
    v1::InsertMapsRequest four = OneMapRequest("site", "f", SquareRoomMap());
    for (const char* id : {"g", "h", "i"}) *four.add_maps() = OneMapRequest("site", id, SquareRoomMap()).maps(0);
    const grpc::Status refused = server.client().InsertMaps(four, &inserted);
    EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_NE(refused.error_message().find("retain_maps_per_collection (3)"), std::string::npos)
        << refused.error_message();
    EXPECT_EQ(ListedIds(server, "site"), (std::vector<std::string>{"c", "e", "f"}));
  }
  // The counters and the index agree with the maps after a restart.
  TestServer reopened(dir_.path(), config);
  ASSERT_TRUE(reopened.ok());
  EXPECT_EQ(ListedIds(reopened, "site"), (std::vector<std::string>{"c", "e", "f"}));
}

TEST_F(MapServiceTest, ALoweredCapIsReachedOverSeveralInserts) {
  std::string newest_eight_first;  // the id of the 293rd of the first 300 maps
  {
    TestServer uncapped(dir_.path());
    v1::InsertMapsRequest many;
    for (int i = 0; i < 300; ++i) *many.add_maps() = OneMapRequest("site", "", SquareRoomMap(8)).maps(0);
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(uncapped.client().InsertMaps(many, &inserted).ok());
    ASSERT_EQ(inserted.maps_size(), 300);
    newest_eight_first = inserted.maps(292).map_id();
  }
  server::ServerConfig config;
  config.retain_maps_per_collection = 10;
  TestServer capped(dir_.path(), config);
  v1::InsertMapsResponse inserted;
  // At most 256 evictions beyond the insert's own map per write.
  ASSERT_TRUE(capped.client().InsertMaps(OneMapRequest("site", "new1", SquareRoomMap(8)), &inserted).ok());
  EXPECT_EQ(inserted.evicted_size(), 257);
  EXPECT_EQ(ListedIds(capped, "site").size(), 44u);
  ASSERT_TRUE(capped.client().InsertMaps(OneMapRequest("site", "new2", SquareRoomMap(8)), &inserted).ok());
  EXPECT_EQ(inserted.evicted_size(), 35);
  const std::vector<std::string> kept = ListedIds(capped, "site");
  ASSERT_EQ(kept.size(), 10u);
  EXPECT_EQ(kept.back(), "new2");
  EXPECT_EQ(kept.front(), newest_eight_first);  // the newest 8 of the first 300, then new1 and new2
}

TEST_F(MapServiceTest, MapsSurviveARestartOnTheSameDataDirectory) {
  {
    TestServer server(dir_.path());
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "kept", SquareRoomMap(12)), &inserted).ok());
  }
  TestServer restarted(dir_.path());
  ASSERT_TRUE(restarted.ok());
  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id("kept");
  v1::GetMapResponse got;
  ASSERT_TRUE(restarted.client().GetMap(get, &got).ok());
  EXPECT_EQ(got.map().map().x_size(), 12);
  v1::ListCollectionsResponse collections;
  ASSERT_TRUE(restarted.client().ListCollections(&collections).ok());
  ASSERT_EQ(collections.collections_size(), 1);
  EXPECT_EQ(collections.collections(0).maps(), 1u);
  EXPECT_EQ(collections.collections(0).points(), 12u);
}

TEST_F(MapServiceTest, AStoreWithInnerWordsSurvivesARestart) {
  server::ServerConfig config;
  config.inner_words = true;  // two postings per feature: the recovery check must count both
  {
    TestServer server(dir_.path(), config);
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "a", SquareRoomMap(60)), &inserted).ok());
    ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "a", SquareRoomMap(80)), &inserted).ok());  // replaced
  }
  TestServer restarted(dir_.path(), config);
  ASSERT_TRUE(restarted.ok());
  v1::ListCollectionsResponse collections;
  ASSERT_TRUE(restarted.client().ListCollections(&collections).ok());
  ASSERT_EQ(collections.collections_size(), 1);
  EXPECT_EQ(collections.collections(0).maps(), 1u);
  EXPECT_GT(collections.collections(0).postings(), 0u);
}

TEST_F(MapServiceTest, ReplacingAMapKeepsCountsRight) {
  TestServer server(dir_.path());
  v1::InsertMapsResponse ignored;
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "a", SquareRoomMap(10)), &ignored).ok());
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "a", SquareRoomMap(30)), &ignored).ok());
  v1::ListCollectionsResponse collections;
  ASSERT_TRUE(server.client().ListCollections(&collections).ok());
  EXPECT_EQ(collections.collections(0).maps(), 1u);
  EXPECT_EQ(collections.collections(0).points(), 30u);
}

TEST_F(MapServiceTest, DeleteRemovesTheMapAndItsCount) {
  TestServer server(dir_.path());
  v1::InsertMapsResponse ignored;
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &ignored).ok());
  v1::DeleteMapRequest del;
  del.set_collection("site");
  del.set_map_id("a");
  ASSERT_TRUE(server.client().DeleteMap(del).ok());
  EXPECT_EQ(server.client().DeleteMap(del).error_code(), grpc::StatusCode::NOT_FOUND);
  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id("a");
  v1::GetMapResponse got;
  EXPECT_EQ(server.client().GetMap(get, &got).error_code(), grpc::StatusCode::NOT_FOUND);
  v1::ListCollectionsResponse collections;
  ASSERT_TRUE(server.client().ListCollections(&collections).ok());
  EXPECT_EQ(collections.collections(0).maps(), 0u);
}

TEST_F(MapServiceTest, ListMapsPagesThroughEveryMapInIdOrder) {
  TestServer server(dir_.path());
  v1::InsertMapsRequest request;
  for (int i = 0; i < 25; ++i) {
    *request.add_maps() = OneMapRequest("site", "map-" + std::to_string(100 + i), SquareRoomMap(8)).maps(0);
  }
  v1::InsertMapsResponse ignored;
  ASSERT_TRUE(server.client().InsertMaps(request, &ignored).ok());
  v1::ListMapsRequest list;
  list.set_collection("site");
  list.set_page_size(10);
  std::vector<std::string> ids;
  int pages = 0;
  do {
    v1::ListMapsResponse page;
    ASSERT_TRUE(server.client().ListMaps(list, &page).ok());
    for (const auto& meta : page.maps()) ids.push_back(meta.map_id());
    list.set_page_token(page.next_page_token());
    ++pages;
  } while (!list.page_token().empty() && pages < 10);
  ASSERT_EQ(ids.size(), 25u);
  EXPECT_EQ(pages, 3);
  EXPECT_TRUE(std::is_sorted(ids.begin(), ids.end()));
  EXPECT_EQ(ids.front(), "map-100");
}

TEST_F(MapServiceTest, ABadPageTokenIsNamedAsSuch) {
  TestServer server(dir_.path());
  v1::InsertMapsResponse ignored;
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &ignored).ok());
  v1::ListMapsRequest list;
  list.set_collection("site");
  list.set_page_token("!!garbage");
  v1::ListMapsResponse page;
  const grpc::Status status = server.client().ListMaps(list, &page);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message().rfind("page_token '!!garbage' is not a next_page_token of ListMaps", 0), 0u)
      << status.error_message();
}

TEST_F(MapServiceTest, AFailedStreamSaysWhichOfItsMapsAreStored) {
  TestServer server(dir_.path());
  std::vector<v1::InsertMapRequest> requests;
  for (int i = 0; i < 4; ++i) requests.push_back(OneMapRequest("fleet", "s" + std::to_string(i), SquareRoomMap()).maps(0));
  requests[2].mutable_map()->clear_x();  // the third map is bad
  v1::InsertMapsResponse response;
  const grpc::Status status = server.client().StreamInsertMaps(requests, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("first 2 maps are stored"), std::string::npos) << status.error_message();
  ASSERT_EQ(response.maps_size(), 2);
  EXPECT_EQ(response.maps(1).map_id(), "s1");
  v1::GetMapRequest get;
  get.set_collection("fleet");
  get.set_map_id("s1");
  v1::GetMapResponse got;
  EXPECT_TRUE(server.client().GetMap(get, &got).ok());
  get.set_map_id("s3");
  EXPECT_EQ(server.client().GetMap(get, &got).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(MapServiceTest, StreamInsertAcknowledgesEveryMapInOrder) {
  TestServer server(dir_.path());
  std::vector<v1::InsertMapRequest> requests;
  for (int i = 0; i < 5; ++i) requests.push_back(OneMapRequest("fleet", "s" + std::to_string(i), SquareRoomMap()).maps(0));
  v1::InsertMapsResponse response;
  ASSERT_TRUE(server.client().StreamInsertMaps(requests, &response).ok());
  ASSERT_EQ(response.maps_size(), 5);
  EXPECT_EQ(response.maps(4).map_id(), "s4");
}

// --- bad input -------------------------------------------------------------

grpc::Status InsertOne(const TestServer& server, const v1::LocalMap& map, const std::string& collection = "site") {
  v1::InsertMapsResponse ignored;
  return server.client().InsertMaps(OneMapRequest(collection, "bad", map), &ignored);
}

TEST_F(MapServiceTest, EmptyMapIsRejectedWithAMessage) {
  TestServer server(dir_.path());
  const grpc::Status status = InsertOne(server, v1::LocalMap());
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("no points"), std::string::npos) << status.error_message();
}

TEST_F(MapServiceTest, NanAndInfiniteCoordinatesAreRejectedNamingThePoint) {
  TestServer server(dir_.path());
  v1::LocalMap nan_map = SquareRoomMap();
  nan_map.set_x(7, std::numeric_limits<float>::quiet_NaN());
  grpc::Status status = InsertOne(server, nan_map);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("point 7 x is NaN"), std::string::npos) << status.error_message();

  v1::LocalMap inf_map = SquareRoomMap();
  inf_map.set_y(3, std::numeric_limits<float>::infinity());
  status = InsertOne(server, inf_map);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("point 3 y is infinite"), std::string::npos) << status.error_message();
}

// A stated odometry drift is stored with the map; one that is not a
// number from 0 to 0.5 rad per metre is refused, and nothing is stored.
TEST_F(MapServiceTest, AMapsOdometryDriftIsKeptOrRefusedNamingIt) {
  TestServer server(dir_.path());
  ASSERT_TRUE(server.ok());
  v1::LocalMap drifting = SquareRoomMap();
  drifting.set_heading_drift_rad_per_m(0.01);
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "m1", drifting), &inserted).ok());
  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id("m1");
  v1::GetMapResponse got;
  ASSERT_TRUE(server.client().GetMap(get, &got).ok());
  EXPECT_EQ(got.map().map().heading_drift_rad_per_m(), 0.01);

  for (double bad : {-0.01, 0.6, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    v1::LocalMap map = SquareRoomMap();
    map.set_heading_drift_rad_per_m(bad);
    grpc::Status status = InsertOne(server, map);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
    EXPECT_NE(status.error_message().find("heading_drift_rad_per_m must be a number from 0 to 0.5"), std::string::npos)
        << status.error_message();
    v1::RetrieveRequest query;  // a query map alike
    query.set_collection("site");
    *query.mutable_map() = map;
    v1::RetrieveResponse answer;
    status = server.client().Retrieve(query, &answer);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
    EXPECT_NE(status.error_message().find("query map: heading_drift_rad_per_m"), std::string::npos)
        << status.error_message();
  }
  // A bend needs the path it bends along.
  v1::LocalMap points_only = SquareRoomMap();
  points_only.clear_trajectory();
  points_only.set_heading_drift_rad_per_m(0.01);
  const grpc::Status no_path = InsertOne(server, points_only);
  EXPECT_EQ(no_path.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(no_path.error_message().find("needs the map's trajectory or scans"), std::string::npos)
      << no_path.error_message();
  v1::ListMapsRequest list;
  list.set_collection("site");
  v1::ListMapsResponse listed;
  ASSERT_TRUE(server.client().ListMaps(list, &listed).ok());
  EXPECT_EQ(listed.maps_size(), 1);
}

TEST_F(MapServiceTest, BadPosesAndFarCoordinatesAreRejectedNamingTheValue) {
  TestServer server(dir_.path());
  v1::LocalMap far_map = SquareRoomMap();
  far_map.set_x(2, 1.0e6f);  // mm sent as m
  grpc::Status status = InsertOne(server, far_map);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("point 2 x = "), std::string::npos) << status.error_message();
  EXPECT_NE(status.error_message().find("max_abs_coordinate_m"), std::string::npos) << status.error_message();

  v1::LocalMap bad_trajectory = SquareRoomMap();
  const std::string bad_pose = "trajectory pose " + std::to_string(bad_trajectory.trajectory_size() + 1);
  bad_trajectory.add_trajectory()->set_x(1.0);
  bad_trajectory.add_trajectory()->set_theta(std::numeric_limits<double>::quiet_NaN());
  status = InsertOne(server, bad_trajectory);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find(bad_pose + ".theta is not finite"), std::string::npos)
      << status.error_message();

  v1::LocalMap bad_scan = SquareRoomMap();
  v1::Scan* scan = bad_scan.add_scans();
  scan->set_angle_step(0.01);
  scan->set_max_range(10.0);
  scan->mutable_pose()->set_y(std::numeric_limits<double>::infinity());
  status = InsertOne(server, bad_scan);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("scan 0 pose.y is infinite"), std::string::npos) << status.error_message();
}

TEST_F(MapServiceTest, MapsWiderThanTheExtentLimitAreRejectedNamingIt) {
  TestServer server(dir_.path());
  v1::LocalMap wide = SquareRoomMap();
  wide.set_x(0, -1000.0f);  // 1 km and a few metres across: beyond the index's pose words' reach
  wide.set_x(1, 30.0f);
  grpc::Status status = InsertOne(server, wide);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("max_map_extent_m"), std::string::npos) << status.error_message();

  v1::LocalMap far_laser = SquareRoomMap();
  v1::Scan* scan = far_laser.add_scans();
  scan->set_angle_step(0.01);
  scan->set_max_range(3e38f);
  scan->add_ranges(1e30f);
  status = InsertOne(server, far_laser);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("scan 0: max_range"), std::string::npos) << status.error_message();
}

TEST_F(MapServiceTest, MismatchedArraysAndBadNamesAreRejected) {
  TestServer server(dir_.path());
  v1::LocalMap uneven = SquareRoomMap();
  uneven.add_x(1.0f);
  EXPECT_EQ(InsertOne(server, uneven).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(InsertOne(server, SquareRoomMap(), "bad/name").error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(InsertOne(server, SquareRoomMap(), "").error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(InsertOne(server, SquareRoomMap(), "..").error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  // A client's bytes are escaped in messages (and so in lmdd's log lines).
  v1::InsertMapsResponse ignored;
  const grpc::Status status =
      server.client().InsertMaps(OneMapRequest("site", "a\nFORGED [error] line", SquareRoomMap()), &ignored);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message().find('\n'), std::string::npos) << status.error_message();
  EXPECT_NE(status.error_message().find("'a\\x0aFORGED"), std::string::npos) << status.error_message();
}

TEST_F(MapServiceTest, ASecondLmddCannotTakeAPortInUse) {
  TestServer first(dir_.path());
  ASSERT_TRUE(first.ok());
  TempDir other;
  server::ServerConfig config;
  config.listen = first.address();
  config.data_dir = other.path();
  auto second = server::LmdServer::Start(config);
  ASSERT_FALSE(second.ok()) << "two lmdd served " << first.address();
  // gRPC logs why (a dump of its errors) but does not return it; lmdd's own line says it.
  EXPECT_EQ(second.status().message(), "cannot listen on " + first.address() + ": Address already in use");
}

TEST_F(MapServiceTest, ABadMapInABatchStoresNothing) {
  TestServer server(dir_.path());
  v1::InsertMapsRequest request = OneMapRequest("site", "good", SquareRoomMap());
  v1::LocalMap bad = SquareRoomMap();
  bad.set_x(0, std::numeric_limits<float>::quiet_NaN());
  *request.add_maps() = OneMapRequest("site", "bad", bad).maps(0);
  v1::InsertMapsResponse ignored;
  const grpc::Status status = server.client().InsertMaps(request, &ignored);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("map 1 ('bad')"), std::string::npos) << status.error_message();
  v1::ListCollectionsResponse collections;
  ASSERT_TRUE(server.client().ListCollections(&collections).ok());
  EXPECT_EQ(collections.collections_size(), 0);
}

TEST_F(MapServiceTest, UnknownCollectionAndMapAreNotFound) {
  TestServer server(dir_.path());
  v1::GetMapRequest get;
  get.set_collection("nowhere");
  get.set_map_id("m1");
  v1::GetMapResponse got;
  grpc::Status status = server.client().GetMap(get, &got);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(status.error_message().find("unknown collection 'nowhere'"), std::string::npos);

  v1::InsertMapsResponse ignored;
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "m1", SquareRoomMap()), &ignored).ok());
  get.set_collection("site");
  get.set_map_id("m2");
  status = server.client().GetMap(get, &got);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(status.error_message().find("no map 'm2'"), std::string::npos);

  v1::ListMapsRequest list;
  list.set_collection("nowhere");
  v1::ListMapsResponse listed;
  EXPECT_EQ(server.client().ListMaps(list, &listed).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(MapServiceTest, MessageOverTheSizeLimitIsResourceExhausted) {
  server::ServerConfig config;
  config.max_message_bytes = 64 * 1024;
  TestServer server(dir_.path(), config);
  const grpc::Status status = InsertOne(server, SquareRoomMap(20000));  // ~160 KB of points
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_FALSE(status.error_message().empty());
}

TEST_F(MapServiceTest, LimitsOnPointsAndBatchSizeNameTheLimit) {
  server::ServerConfig config;
  config.max_points_per_map = 30;
  config.max_maps_per_batch = 2;
  TestServer server(dir_.path(), config);
  grpc::Status status = InsertOne(server, SquareRoomMap(31));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("max_points_per_map"), std::string::npos);

  v1::InsertMapsRequest request = OneMapRequest("site", "", SquareRoomMap(8));
  *request.add_maps() = request.maps(0);
  *request.add_maps() = request.maps(0);
  v1::InsertMapsResponse ignored;
  status = server.client().InsertMaps(request, &ignored);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("max_maps_per_batch"), std::string::npos);
}

TEST_F(MapServiceTest, RemoteAddressWithoutSecurityIsRefused) {
  server::ServerConfig config;
  config.listen = "0.0.0.0:0";
  config.data_dir = dir_.path();
  auto started = server::LmdServer::Start(config);
  ASSERT_FALSE(started.ok());
  EXPECT_NE(started.status().message().find("allow_insecure_remote"), std::string::npos);
  config.listen = "garbage";
  started = server::LmdServer::Start(config);
  ASSERT_FALSE(started.ok());
  EXPECT_NE(started.status().message().find("is not HOST:PORT"), std::string::npos) << started.status().message();
}

// gRPC would serve on port 99999 modulo 65536 (34463), and on 65536 on a random port.
TEST_F(MapServiceTest, AListenPortOutOfRangeIsRefused) {
  server::ServerConfig config;
  config.data_dir = dir_.path();
  for (const std::string port : {"99999", "65536"}) {
    config.listen = "127.0.0.1:" + port;
    auto started = server::LmdServer::Start(config);
    ASSERT_FALSE(started.ok()) << port;
    EXPECT_EQ(started.status().message(),
              "listen address '127.0.0.1:" + port + "': port " + port + " is not from 0 to 65535");
  }
}

}  // namespace
}  // namespace lmd::testing
