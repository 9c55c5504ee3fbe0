// Placement decisions and the primary's replication log (server/cluster),
// without etcd.
#include "server/cluster/placement.h"
#include "server/cluster/replication_log.h"

#include <algorithm>

#include <gtest/gtest.h>

namespace lmd::server::cluster {
namespace {

LiveNodes Nodes(std::initializer_list<std::pair<const char*, const char*>> ids_and_zones) {
  LiveNodes live;
  for (const auto& [id, zone] : ids_and_zones) {
    internal::NodeRecord record;
    record.set_node_id(id);
    record.set_zone(zone);
    live[id] = record;
  }
  return live;
}

std::vector<std::string> List(const google::protobuf::RepeatedPtrField<std::string>& ids) {
  return {ids.begin(), ids.end()};
}

TEST(PlacementTest, ANewCollectionLivesOnItsCreatorAndNodesOfOtherZones) {
  const LiveNodes live = Nodes({{"a1", "a"}, {"a2", "a"}, {"a3", "a"}, {"b1", "b"}, {"c1", "c"}});
  const internal::Placement p = NewPlacement("site", live, "a1", 3);
  EXPECT_EQ(p.epoch(), 1u);
  EXPECT_EQ(p.primary(), "a1");
  ASSERT_EQ(p.replicas_size(), 3);
  EXPECT_EQ(List(p.in_sync()), List(p.replicas()));  // an empty collection is in sync everywhere
  std::set<std::string> zones;
  for (const std::string& id : p.replicas()) zones.insert(live.at(id).zone());
  EXPECT_EQ(zones, (std::set<std::string>{"a", "b", "c"}));
}

TEST(PlacementTest, ACollectionItsCreatorAlreadyHeldIsCopiedByTheOthersBeforeTheyAreInSync) {
  const internal::Placement p =
      NewPlacement("site", Nodes({{"n1", ""}, {"n2", ""}, {"n3", ""}}), "n1", 3, /*others_in_sync=*/false);
  EXPECT_EQ(p.replicas_size(), 3);
  EXPECT_EQ(List(p.in_sync()), (std::vector<std::string>{"n1"}));
}

TEST(PlacementTest, CollectionsSpreadOverTheNodes) {
  const LiveNodes live = Nodes({{"n1", ""}, {"n2", ""}, {"n3", ""}, {"n4", ""}, {"n5", ""}});
  std::map<std::string, int> copies;
  for (int i = 0; i < 200; ++i) {
    const internal::Placement p = NewPlacement("c" + std::to_string(i), live, "n1", 2);
    for (const std::string& id : p.replicas()) ++copies[id];
  }
  EXPECT_EQ(copies["n1"], 200);
  for (const char* id : {"n2", "n3", "n4", "n5"}) {
    EXPECT_GT(copies[id], 25) << id;  // 50 each if perfectly even
    EXPECT_LT(copies[id], 75) << id;
  }
}

TEST(PlacementTest, ADeadPrimaryIsReplacedByALiveInSyncCopy) {
  internal::Placement p = NewPlacement("site", Nodes({{"n1", ""}, {"n2", ""}, {"n3", ""}}), "n1", 3);
  p.clear_in_sync();
  for (const char* id : {"n1", "n3", "n2"}) p.add_in_sync(id);
  const std::optional<internal::Placement> next = Repaired("site", p, Nodes({{"n2", ""}, {"n3", ""}}), 3);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->primary(), "n3");  // the first live one of the in-sync set
  EXPECT_EQ(next->epoch(), 2u);
  EXPECT_EQ(List(next->in_sync()), (std::vector<std::string>{"n3", "n2"}));
  EXPECT_EQ(next->replicas_size(), 3);  // n1 stays a replica: it catches up when it returns
  EXPECT_FALSE(Repaired("site", *next, Nodes({{"n2", ""}, {"n3", ""}}), 3));  // nothing more to do
}

TEST(PlacementTest, WithoutALiveInSyncCopyThePlacementWaits) {
  internal::Placement p = NewPlacement("site", Nodes({{"n1", ""}, {"n2", ""}}), "n1", 2);
  p.clear_in_sync();
  p.add_in_sync("n1");  // n2 is catching up: it cannot take over
  EXPECT_FALSE(Repaired("site", p, Nodes({{"n2", ""}}), 2));
}

TEST(PlacementTest, ALiveNodeJoinsAnUnderReplicatedCollectionAsACatchingUpCopy) {
  internal::Placement p = NewPlacement("site", Nodes({{"n1", ""}, {"n2", ""}}), "n1", 3);
  ASSERT_EQ(p.replicas_size(), 2);
  const std::optional<internal::Placement> next =
      Repaired("site", p, Nodes({{"n1", ""}, {"n2", ""}, {"n3", ""}}), 3);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->replicas_size(), 3);
  EXPECT_FALSE(InSync(*next, "n3"));
  EXPECT_EQ(next->epoch(), p.epoch());
}

TEST(PlacementTest, ACollectionsOwnFactorOverridesTheClustersBothWays) {
  const LiveNodes live = Nodes({{"n1", ""}, {"n2", ""}, {"n3", ""}, {"n4", ""}});
  internal::Placement p = NewPlacement("site", live, "n1", 3);
  p.set_replication_factor(4);
  std::optional<internal::Placement> next = Repaired("site", p, live, 3);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->replicas_size(), 4);  // the fourth copies the collection before it counts
  EXPECT_EQ(next->in_sync_size(), 3);

  p.set_replication_factor(1);  // lowered: the copies other than the primary leave
  next = Repaired("site", p, live, 3);
  ASSERT_TRUE(next);
  EXPECT_EQ(List(next->replicas()), std::vector<std::string>{"n1"});
  EXPECT_EQ(List(next->in_sync()), std::vector<std::string>{"n1"});
  EXPECT_EQ(WantedCopies(*next, 3), 1u);
}

