// EtcdClient: a small client for etcd's v3 gRPC API (etcd 3.4), the store
// behind lmd's replicated collections. Reads and writes of keys, compare-and-
// swap on a key's mod_revision, leases, and the two long-running helpers: a
// LeaseKeeper that keeps a lease alive (lease_keeper.h) and a PrefixWatcher
// that follows every change under a prefix (etcd_watch.h).
//
// Failover: the client knows every member's endpoint. A call starts at the
// endpoint that answered last; when that one cannot be reached, answers
// UNAVAILABLE (it has no leader, it is stopping) or times out, the call moves
// on to the next endpoint, round the list, until retry_budget_ms is spent. So
// losing a minority of a cluster's members is invisible to callers. Any other
// error returns at once. Errors are Status values whose message names the
// endpoint and the call ("etcd 127.0.0.1:2379 unavailable: put \"a\": ...").
//
// Thread-safe: one client serves any number of threads.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"
#include "server/cluster/etcd_watch.h"
#include "server/cluster/lease_keeper.h"

namespace lmd::server::cluster {

class EtcdEndpoints;

struct EtcdClientOptions {
  // Client address of each member, "host:port", tried in this order.
  // Default: one member on this host at etcd's default client port.
  std::vector<std::string> endpoints = {"127.0.0.1:2379"};
  // Deadline of one attempt at one endpoint, in ms. Default 2000: a healthy
  // etcd answers in milliseconds; this is what a hung member costs a call.
  int call_timeout_ms = 2000;
  // How long a call keeps trying the endpoints in turn, in ms from its start;
  // no attempt starts later than that (one may end up to call_timeout_ms
  // after). Default 5000: time for a 3-member cluster to elect a new leader
  // (etcd's default election timeout is 1 s) and for a restarted member to
  // be reconnected.
  int retry_budget_ms = 5000;
};

// A key's value and the revision of its last write.
struct EtcdValue {
  std::string value;
  int64_t mod_revision = 0;
  int64_t lease = 0;  // the lease the key is attached to; 0: none
};

struct EtcdKeyValue {
  std::string key;
  std::string value;
  int64_t mod_revision = 0;
  int64_t lease = 0;
};

// The keys under a prefix as of one revision.
struct EtcdRange {
  std::vector<EtcdKeyValue> kvs;  // in key order
  // The store's revision the read saw: a watch from revision + 1 sees every
  // later change.
  int64_t revision = 0;
};

class EtcdClient {
 public:
  // Opens channels to every endpoint and checks that one of them answers a
  // read (within retry_budget_ms). InvalidArgument for an empty endpoint
  // list or a non-positive timeout; else the error of the last endpoint tried.
  static Result<std::unique_ptr<EtcdClient>> Connect(EtcdClientOptions options);
  ~EtcdClient();
  EtcdClient(const EtcdClient&) = delete;
  EtcdClient& operator=(const EtcdClient&) = delete;

  // The value of `key`, or nullopt if there is no such key.
  Result<std::optional<EtcdValue>> Get(const std::string& key) const;

  // Every key that starts with `prefix` ("" for all keys), as of one revision.
  Result<EtcdRange> GetPrefix(const std::string& prefix) const;

  // Sets `key` to `value`, attached to `lease` unless it is 0 (NotFound if
  // that lease does not exist). Returns the key's new mod_revision.
  Result<int64_t> Put(const std::string& key, const std::string& value, int64_t lease = 0);

  // Deletes `key`; true if it existed (false too when an attempt lost in a
  // failover had deleted it).
  Result<bool> Delete(const std::string& key);

  // Compare-and-swap: sets `key` only if its mod_revision is still
  // `expected_mod_revision`, or, for 0, only if the key does not exist.
  // true if this call wrote the key, false if the key had moved on (re-read
  // it). Of several callers racing from the same revision exactly one gets
  // true. DeadlineExceeded, "outcome unknown", when an attempt at one member
  // failed after it was sent (so it may have been applied) and the retry at
  // another found the key changed: the caller re-reads to learn which.
  Result<bool> PutIfRevision(const std::string& key, const std::string& value, int64_t expected_mod_revision,
                             int64_t lease = 0);

  // Deletes `key` only if its mod_revision is still `expected_mod_revision`
  // (> 0). true if this call deleted it; false if the key had changed or is
  // gone. DeadlineExceeded, "outcome unknown", as for PutIfRevision.
  Result<bool> DeleteIfRevision(const std::string& key, int64_t expected_mod_revision);

  // Drops the store's history before `revision`: reads and watches at older
  // revisions are no longer possible (a PrefixWatcher behind it resets).
  Status Compact(int64_t revision);

  // A new lease of `ttl_seconds` (> 0). etcd may raise the TTL to its minimum
  // (1.5 election timeouts, rounded up to seconds: 2 s with default flags);
  // the TTL granted is in the result.
  Result<EtcdLease> GrantLease(int64_t ttl_seconds);

  // Ends `lease_id` now and deletes every key attached to it. NotFound if
  // there is no such lease (it expired or was revoked).
  Status RevokeLease(int64_t lease_id);

  // Starts keeping `lease` alive until the returned keeper is destroyed; see
  // LeaseKeeper. Start it right after GrantLease: the keeper counts the TTL
  // from lease.granted_at.
  std::unique_ptr<LeaseKeeper> KeepAlive(const EtcdLease& lease, LeaseKeeper::LostCallback on_lost) const;

  // Starts following every change under `prefix` from `start_revision`
  // (inclusive; <= 0: from now), calling `on_batch` on the watcher's own
  // thread; see PrefixWatcher.
  std::unique_ptr<PrefixWatcher> WatchPrefix(const std::string& prefix, int64_t start_revision,
                                             PrefixWatcher::BatchCallback on_batch) const;

  // The endpoint that answered last, where the next call starts.
  std::string current_endpoint() const;

 private:
  explicit EtcdClient(std::shared_ptr<EtcdEndpoints> endpoints);

  std::shared_ptr<EtcdEndpoints> endpoints_;
};

}  // namespace lmd::server::cluster
