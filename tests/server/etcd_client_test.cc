// EtcdClient, LeaseKeeper and PrefixWatcher against real etcd processes
// (tests/server/etcd_process.h): one member for most tests, three for
// failover. Leases are 1 s (the helper's fast election flags allow that), so
// the file runs in about 15 s.
#include "server/cluster/etcd_client.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include <gtest/gtest.h>

#include "tests/server/etcd_process.h"

namespace lmd::server::cluster {
namespace {

using lmd::testing::EtcdCluster;
using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;

EtcdClientOptions OptionsFor(const std::vector<std::string>& endpoints) {
  EtcdClientOptions options;
  options.endpoints = endpoints;
  options.call_timeout_ms = 1000;
  options.retry_budget_ms = 4000;
  return options;
}

std::unique_ptr<EtcdClient> ConnectOrNull(const std::vector<std::string>& endpoints) {
  auto client = EtcdClient::Connect(OptionsFor(endpoints));
  EXPECT_TRUE(client.ok()) << client.status().ToString();
  return client.ok() ? std::move(client).value() : nullptr;
}

// Polls `done` every 10 ms for at most `timeout`; whether it became true.
template <typename Predicate>
bool WaitFor(Predicate done, milliseconds timeout) {
  const auto give_up = Clock::now() + timeout;
  while (!done()) {
    if (Clock::now() >= give_up) return false;
    std::this_thread::sleep_for(milliseconds(10));
  }
  return true;
}

bool KeyExists(const EtcdClient& client, const std::string& key) {
  auto value = client.Get(key);
  EXPECT_TRUE(value.ok()) << value.status().ToString();
  return value.ok() && value->has_value();
}

// "put k=v" or "delete k".
std::string Describe(const WatchEvent& event) {
  return event.type == WatchEvent::Type::kPut ? "put " + event.key + "=" + event.value : "delete " + event.key;
}

// What a watcher delivered, for the test thread to wait on.
class Recorder {
 public:
  PrefixWatcher::BatchCallback Callback() {
    return [this](const WatchBatch& batch) {
      std::lock_guard<std::mutex> lock(mu_);
      batches_.push_back(batch);
      for (const WatchEvent& event : batch.events) events_.push_back(event);
      changed_.notify_all();
    };
  }
  bool WaitForEvents(size_t count, milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mu_);
    return changed_.wait_for(lock, timeout, [&] { return events_.size() >= count; });
  }
  std::vector<std::string> Described() const {
    std::lock_guard<std::mutex> lock(mu_);
    std::vector<std::string> described;
    for (const WatchEvent& event : events_) described.push_back(Describe(event));
    return described;
  }
  std::vector<WatchEvent> events() const {
    std::lock_guard<std::mutex> lock(mu_);
    return events_;
  }
  std::vector<WatchBatch> batches() const {
    std::lock_guard<std::mutex> lock(mu_);
    return batches_;
  }

 private:
  mutable std::mutex mu_;
  std::condition_variable changed_;
  std::vector<WatchBatch> batches_;
  std::vector<WatchEvent> events_;
};

// What a LeaseKeeper reported.
struct LossRecord {
  std::atomic<int> calls{0};
  std::mutex mu;
  Status why;
  LeaseKeeper::LostCallback Callback() {
    return [this](const Status& status) {
      {
        std::lock_guard<std::mutex> lock(mu);
        why = status;
      }
      ++calls;
    };
  }
};

TEST(EtcdClientTest, ConnectRefusesAnEmptyEndpointList) {
  EtcdClientOptions options;
  options.endpoints.clear();
  auto client = EtcdClient::Connect(options);
  ASSERT_FALSE(client.ok());
  EXPECT_EQ(client.status().code(), Status::Code::kInvalidArgument);
}

TEST(EtcdClientTest, ConnectNamesTheEndpointWhenNoMemberAnswers) {
  const std::string endpoint = "127.0.0.1:" + std::to_string(lmd::testing::UnusedLoopbackPort());
  EtcdClientOptions options = OptionsFor({endpoint});
  options.retry_budget_ms = 300;
  const auto start = Clock::now();
  auto client = EtcdClient::Connect(options);
  ASSERT_FALSE(client.ok());
  EXPECT_EQ(client.status().code(), Status::Code::kUnavailable);
  EXPECT_NE(client.status().message().find("etcd " + endpoint + " unavailable: connect"), std::string::npos)
      << client.status().message();
  EXPECT_LT(Clock::now() - start, milliseconds(1500));
}

TEST(EtcdClientTest, PutThenGetReturnsTheValueAndItsModRevision) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);

  const std::string binary("v\0\xff", 3);
  auto first = client->Put("k", binary);
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  auto read = client->Get("k");
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  ASSERT_TRUE(read->has_value());
  EXPECT_EQ((*read)->value, binary);
  EXPECT_EQ((*read)->mod_revision, *first);

  auto second = client->Put("k", "v2");
  ASSERT_TRUE(second.ok());
  EXPECT_GT(*second, *first);
  read = client->Get("k");
  ASSERT_TRUE(read.ok() && read->has_value());
  EXPECT_EQ((*read)->value, "v2");
  EXPECT_EQ((*read)->mod_revision, *second);

  auto absent = client->Get("no such key");
  ASSERT_TRUE(absent.ok()) << absent.status().ToString();
  EXPECT_FALSE(absent->has_value());
}

