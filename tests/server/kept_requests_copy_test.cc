// A whole copy of a collection (a replica catching up from scratch) carries
// the insert request ids its source keeps: after a failover to that copy, a
// retried insert is still answered once.
#include <gtest/gtest.h>

#include "tests/server/store_fixture.h"

namespace lmd::testing {
namespace {

TEST(KeptRequestsCopyTest, ACopyKeepsItsSourcesRequestIdsAndForgetsItsOwn) {
  TempDir source_dir, copy_dir;
  auto source = OpenStore(source_dir);
  auto copy = OpenStore(copy_dir);
  const server::InsertLimits limits;
  const server::InsertRequestId first{"tick-1", 11}, second{"tick-2", 22}, stale{"never-acknowledged", 33};
  std::vector<server::MapWrite> maps = OneWrite(*source, 12);
  ASSERT_TRUE(source->InsertMaps(&maps, limits, nullptr, nullptr, &first).ok());
  const std::string first_id = maps[0].map.metadata().map_id();
  maps = OneWrite(*source, 16);
  ASSERT_TRUE(source->InsertMaps(&maps, limits, nullptr, nullptr, &second).ok());
  maps = OneWrite(*copy, 20);  // what the copy held before: replaced by the source's
  ASSERT_TRUE(copy->InsertMaps(&maps, limits, nullptr, nullptr, &stale).ok());

  std::vector<server::KeptRequest> requests;
  server::ReplicationMark mark;
  ASSERT_TRUE(source
                  ->ForEachMap(
                      "site", 1, [](std::vector<server::StoredEntry>&&) { return true; },
                      [&](std::vector<server::KeptRequest>&& chunk) {
                        for (auto& r : chunk) requests.push_back(std::move(r));
                        return true;
                      },
                      &mark)
                  .ok());
  ASSERT_EQ(requests.size(), 2u);
  EXPECT_EQ(requests[0].id, "tick-1");  // oldest first
  ASSERT_TRUE(copy->SetMark("site", {1, 2}, &requests).ok());

  bool replayed = false;
  maps = OneWrite(*copy, 12);
  ASSERT_TRUE(copy->InsertMaps(&maps, limits, nullptr, nullptr, &first, &replayed).ok());
  EXPECT_TRUE(replayed);
  EXPECT_EQ(maps[0].map.metadata().map_id(), first_id);
  maps = OneWrite(*copy, 20);
  ASSERT_TRUE(copy->InsertMaps(&maps, limits, nullptr, nullptr, &stale, &replayed).ok());
  EXPECT_FALSE(replayed) << "the copy's own kept id was not its source's: forgotten";
  // The copy numbers its next kept ids after the source's, and forgets the oldest first.
  server::InsertLimits keep_two = limits;
  keep_two.request_ids_kept = 2;
  const server::InsertRequestId third{"tick-3", 44};
  maps = OneWrite(*copy, 24);
  ASSERT_TRUE(copy->InsertMaps(&maps, keep_two, nullptr, nullptr, &third).ok());
  maps = OneWrite(*copy, 12);
  ASSERT_TRUE(copy->InsertMaps(&maps, keep_two, nullptr, nullptr, &first, &replayed).ok());
  EXPECT_FALSE(replayed) << "tick-1 was the oldest of four kept with a limit of two";
  EXPECT_TRUE(source->Close().ok());
  EXPECT_TRUE(copy->Close().ok());
}

}  // namespace
}  // namespace lmd::testing
