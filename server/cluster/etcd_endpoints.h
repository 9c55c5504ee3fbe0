// EtcdEndpoints (internal to server/cluster): one gRPC channel, with its
// stubs, per etcd member, and the failover loop that every unary call goes
// through. Shared (shared_ptr) by an EtcdClient and the keepers and watchers
// it starts, so any of them may outlive the others.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "core/status.h"
#include "etcd/etcd_rpc.grpc.pb.h"
#include "server/cluster/etcd_client.h"

namespace lmd::server::cluster {

using Clock = std::chrono::steady_clock;

// Metadata that makes a member refuse a call, or end a stream, while it has
// no leader (etcd's "hasleader"), so a member cut off from the others sends
// the caller on to the next endpoint instead of stalling it. Every call and
// stream of the client carries it.
inline constexpr char kRequireLeaderKey[] = "hasleader";
inline constexpr char kRequireLeaderValue[] = "true";

class EtcdEndpoints {
 public:
  // Channels to every endpoint of `options` (validated by the caller); no
  // connection is made yet.
  explicit EtcdEndpoints(const EtcdClientOptions& options);
  EtcdEndpoints(const EtcdEndpoints&) = delete;
  EtcdEndpoints& operator=(const EtcdEndpoints&) = delete;

  const EtcdClientOptions& options() const { return options_; }
  size_t size() const { return members_.size(); }
  const std::string& endpoint(size_t i) const { return options_.endpoints[i]; }
  etcdserverpb::KV::Stub& kv(size_t i) const { return *members_[i].kv; }
  etcdserverpb::Watch::Stub& watch(size_t i) const { return *members_[i].watch; }
  etcdserverpb::Lease::Stub& lease(size_t i) const { return *members_[i].lease; }

  // The endpoint that answered last: where calls, keepers and watchers start.
  size_t preferred() const { return preferred_.load(); }

  // One attempt of a call at endpoint `i` under `context` (its deadline is
  // set): the gRPC call itself, which fills the caller's response.
  using Attempt = std::function<grpc::Status(size_t i, grpc::ClientContext* context)>;

  // Runs `attempt` at the preferred endpoint and, while attempts fail with
  // UNAVAILABLE or DEADLINE_EXCEEDED or the endpoint cannot be reached, at the
  // next ones in turn until options().retry_budget_ms is spent. OK once an
  // attempt succeeds; else the last failure as a Status naming its endpoint
  // and `what` ("put \"a\""). (OUT) *unsure, if given: OK, or the first
  // failure of an attempt that had been sent, which etcd may have applied.
  Status Call(const std::string& what, const Attempt& attempt, Status* unsure = nullptr);

  // Waits until `until`, or until `stop` returns true (checked every 50 ms;
  // false then), watching the channels meanwhile. Waiting this way rather
  // than sleeping is what lets gRPC finish reconnecting in the background:
  // with the synchronous API no other thread polls the sockets (gRPC's
  // backup poller runs every 5 s), so a client that slept between attempts
  // would find a restarted member only by chance.
  bool WaitPolling(Clock::time_point until, const std::function<bool()>& stop = nullptr) const;

  // `status`, which endpoint `i` returned for `what`, as a Status:
  // "etcd 127.0.0.1:2379 unavailable: put \"a\": <gRPC message>".
  Status ToStatus(size_t i, const std::string& what, const grpc::Status& status) const;

 private:
  struct Member {
    std::shared_ptr<grpc::Channel> channel;
    std::unique_ptr<etcdserverpb::KV::Stub> kv;
    std::unique_ptr<etcdserverpb::Watch::Stub> watch;
    std::unique_ptr<etcdserverpb::Lease::Stub> lease;
  };

  // Whether endpoint `i`'s channel is connected, waiting (until `deadline`)
  // while it connects; false at once if its last connection attempt failed
  // (gRPC tries again after a backoff). A call is sent only when this is
  // true, so a member that could not be reached has not applied it.
  bool Connected(size_t i, Clock::time_point deadline) const;

  const EtcdClientOptions options_;
  std::vector<Member> members_;
  std::atomic<size_t> preferred_{0};
};

// `deadline` as gRPC takes it (on the system clock; the client measures on
// the steady one).
std::chrono::system_clock::time_point GrpcDeadline(Clock::time_point deadline);

// The end of the key range holding every key that starts with `prefix`:
// `prefix` with its last byte below 0xff plus one, or "\0" (every key from
// the start) when there is none, as for "".
std::string PrefixRangeEnd(const std::string& prefix);

// The first key of that range: `prefix`, or "\0" for "" (etcd refuses an
// empty key).
std::string PrefixRangeKey(const std::string& prefix);

// A key for messages: quoted, bytes outside printable ASCII as \xNN.
std::string QuoteKey(const std::string& key);

// "lease 694d77aa9e38260f": a lease for messages, in hex as etcdctl prints it.
std::string LeaseName(int64_t lease_id);

}  // namespace lmd::server::cluster