TEST(EtcdClientTest, GetPrefixReturnsTheKeysUnderThePrefixInKeyOrder) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  // "col/" with neighbours on both sides, and a prefix ending in 0xff.
  for (const std::string key : {"col/b", "col", "col/a", "col0", "cok", "col/", "p\xff", "p\xff\xff", "q"}) {
    ASSERT_TRUE(client->Put(key, "value of " + key).ok());
  }
  auto last = client->Put("col/c", "value of col/c");
  ASSERT_TRUE(last.ok());

  auto range = client->GetPrefix("col/");
  ASSERT_TRUE(range.ok()) << range.status().ToString();
  std::vector<std::string> keys;
  for (const EtcdKeyValue& kv : range->kvs) {
    keys.push_back(kv.key);
    EXPECT_EQ(kv.value, "value of " + kv.key);
  }
  EXPECT_EQ(keys, (std::vector<std::string>{"col/", "col/a", "col/b", "col/c"}));
  EXPECT_EQ(range->revision, *last);
  EXPECT_EQ(range->kvs.back().mod_revision, *last);

  auto high = client->GetPrefix("p\xff");
  ASSERT_TRUE(high.ok());
  ASSERT_EQ(high->kvs.size(), 2u);
  EXPECT_EQ(high->kvs[1].key, "p\xff\xff");

  auto all = client->GetPrefix("");
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->kvs.size(), 10u);
}

TEST(EtcdClientTest, DeleteSaysWhetherTheKeyExisted) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  ASSERT_TRUE(client->Put("k", "v").ok());
  auto deleted = client->Delete("k");
  ASSERT_TRUE(deleted.ok()) << deleted.status().ToString();
  EXPECT_TRUE(*deleted);
  EXPECT_FALSE(KeyExists(*client, "k"));
  deleted = client->Delete("k");
  ASSERT_TRUE(deleted.ok());
  EXPECT_FALSE(*deleted);
}

TEST(EtcdClientTest, PutIfRevisionWritesOnlyAtTheKeysCurrentRevision) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  auto first = client->Put("k", "v1");
  ASSERT_TRUE(first.ok());

  auto swapped = client->PutIfRevision("k", "v2", *first);
  ASSERT_TRUE(swapped.ok()) << swapped.status().ToString();
  EXPECT_TRUE(*swapped);
  auto stale = client->PutIfRevision("k", "v3", *first);
  ASSERT_TRUE(stale.ok()) << stale.status().ToString();
  EXPECT_FALSE(*stale);
  auto read = client->Get("k");
  ASSERT_TRUE(read.ok() && read->has_value());
  EXPECT_EQ((*read)->value, "v2");

  auto absent = client->PutIfRevision("no such key", "v", *first);
  ASSERT_TRUE(absent.ok());
  EXPECT_FALSE(*absent);
  EXPECT_FALSE(KeyExists(*client, "no such key"));
}

TEST(EtcdClientTest, OfTwoWritersRacingFromOneRevisionExactlyOneWins) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto a = ConnectOrNull((*etcd)->endpoints());
  auto b = ConnectOrNull((*etcd)->endpoints());
  ASSERT_TRUE(a != nullptr && b != nullptr);
  auto revision = a->Put("leader", "nobody");
  ASSERT_TRUE(revision.ok());
  for (int round = 0; round < 20; ++round) {
    std::atomic<bool> go{false};
    Result<bool> a_won = false, b_won = false;
    std::thread writer_a([&] {
      while (!go) std::this_thread::yield();
      a_won = a->PutIfRevision("leader", "a", *revision);
    });
    std::thread writer_b([&] {
      while (!go) std::this_thread::yield();
      b_won = b->PutIfRevision("leader", "b", *revision);
    });
    go = true;
    writer_a.join();
    writer_b.join();
    ASSERT_TRUE(a_won.ok() && b_won.ok()) << a_won.status().ToString() << " " << b_won.status().ToString();
    EXPECT_NE(*a_won, *b_won) << "round " << round;
    auto read = a->Get("leader");
    ASSERT_TRUE(read.ok() && read->has_value());
    EXPECT_EQ((*read)->value, *a_won ? "a" : "b");
    revision = (*read)->mod_revision;
  }
}

