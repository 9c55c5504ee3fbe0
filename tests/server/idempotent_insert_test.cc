// Retried inserts: a request id lmdd has kept is answered again without
// storing its maps twice (InsertMapsRequest.request_id, and each message's
// InsertMapRequest.request_id in a stream).
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

v1::InsertMapsRequest WithRequestId(const std::string& request_id, int points, const std::string& map_id = "") {
  v1::InsertMapsRequest request = OneMapRequest("site", map_id, SquareRoomMap(points));
  request.set_request_id(request_id);
  return request;
}

uint64_t StoredMaps(const TestServer& server) {
  v1::ListCollectionsResponse collections;
  EXPECT_TRUE(server.client().ListCollections(&collections).ok());
  return collections.collections_size() == 0 ? 0 : collections.collections(0).maps();
}

class IdempotentInsertTest : public ::testing::Test {
 protected:
  TempDir dir_;
};

TEST_F(IdempotentInsertTest, ARepeatedRequestIdIsAnsweredAsTheFirstTimeAndStoresNothing) {
  TestServer server(dir_.path());
  ASSERT_TRUE(server.ok());
  v1::InsertMapsResponse first, again;
  ASSERT_TRUE(server.client().InsertMaps(WithRequestId("tick-1", 12), &first).ok());
  EXPECT_FALSE(first.replayed());
  ASSERT_TRUE(server.client().InsertMaps(WithRequestId("tick-1", 12), &again).ok());
  EXPECT_TRUE(again.replayed());
  ASSERT_EQ(again.maps_size(), 1);
  EXPECT_EQ(again.maps(0).map_id(), first.maps(0).map_id());
  EXPECT_EQ(again.maps(0).point_count(), 12u);
  EXPECT_EQ(StoredMaps(server), 1u);
  // Another id is another insert.
  ASSERT_TRUE(server.client().InsertMaps(WithRequestId("tick-2", 12), &again).ok());
  EXPECT_FALSE(again.replayed());
  EXPECT_NE(again.maps(0).map_id(), first.maps(0).map_id());
  EXPECT_EQ(StoredMaps(server), 2u);
}

TEST_F(IdempotentInsertTest, AKeptRequestIdSentWithOtherMapsIsRefused) {
  TestServer server(dir_.path());
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server.client().InsertMaps(WithRequestId("tick-1", 12), &inserted).ok());
  const grpc::Status reused = server.client().InsertMaps(WithRequestId("tick-1", 16), &inserted);
  EXPECT_EQ(reused.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(reused.error_message().find("tick-1"), std::string::npos) << reused.error_message();
  EXPECT_EQ(StoredMaps(server), 1u);
}

TEST_F(IdempotentInsertTest, KeptRequestIdsSurviveARestart) {
  std::string first_id;
  {
    TestServer server(dir_.path());
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(server.client().InsertMaps(WithRequestId("tick-1", 12), &inserted).ok());
    first_id = inserted.maps(0).map_id();
  }
  TestServer restarted(dir_.path());
  v1::InsertMapsResponse again;
  ASSERT_TRUE(restarted.client().InsertMaps(WithRequestId("tick-1", 12), &again).ok());
  EXPECT_TRUE(again.replayed());
  EXPECT_EQ(again.maps(0).map_id(), first_id);
  EXPECT_EQ(StoredMaps(restarted), 1u);
}

TEST_F(IdempotentInsertTest, OnlyTheNewestRequestIdsAreKept) {
  server::ServerConfig config;
  config.insert_request_ids_kept = 2;
  TestServer server(dir_.path(), config);
  v1::InsertMapsResponse inserted;
  for (const char* id : {"r1", "r2", "r3"}) ASSERT_TRUE(server.client().InsertMaps(WithRequestId(id, 12), &inserted).ok());
  ASSERT_TRUE(server.client().InsertMaps(WithRequestId("r3", 12), &inserted).ok());
  EXPECT_TRUE(inserted.replayed());
  ASSERT_TRUE(server.client().InsertMaps(WithRequestId("r1", 12), &inserted).ok());
  EXPECT_FALSE(inserted.replayed()) << "r1 is beyond the two newest: forgotten, so stored anew";
  EXPECT_EQ(StoredMaps(server), 4u);
}

TEST_F(IdempotentInsertTest, BadRequestIdsAreRefusedNamingTheField) {
  TestServer server(dir_.path());
  v1::InsertMapsResponse inserted;
  for (const std::string& id : {std::string("with space"), std::string(65, 'x'), std::string("tab\there")}) {
    const grpc::Status refused = server.client().InsertMaps(WithRequestId(id, 12), &inserted);
    EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << id;
    EXPECT_NE(refused.error_message().find("request_id"), std::string::npos) << refused.error_message();
  }
  v1::InsertMapsRequest two_collections = WithRequestId("tick-1", 12);
  *two_collections.add_maps() = OneMapRequest("other", "", SquareRoomMap(12)).maps(0);
  const grpc::Status mixed = server.client().InsertMaps(two_collections, &inserted);
  EXPECT_EQ(mixed.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(mixed.error_message().find("request_id"), std::string::npos) << mixed.error_message();
  EXPECT_EQ(StoredMaps(server), 0u);
}

// A stream sent again after it was cut off (its answer lost) stores each of
// its maps once: the messages lmdd kept are answered with the ids it gave
// them, the rest are stored.
TEST_F(IdempotentInsertTest, AStreamSentAgainStoresEachOfItsMapsOnce) {
  TestServer server(dir_.path());
  std::vector<v1::InsertMapRequest> stream;
  for (int i = 0; i < 3; ++i) {
    stream.push_back(OneMapRequest("site", "", SquareRoomMap(12 + i)).maps(0));
    stream.back().set_request_id("tick-" + std::to_string(i));
  }
  const std::vector<v1::InsertMapRequest> cut_off(stream.begin(), stream.begin() + 2);
  v1::InsertMapsResponse first, again;
  ASSERT_TRUE(server.client().StreamInsertMaps(cut_off, &first).ok());
  EXPECT_FALSE(first.replayed());
  ASSERT_EQ(first.maps_size(), 2);
  EXPECT_EQ(StoredMaps(server), 2u);
  ASSERT_TRUE(server.client().StreamInsertMaps(stream, &again).ok());
  EXPECT_TRUE(again.replayed());
  ASSERT_EQ(again.maps_size(), 3);
  EXPECT_EQ(again.maps(0).map_id(), first.maps(0).map_id());
  EXPECT_EQ(again.maps(1).map_id(), first.maps(1).map_id());
  EXPECT_EQ(again.maps(2).point_count(), 14u);
  EXPECT_EQ(StoredMaps(server), 3u);
}

TEST_F(IdempotentInsertTest, AMapsOwnRequestIdIsRefusedOutsideAStream) {
  TestServer server(dir_.path());
  v1::InsertMapsRequest request = OneMapRequest("site", "", SquareRoomMap(12));
  request.mutable_maps(0)->set_request_id("tick-1");
  v1::InsertMapsResponse inserted;
  const grpc::Status refused = server.client().InsertMaps(request, &inserted);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("maps[0].request_id"), std::string::npos) << refused.error_message();
  EXPECT_EQ(StoredMaps(server), 0u);
}

}  // namespace
}  // namespace lmd::testing
