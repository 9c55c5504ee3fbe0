// MapStore::DropCollection: a collection deleted whole, in one write, its
// neighbours by name untouched, and a collection of that name created again
// numbering its maps after the dropped ones.
#include <gtest/gtest.h>

#include "tests/server/store_fixture.h"

namespace lmd::testing {
namespace {

std::string InsertOne(server::MapStore* store, const std::string& collection, int points) {
  std::vector<server::MapWrite> maps = OneWrite(*store, points, collection);
  const Status inserted = store->InsertMaps(&maps, server::InsertLimits{});
  EXPECT_TRUE(inserted.ok()) << inserted.ToString();
  return maps[0].map.metadata().map_id();
}

std::vector<std::string> Names(const server::MapStore& store) {
  std::vector<std::string> names;
  for (const v1::CollectionInfo& info : store.ListCollections()) names.push_back(info.name());
  return names;
}

TEST(DropCollectionTest, DeletesOneCollectionWholeAndNothingElse) {
  TempDir dir;
  auto store = OpenStore(dir);
  const server::InsertRequestId request{"tick-1", 7};
  std::vector<server::MapWrite> maps = OneWrite(*store, 12, "a");
  ASSERT_TRUE(store->InsertMaps(&maps, server::InsertLimits{}, nullptr, nullptr, &request).ok());
  InsertOne(store.get(), "a", 16);
  // Names that sort next to "a/" keys: "a-b/..." and "a.b/..." before, "a0/..." after.
  const std::string neighbour_before = InsertOne(store.get(), "a.b", 12);
  const std::string neighbour_dash = InsertOne(store.get(), "a-b", 16);
  const std::string neighbour_after = InsertOne(store.get(), "a0", 20);

  ASSERT_TRUE(store->DropCollection("a").ok());
  EXPECT_FALSE(store->HasCollection("a"));
  EXPECT_EQ(Names(*store), (std::vector<std::string>{"a-b", "a.b", "a0"}));
  EXPECT_EQ(store->GetMap("a", "m000000000000").status().code(), Status::Code::kNotFound);
  EXPECT_EQ(store->DropCollection("a").code(), Status::Code::kNotFound);
  EXPECT_TRUE(store->GetMap("a.b", neighbour_before).ok());
  EXPECT_TRUE(store->GetMap("a-b", neighbour_dash).ok());
  EXPECT_TRUE(store->GetMap("a0", neighbour_after).ok());

  // Created again: its kept request ids went with it, and its index ids
  // follow the dropped collection's two.
  maps = OneWrite(*store, 20, "a");
  bool replayed = true;
  ASSERT_TRUE(store->InsertMaps(&maps, server::InsertLimits{}, nullptr, nullptr, &request, &replayed).ok());
  EXPECT_FALSE(replayed);
  EXPECT_EQ(store->Indexed("a", 0).status().code(), Status::Code::kNotFound);
  EXPECT_EQ(store->Indexed("a", 1).status().code(), Status::Code::kNotFound);
  EXPECT_TRUE(store->Indexed("a", 2).ok());
  ASSERT_EQ(store->ListCollections().front().name(), "a");
  EXPECT_EQ(store->ListCollections().front().maps(), 1u);
  ASSERT_TRUE(store->Close().ok());

  // Reopened: the store checks every collection's counters against its
  // records (a partial drop would fail here).
  auto reopened = OpenStore(dir);
  EXPECT_EQ(Names(*reopened), (std::vector<std::string>{"a", "a-b", "a.b", "a0"}));
  EXPECT_TRUE(reopened->Close().ok());
}

}  // namespace
}  // namespace lmd::testing