TEST(EtcdClientTest, PutIfRevisionZeroCreatesOnlyAnAbsentKey) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  auto created = client->PutIfRevision("k", "first", 0);
  ASSERT_TRUE(created.ok()) << created.status().ToString();
  EXPECT_TRUE(*created);
  auto again = client->PutIfRevision("k", "second", 0);
  ASSERT_TRUE(again.ok());
  EXPECT_FALSE(*again);
  auto read = client->Get("k");
  ASSERT_TRUE(read.ok() && read->has_value());
  EXPECT_EQ((*read)->value, "first");

  ASSERT_TRUE(client->Delete("k").ok());
  auto recreated = client->PutIfRevision("k", "third", 0);
  ASSERT_TRUE(recreated.ok());
  EXPECT_TRUE(*recreated);
}

TEST(EtcdClientTest, DeleteIfRevisionDeletesOnlyAtTheKeysCurrentRevision) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  auto first = client->Put("k", "v1");
  auto second = client->Put("k", "v2");
  ASSERT_TRUE(first.ok() && second.ok());
  auto stale = client->DeleteIfRevision("k", *first);
  ASSERT_TRUE(stale.ok()) << stale.status().ToString();
  EXPECT_FALSE(*stale);
  EXPECT_TRUE(KeyExists(*client, "k"));
  auto current = client->DeleteIfRevision("k", *second);
  ASSERT_TRUE(current.ok());
  EXPECT_TRUE(*current);
  EXPECT_FALSE(KeyExists(*client, "k"));
  EXPECT_EQ(client->DeleteIfRevision("k", 0).status().code(), Status::Code::kInvalidArgument);
}

TEST(EtcdClientTest, ErrorsNameTheEndpointAndTheCall) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  auto put = client->Put("k", "v", /*lease=*/0x1234);
  ASSERT_FALSE(put.ok());
  EXPECT_EQ(put.status().code(), Status::Code::kNotFound);
  EXPECT_EQ(put.status().message(),
            "etcd " + (*etcd)->endpoint(0) + ": put \"k\": etcdserver: requested lease not found");
}

TEST(EtcdClientTest, ADeadFirstEndpointIsSkipped) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  const std::string dead = "127.0.0.1:" + std::to_string(lmd::testing::UnusedLoopbackPort());
  auto client = ConnectOrNull({dead, (*etcd)->endpoint(0)});
  ASSERT_NE(client, nullptr);
  EXPECT_EQ(client->current_endpoint(), (*etcd)->endpoint(0));
  EXPECT_TRUE(client->Put("k", "v").ok());
}

TEST(EtcdClientTest, ALeasedKeyStaysWhileItsKeeperRunsAndGoesOnceItStops) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  auto lease = client->GrantLease(1);
  ASSERT_TRUE(lease.ok()) << lease.status().ToString();
  ASSERT_EQ(lease->ttl_seconds, 1);
  LossRecord loss;
  auto keeper = client->KeepAlive(*lease, loss.Callback());
  ASSERT_TRUE(client->Put("owned", "me", lease->id).ok());

  std::this_thread::sleep_for(milliseconds(2100));  // beyond 2 TTLs
  EXPECT_TRUE(KeyExists(*client, "owned"));
  EXPECT_FALSE(keeper->lost());
  EXPECT_EQ(loss.calls, 0);

  keeper.reset();
  EXPECT_TRUE(KeyExists(*client, "owned"));  // the lease runs out, it is not revoked
  EXPECT_TRUE(WaitFor([&] { return !KeyExists(*client, "owned"); }, milliseconds(3000)));
  EXPECT_EQ(loss.calls, 0);
}