TEST(PlacementTest, ADeadCopyLeavesOnlyOnceItsReplacementCaughtUp) {
  internal::Placement p = NewPlacement("site", Nodes({{"n1", ""}, {"n2", ""}, {"n3", ""}}), "n1", 3);
  const LiveNodes without_n3 = Nodes({{"n1", ""}, {"n2", ""}, {"n4", ""}});
  std::optional<internal::Placement> next = Repaired("site", p, without_n3, 3);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->replicas_size(), 4);  // n3 stays while n4 copies: only two copies are in sync
  EXPECT_FALSE(InSync(*next, "n4"));
  p = *next;
  p.add_in_sync("n4");  // n4 caught up
  next = Repaired("site", p, without_n3, 3);
  ASSERT_TRUE(next);
  EXPECT_EQ(List(next->replicas()), (std::vector<std::string>{"n1", "n2", "n4"}));
  EXPECT_EQ(next->in_sync_size(), 3);
}

TEST(PlacementTest, ACopyGoneBrieflyIsNotMadeElsewhere) {
  const internal::Placement p = NewPlacement("site", Nodes({{"n1", ""}, {"n2", ""}, {"n3", ""}}), "n1", 3);
  const std::optional<internal::Placement> next =
      Repaired("site", p, Nodes({{"n1", ""}, {"n2", ""}, {"n4", ""}}), 3, /*returning=*/Nodes({{"n3", ""}}));
  ASSERT_TRUE(next);
  std::vector<std::string> replicas = List(next->replicas());
  std::sort(replicas.begin(), replicas.end());
  EXPECT_EQ(replicas, (std::vector<std::string>{"n1", "n2", "n3"}));  // n4 copies nothing
  EXPECT_EQ(List(next->in_sync()), (std::vector<std::string>{"n1", "n2"}));
}

TEST(PlacementTest, ANodeJoiningTakesTheCopiesItRanksHighestFor) {
  const LiveNodes three = Nodes({{"n1", ""}, {"n2", ""}, {"n3", ""}});
  const LiveNodes four = Nodes({{"n1", ""}, {"n2", ""}, {"n3", ""}, {"n4", ""}});
  int moved = 0;
  for (int c = 0; c < 100; ++c) {
    const std::string name = "site" + std::to_string(c);
    internal::Placement p = NewPlacement(name, three, "n1", 2);
    const std::vector<std::string> target = TargetCopies(name, "n1", four, 2);
    std::optional<internal::Placement> next = Repaired(name, p, four, 2);
    if (std::find(target.begin(), target.end(), "n4") == target.end()) {
      EXPECT_FALSE(next) << name << ": n4 ranks below its copies: nothing moves";
      continue;
    }
    ++moved;
    ASSERT_TRUE(next) << name;
    EXPECT_EQ(next->replicas_size(), 3) << name << ": n4 copies first, the copy it replaces stays meanwhile";
    p = *next;
    p.add_in_sync("n4");
    next = Repaired(name, p, four, 2);
    ASSERT_TRUE(next) << name;
    EXPECT_EQ(List(next->replicas()), target) << name;
    EXPECT_EQ(next->in_sync_size(), 2) << name;
  }
  // The primary stays; of its one other copy, n4 should take about a third.
  EXPECT_GT(moved, 15);
  EXPECT_LT(moved, 55);
}

internal::ApplyRequest Write(uint64_t epoch, uint64_t seq) {
  internal::ApplyRequest w;
  w.set_epoch(epoch);
  w.set_seq(seq);
  return w;
}

TEST(ReplicationLogTest, ACopyResumesAfterAWriteThisPrimaryHas) {
  ReplicationLog log(1 << 20);
  log.Reset(1, 10);  // the primary's store stood at write 10 of epoch 1
  for (uint64_t s = 11; s <= 14; ++s) log.Append(Write(2, s));
  const auto from_base = log.After(1, 10);
  ASSERT_TRUE(from_base);
  ASSERT_EQ(from_base->size(), 4u);
  EXPECT_EQ(from_base->front().seq(), 11u);
  const auto from_12 = log.After(2, 12);
  ASSERT_TRUE(from_12);
  EXPECT_EQ(from_12->size(), 2u);
  EXPECT_TRUE(log.After(2, 14)->empty());
}

TEST(ReplicationLogTest, ADivergedOrTooOldCopyIsNotResumed) {
  ReplicationLog log(1 << 20);
  log.Reset(1, 10);
  for (uint64_t s = 11; s <= 14; ++s) log.Append(Write(2, s));
  EXPECT_FALSE(log.After(1, 12));  // its write 12 came from the old primary: diverged
  EXPECT_FALSE(log.After(1, 9));   // before the log
  EXPECT_FALSE(log.After(2, 15));  // ahead of this primary: it holds writes never acknowledged
  EXPECT_FALSE(log.After(2, 10));  // write 10 was of epoch 1
}

TEST(ReplicationLogTest, TheLogKeepsItsByteBudget) {
  ReplicationLog log(1);  // room for the newest write only
  log.Reset(1, 0);
  for (uint64_t s = 1; s <= 5; ++s) log.Append(Write(1, s));
  EXPECT_FALSE(log.After(1, 3));
  const auto last = log.After(1, 4);
  ASSERT_TRUE(last);
  EXPECT_EQ(last->size(), 1u);
}

}  // namespace
}  // namespace lmd::server::cluster
