// LeaseKeeper: keeps an etcd lease alive for as long as it exists. Its own
// thread renews the lease every TTL/3 over etcd's LeaseKeepAlive RPC, moving
// to the next endpoint when one fails. If the lease could not be renewed
// before it expired, or etcd answers that it is gone (TTL <= 0), on_lost is
// called, once, and the keeper stops: the keys attached to the lease are, or
// soon will be, deleted, so whoever holds them must act as if it no longer
// does. Destroying the keeper stops the renewals without revoking the lease,
// which then expires after its TTL (EtcdClient::RevokeLease ends it at once).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

#include "core/status.h"

namespace grpc {
class ClientContext;
}

namespace lmd::server::cluster {

class EtcdEndpoints;

// A lease as granted by EtcdClient::GrantLease.
struct EtcdLease {
  int64_t id = 0;
  // The TTL etcd granted (it raises small TTLs to its minimum), in seconds.
  int64_t ttl_seconds = 0;
  // When the grant was asked for: the lease lasts at least until
  // granted_at + ttl_seconds unless revoked.
  std::chrono::steady_clock::time_point granted_at;
};

class LeaseKeeper {
 public:
  // Why the lease was lost: DeadlineExceeded (not renewed in time) or
  // NotFound (etcd says it expired or was revoked), naming the lease.
  using LostCallback = std::function<void(const Status& why)>;

  // Made by EtcdClient::KeepAlive; starts the thread. The lease is taken to
  // expire at lease.granted_at + lease.ttl_seconds until etcd renews it.
  LeaseKeeper(std::shared_ptr<EtcdEndpoints> endpoints, EtcdLease lease, LostCallback on_lost);
  // Stops renewing (cancelling a renewal in flight) and joins the thread; no
  // on_lost call starts after it returns. May be called from on_lost.
  ~LeaseKeeper();
  LeaseKeeper(const LeaseKeeper&) = delete;
  LeaseKeeper& operator=(const LeaseKeeper&) = delete;

  const EtcdLease& lease() const { return lease_; }

  // True once the lease is known lost (on_lost has run or is running).
  bool lost() const;

 private:
  using Clock = std::chrono::steady_clock;

  void Run();
  // One renewal at endpoint `i`, finished by `deadline`: a LeaseKeepAlive
  // stream carrying one request and its answer. The TTL etcd answered.
  Result<int64_t> Renew(size_t i, Clock::time_point deadline);
  bool stopping() const;
  // Waits until `until`; false (at once) if the keeper is stopping.
  bool SleepUntil(Clock::time_point until);
  // Marks the lease lost and calls on_lost; the thread returns right after.
  void Lose(const Status& why);

  const std::shared_ptr<EtcdEndpoints> endpoints_;
  const EtcdLease lease_;
  LostCallback on_lost_;  // used by the keeper's thread only

  mutable std::mutex mu_;
  std::condition_variable wake_;
  // State below is guarded by mu_.
  bool stopping_ = false;
  bool lost_ = false;
  grpc::ClientContext* renewal_ = nullptr;  // the renewal in flight, for TryCancel

  std::thread thread_;  // last: starts once the rest is built
};

}  // namespace lmd::server::cluster