TEST(EtcdClientTest, RevokingALeaseDeletesItsKeysAndTellsItsKeeper) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  auto lease = client->GrantLease(1);
  ASSERT_TRUE(lease.ok());
  LossRecord loss;
  auto keeper = client->KeepAlive(*lease, loss.Callback());
  ASSERT_TRUE(client->Put("owned", "me", lease->id).ok());

  ASSERT_TRUE(client->RevokeLease(lease->id).ok());
  EXPECT_FALSE(KeyExists(*client, "owned"));
  ASSERT_TRUE(WaitFor([&] { return loss.calls > 0; }, milliseconds(2000)));
  EXPECT_TRUE(keeper->lost());
  std::lock_guard<std::mutex> lock(loss.mu);
  EXPECT_EQ(loss.why.code(), Status::Code::kNotFound) << loss.why.ToString();
  EXPECT_NE(loss.why.message().find("has expired or was revoked"), std::string::npos) << loss.why.message();
  EXPECT_EQ(client->RevokeLease(lease->id).code(), Status::Code::kNotFound);
}

TEST(EtcdClientTest, AKeeperMayBeDestroyedFromItsOnLost) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  auto lease = client->GrantLease(1);
  ASSERT_TRUE(lease.ok());
  std::mutex mu;
  std::unique_ptr<LeaseKeeper> keeper;
  std::atomic<bool> destroyed{false};
  {
    std::lock_guard<std::mutex> lock(mu);
    keeper = client->KeepAlive(*lease, [&](const Status&) {
      std::lock_guard<std::mutex> lock(mu);
      keeper.reset();
      destroyed = true;
    });
  }
  ASSERT_TRUE(client->RevokeLease(lease->id).ok());
  EXPECT_TRUE(WaitFor([&] { return destroyed.load(); }, milliseconds(2000)));
}

TEST(EtcdClientTest, AKeeperReportsItsLeaseLostWhenEtcdPausesLongerThanTheTtl) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  auto lease = client->GrantLease(1);
  ASSERT_TRUE(lease.ok());
  LossRecord loss;
  auto keeper = client->KeepAlive(*lease, loss.Callback());
  std::this_thread::sleep_for(milliseconds(350));  // a renewal

  (*etcd)->Pause(0);
  const auto paused = Clock::now();
  const bool reported = WaitFor([&] { return loss.calls > 0; }, milliseconds(2500));
  const auto took = Clock::now() - paused;
  std::this_thread::sleep_for(milliseconds(300));
  (*etcd)->Resume(0);
  ASSERT_TRUE(reported);
  EXPECT_LE(took, milliseconds(1300));  // within the TTL of the last renewal, plus scheduling
  EXPECT_EQ(loss.calls, 1);
  std::lock_guard<std::mutex> lock(loss.mu);
  EXPECT_EQ(loss.why.code(), Status::Code::kDeadlineExceeded) << loss.why.ToString();
  EXPECT_NE(loss.why.message().find("expired before it could be renewed"), std::string::npos) << loss.why.message();
}

TEST(EtcdClientTest, AKeeperReportsItsLeaseLostWhenEtcdDies) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  auto lease = client->GrantLease(1);
  ASSERT_TRUE(lease.ok());
  LossRecord loss;
  auto keeper = client->KeepAlive(*lease, loss.Callback());
  std::this_thread::sleep_for(milliseconds(350));  // a renewal
  (*etcd)->Kill(0);
  ASSERT_TRUE(WaitFor([&] { return loss.calls > 0; }, milliseconds(2500)));
  std::this_thread::sleep_for(milliseconds(300));
  EXPECT_EQ(loss.calls, 1);
  EXPECT_TRUE(keeper->lost());
}

TEST(EtcdClientTest, AWatcherSeesThePutsAndDeletesUnderItsPrefixInOrder) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  auto before = client->GetPrefix("w/");
  ASSERT_TRUE(before.ok());
  Recorder live;
  auto watcher = client->WatchPrefix("w/", before->revision + 1, live.Callback());

  std::vector<int64_t> revisions;
  auto put = [&](const std::string& key, const std::string& value) {
    auto revision = client->Put(key, value);
    ASSERT_TRUE(revision.ok()) << revision.status().ToString();
    if (key.rfind("w/", 0) == 0) revisions.push_back(*revision);
  };
  put("w/a", "1");
  put("x/a", "not watched");
  put("w", "not watched either");
  put("w/b", "2");
  put("w/a", "3");
  ASSERT_TRUE(client->Delete("w/b").ok());
  revisions.push_back(revisions.back() + 1);
  auto cas = client->PutIfRevision("w/c", "4", 0);
  ASSERT_TRUE(cas.ok() && *cas);
  revisions.push_back(revisions.back() + 1);

  const std::vector<std::string> expected = {"put w/a=1", "put w/b=2", "put w/a=3", "delete w/b", "put w/c=4"};
  ASSERT_TRUE(live.WaitForEvents(expected.size(), milliseconds(3000))) << live.Described().size();
  EXPECT_EQ(live.Described(), expected);
  std::vector<int64_t> seen;
  for (const WatchEvent& event : live.events()) seen.push_back(event.mod_revision);
  EXPECT_EQ(seen, revisions);
  EXPECT_EQ(watcher->next_revision(), revisions.back() + 1);
  for (const WatchBatch& batch : live.batches()) EXPECT_FALSE(batch.reset);

  // A watcher started later from the first revision replays the same history.
  Recorder replay;
  auto late = client->WatchPrefix("w/", revisions.front(), replay.Callback());
  ASSERT_TRUE(replay.WaitForEvents(expected.size(), milliseconds(3000)));
  EXPECT_EQ(replay.Described(), expected);
}

