// HitVerifier's cache of prepared db maps: a hit's prepared map is reused
// while it fits the byte budget and rebuilt once it was evicted; a query's
// prepared map is reused when a stored map has the same content.
#include "server/hit_verifier.h"

#include <map>

#include <gtest/gtest.h>

#include "proto/convert.h"
#include "server/indexing.h"
#include "tests/server/test_server.h"

namespace lmd::server {
namespace {

class HitVerifierTest : public ::testing::Test {
 protected:
  void SetUp() override {
    MapStoreOptions options;
    options.data_dir = dir_.path() + "/store";
    Result<std::unique_ptr<MapStore>> store = MapStore::Open(options);
    ASSERT_TRUE(store.ok()) << store.status().ToString();
    store_ = std::move(store).value();
    indexing_ = options.indexing;
    query_ = FromProto(testing::SquareRoomMap(200));
    query_key_ = DescriptorCache::KeyOf(testing::SquareRoomMap(200).SerializeAsString());
    query_lmd_ = DescribeForIndex(query_, indexing_);
    std::vector<MapWrite> writes;
    for (const char* id : {"a", "b"}) {  // two stored copies of the query's room
      MapWrite write;
      write.map.mutable_metadata()->set_collection("c");
      write.map.mutable_metadata()->set_map_id(id);
      *write.map.mutable_map() = testing::SquareRoomMap(200);
      write.lmd = query_lmd_;
      writes.push_back(std::move(write));
    }
    ASSERT_TRUE(store_->InsertMaps(&writes, server::InsertLimits()).ok());
    RetrieveOptions retrieve;
    retrieve.top_k = 2;
    Result<std::vector<StoreHit>> hits = store_->Retrieve("c", query_lmd_, retrieve);
    ASSERT_TRUE(hits.ok());
    ASSERT_EQ(hits->size(), 2u);
    hits_ = std::move(hits).value();
  }

  void TearDown() override { ASSERT_TRUE(store_->Close().ok()); }

  // The prepared map each verified hit was matched against, by map id.
  std::map<std::string, std::shared_ptr<const PreparedMap>> Verify(HitVerifier* verifier,
                                                                   double reverse_conflict_weight = 0.0) {
    Result<std::vector<VerifiedStoreHit>> verified =
        verifier->Verify("c", query_, query_key_, query_lmd_, hits_, 2, 0, reverse_conflict_weight, {});
    EXPECT_TRUE(verified.ok());
    std::map<std::string, std::shared_ptr<const PreparedMap>> out;
    for (const VerifiedStoreHit& hit : *verified) {
      EXPECT_TRUE(hit.verified) << hit.hit.map_id;
      out[hit.hit.map_id] = hit.prepared;
    }
    return out;
  }

  testing::TempDir dir_;
  std::unique_ptr<MapStore> store_;
  IndexingConfig indexing_;
  LocalMap query_;
  DescriptorCache::Key query_key_;
  Lmd query_lmd_;
  std::vector<StoreHit> hits_;
};

TEST_F(HitVerifierTest, CacheKeepsPreparedMapsWithinItsByteBudget) {
  HitVerifier roomy(store_.get(), size_t{64} << 20);
  auto first = Verify(&roomy);
  auto second = Verify(&roomy);
  ASSERT_EQ(first.size(), 2u);
  EXPECT_EQ(first["a"], second["a"]);  // both kept: the same prepared maps
  EXPECT_EQ(first["b"], second["b"]);

  HitVerifier none(store_.get(), 0);
  EXPECT_NE(Verify(&none)["a"], Verify(&none)["a"]);  // nothing kept

  // Room for one map: each verification evicts the other map (least recently
  // used), so both are rebuilt the second time.
  const size_t one_map = first["a"]->MemoryBytes();
  HitVerifier tight(store_.get(), one_map + one_map / 2);
  first = Verify(&tight);
  second = Verify(&tight);
  EXPECT_NE(first["a"], second["a"]);
  EXPECT_NE(first["b"], second["b"]);
}

TEST_F(HitVerifierTest, AQueryPreparedForReverseConflictsIsReusedForAStoredMapOfTheSameContent) {
  HitVerifier verifier(store_.get(), size_t{64} << 20);
  Verify(&verifier, 0.5);
  // The query, then "a" and "b" (stored copies of the query's bytes): the
  // first of them takes the query's preparation, the second is built.
  EXPECT_EQ(verifier.maps_prepared(), 2u);
  Verify(&verifier, 0.5);  // the query is prepared again, the hits are cached
  EXPECT_EQ(verifier.maps_prepared(), 3u);

  HitVerifier no_reverse(store_.get(), size_t{64} << 20);
  Verify(&no_reverse);
  EXPECT_EQ(no_reverse.maps_prepared(), 2u);  // no query preparation
}

TEST_F(HitVerifierTest, ACancelledCallStopsBeforeTheNextScanMatch) {
  HitVerifier verifier(store_.get(), size_t{64} << 20);
  int asked = 0;
  // Cancelled after the first hit's match: the second is never prepared.
  Result<std::vector<VerifiedStoreHit>> verified =
      verifier.Verify("c", query_, query_key_, query_lmd_, hits_, 2, 0, 0.0, [&asked] { return ++asked > 1; });
  EXPECT_EQ(verified.status().code(), Status::Code::kCancelled);
  EXPECT_EQ(verifier.maps_prepared(), 1u);
}

}  // namespace
}  // namespace lmd::server