TEST(EtcdClientTest, AWatcherResumesAfterEtcdRestartsWithoutMissingOrRepeatingEvents) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  Recorder recorder;
  auto watcher = client->WatchPrefix("w/", 0, recorder.Callback());
  ASSERT_TRUE(WaitFor([&] { return watcher->next_revision() > 0; }, milliseconds(2000)));
  ASSERT_TRUE(client->Put("w/a", "1").ok());
  ASSERT_TRUE(client->Put("w/b", "2").ok());
  ASSERT_TRUE(recorder.WaitForEvents(2, milliseconds(2000)));

  (*etcd)->Kill(0);
  ASSERT_TRUE((*etcd)->Restart(0).ok());
  // Written while the watcher is still reconnecting: it must replay them.
  ASSERT_TRUE(client->Put("w/c", "3").ok());
  ASSERT_TRUE(client->Delete("w/a").ok());
  ASSERT_TRUE(client->Put("w/d", "4").ok());

  const std::vector<std::string> expected = {"put w/a=1", "put w/b=2", "put w/c=3", "delete w/a", "put w/d=4"};
  ASSERT_TRUE(recorder.WaitForEvents(expected.size(), milliseconds(5000))) << recorder.Described().size();
  std::this_thread::sleep_for(milliseconds(200));  // nothing more arrives
  EXPECT_EQ(recorder.Described(), expected);
  const std::vector<WatchEvent> events = recorder.events();
  for (size_t i = 1; i < events.size(); ++i) EXPECT_EQ(events[i].mod_revision, events[i - 1].mod_revision + 1);
}

TEST(EtcdClientTest, AWatcherBehindACompactionResetsWithTheWholePrefix) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  ASSERT_TRUE(client->Put("w/a", "1").ok());
  ASSERT_TRUE(client->Put("w/b", "2").ok());
  ASSERT_TRUE(client->Delete("w/a").ok());
  ASSERT_TRUE(client->Put("w/c", "3").ok());
  auto now = client->Put("x/a", "not watched");
  ASSERT_TRUE(now.ok());
  ASSERT_TRUE(client->Compact(*now).ok());

  Recorder recorder;
  auto watcher = client->WatchPrefix("w/", 1, recorder.Callback());
  ASSERT_TRUE(recorder.WaitForEvents(2, milliseconds(3000)));
  ASSERT_TRUE(client->Put("w/d", "4").ok());
  ASSERT_TRUE(recorder.WaitForEvents(3, milliseconds(3000)));

  const std::vector<WatchBatch> batches = recorder.batches();
  ASSERT_EQ(batches.size(), 2u);
  EXPECT_TRUE(batches[0].reset);
  EXPECT_EQ(batches[0].revision, *now);
  EXPECT_FALSE(batches[1].reset);
  EXPECT_EQ(recorder.Described(), (std::vector<std::string>{"put w/b=2", "put w/c=3", "put w/d=4"}));
}

TEST(EtcdClientTest, AWatcherStopsPromptlyWhenDestroyed) {
  auto etcd = EtcdCluster::Start();
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto client = ConnectOrNull((*etcd)->endpoints());
  ASSERT_NE(client, nullptr);
  Recorder recorder;
  auto following = client->WatchPrefix("w/", 0, recorder.Callback());
  auto reconnecting = client->WatchPrefix("w/", 0, recorder.Callback());
  ASSERT_TRUE(WaitFor([&] { return following->next_revision() > 0; }, milliseconds(2000)));

  auto start = Clock::now();
  following.reset();  // on a healthy stream
  EXPECT_LT(Clock::now() - start, milliseconds(300));

  (*etcd)->Kill(0);
  std::this_thread::sleep_for(milliseconds(700));
  start = Clock::now();
  reconnecting.reset();  // between attempts to reach a dead etcd
  EXPECT_LT(Clock::now() - start, milliseconds(300));
}

TEST(EtcdClientTest, AThreeMemberClusterKeepsServingWhenAMemberHangsOrItsLeaderDies) {
  auto etcd = EtcdCluster::Start(3);
  ASSERT_TRUE(etcd.ok()) << etcd.status().ToString();
  auto leader = (*etcd)->Leader();
  ASSERT_TRUE(leader.ok()) << leader.status().ToString();
  // Endpoints: a follower, then the leader, then the other follower.
  std::vector<int> order;
  for (int i = 0; i < 3; ++i) {
    if (i != *leader) order.push_back(i);
  }
  order.insert(order.begin() + 1, *leader);
  std::vector<std::string> endpoints;
  for (const int i : order) endpoints.push_back((*etcd)->endpoint(i));
  EtcdClientOptions options = OptionsFor(endpoints);
  // Long enough that a live member answers in time on a loaded 2-core
  // machine (500 ms was not, under ctest -j2): only the paused one times out.
  options.call_timeout_ms = 2000;
  auto connected = EtcdClient::Connect(options);
  ASSERT_TRUE(connected.ok()) << connected.status().ToString();
  EtcdClient& client = **connected;
  ASSERT_EQ(client.current_endpoint(), endpoints[0]);

  // A hung follower: the attempt there times out, another member applies it.
  (*etcd)->Pause(order[0]);
  auto created = client.PutIfRevision("c/1", "one", 0);
  (*etcd)->Resume(order[0]);
  // Either another member applied it, or the paused one had taken it before
  // SIGSTOP landed (signals arrive asynchronously; seen under load): then
  // the retry finds the key written and the outcome is unknown, and the
  // contract is to re-read.
  if (created.ok()) {
    EXPECT_TRUE(*created);
  } else {
    ASSERT_EQ(created.status().code(), Status::Code::kDeadlineExceeded) << created.status().ToString();
    EXPECT_NE(created.status().message().find("outcome unknown"), std::string::npos) << created.status().ToString();
  }
  auto written = client.Get("c/1");
  ASSERT_TRUE(written.ok() && written->has_value()) << written.status().ToString();
  EXPECT_EQ((*written)->value, "one");

  // The client, a keeper and a watcher at the leader, which dies. 3 s: a
  // 1 s lease could run out, for the keeper, during the election; 3 s leaves
  // room for a loaded 2-core machine.
  auto lease = client.GrantLease(3);
  ASSERT_TRUE(lease.ok()) << lease.status().ToString();
  LossRecord loss;
  auto keeper = client.KeepAlive(*lease, loss.Callback());
  ASSERT_TRUE(client.Put("c/owned", "me", lease->id).ok());
  Recorder recorder;
  auto watcher = client.WatchPrefix("c/", 0, recorder.Callback());
  ASSERT_TRUE(WaitFor([&] { return watcher->next_revision() > 0; }, milliseconds(2000)));
  auto one = client.Get("c/1");
  ASSERT_TRUE(one.ok() && one->has_value());

  (*etcd)->Kill(*leader);
  const auto killed = Clock::now();
  auto second = client.Put("c/2", "two");
  ASSERT_TRUE(second.ok()) << second.status().ToString();
  auto read = client.Get("c/2");
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  ASSERT_TRUE(read->has_value());
  EXPECT_EQ((*read)->value, "two");
  EXPECT_NE(client.current_endpoint(), endpoints[1]);
  auto swapped = client.PutIfRevision("c/1", "uno", (*one)->mod_revision);
  ASSERT_TRUE(swapped.ok()) << swapped.status().ToString();
  EXPECT_TRUE(*swapped);

  ASSERT_TRUE(recorder.WaitForEvents(2, milliseconds(5000))) << recorder.Described().size();
  EXPECT_EQ(recorder.Described(), (std::vector<std::string>{"put c/2=two", "put c/1=uno"}));
  std::this_thread::sleep_until(killed + milliseconds(3100));  // beyond the TTL
  EXPECT_EQ(loss.calls, 0);
  EXPECT_TRUE(KeyExists(client, "c/owned"));
}

}  // namespace
}  // namespace lmd::server::cluster
