#include "server/cluster/etcd_client.h"

#include <spdlog/spdlog.h>

#include "server/cluster/etcd_endpoints.h"

namespace lmd::server::cluster {
namespace {

// Runs `txn`, one compare on `key` with one op on each side, as a
// compare-and-swap: true if the compare held (and the op ran).
Result<bool> CompareAndSwap(EtcdEndpoints& endpoints, const std::string& what, const etcdserverpb::TxnRequest& txn) {
  etcdserverpb::TxnResponse response;
  Status unsure;
  const Status status = endpoints.Call(
      what,
      [&](size_t i, grpc::ClientContext* context) {
        response.Clear();
        return endpoints.kv(i).Txn(context, txn, &response);
      },
      &unsure);
  if (!status.ok()) return status;
  if (!response.succeeded() && !unsure.ok()) {
    // The key has moved on, maybe by our own earlier attempt.
    return Status::DeadlineExceeded(what + ": outcome unknown: an earlier attempt may have been applied (" +
                                    unsure.message() + "); re-read the key");
  }
  return response.succeeded();
}

}  // namespace

Result<std::unique_ptr<EtcdClient>> EtcdClient::Connect(EtcdClientOptions options) {
  if (options.endpoints.empty()) return Status::InvalidArgument("etcd: no endpoints given");
  for (const std::string& endpoint : options.endpoints) {
    if (endpoint.empty()) return Status::InvalidArgument("etcd: an endpoint is empty");
  }
  if (options.call_timeout_ms <= 0 || options.retry_budget_ms <= 0) {
    return Status::InvalidArgument("etcd: call_timeout_ms and retry_budget_ms must be positive");
  }
  auto endpoints = std::make_shared<EtcdEndpoints>(options);
  etcdserverpb::RangeRequest probe;  // a linearizable read: the member must be part of a quorum
  probe.set_key(std::string(1, '\0'));
  probe.set_count_only(true);
  const Status status = endpoints->Call("connect", [&](size_t i, grpc::ClientContext* context) {
    etcdserverpb::RangeResponse response;
    return endpoints->kv(i).Range(context, probe, &response);
  });
  if (!status.ok()) return status;
  spdlog::debug("etcd: connected to {} ({} endpoints)", endpoints->endpoint(endpoints->preferred()),
                endpoints->size());
  return std::unique_ptr<EtcdClient>(new EtcdClient(std::move(endpoints)));
}

EtcdClient::EtcdClient(std::shared_ptr<EtcdEndpoints> endpoints) : endpoints_(std::move(endpoints)) {}

EtcdClient::~EtcdClient() = default;

Result<std::optional<EtcdValue>> EtcdClient::Get(const std::string& key) const {
  etcdserverpb::RangeRequest request;
  request.set_key(key);
  etcdserverpb::RangeResponse response;
  const Status status = endpoints_->Call("get " + QuoteKey(key), [&](size_t i, grpc::ClientContext* context) {
    response.Clear();
    return endpoints_->kv(i).Range(context, request, &response);
  });
  if (!status.ok()) return status;
  if (response.kvs_size() == 0) return std::optional<EtcdValue>();
  const mvccpb::KeyValue& kv = response.kvs(0);
  return std::optional<EtcdValue>(EtcdValue{kv.value(), kv.mod_revision(), kv.lease()});
}

Result<EtcdRange> EtcdClient::GetPrefix(const std::string& prefix) const {
  etcdserverpb::RangeRequest request;
  request.set_key(PrefixRangeKey(prefix));
  request.set_range_end(PrefixRangeEnd(prefix));
  etcdserverpb::RangeResponse response;
  const Status status = endpoints_->Call("get prefix " + QuoteKey(prefix), [&](size_t i, grpc::ClientContext* context) {
    response.Clear();
    return endpoints_->kv(i).Range(context, request, &response);
  });
  if (!status.ok()) return status;
  EtcdRange range;
  range.revision = response.header().revision();
  range.kvs.reserve(response.kvs_size());
  for (const mvccpb::KeyValue& kv : response.kvs()) {
    range.kvs.push_back({kv.key(), kv.value(), kv.mod_revision(), kv.lease()});
  }
  return range;
}

Result<int64_t> EtcdClient::Put(const std::string& key, const std::string& value, int64_t lease) {
  etcdserverpb::PutRequest request;
  request.set_key(key);
  request.set_value(value);
  request.set_lease(lease);
  etcdserverpb::PutResponse response;
  const Status status = endpoints_->Call("put " + QuoteKey(key), [&](size_t i, grpc::ClientContext* context) {
    response.Clear();
    return endpoints_->kv(i).Put(context, request, &response);
  });
  if (!status.ok()) return status;
  return response.header().revision();
}

Result<bool> EtcdClient::Delete(const std::string& key) {
  etcdserverpb::DeleteRangeRequest request;
  request.set_key(key);
  etcdserverpb::DeleteRangeResponse response;
  const Status status = endpoints_->Call("delete " + QuoteKey(key), [&](size_t i, grpc::ClientContext* context) {
    response.Clear();
    return endpoints_->kv(i).DeleteRange(context, request, &response);
  });
  if (!status.ok()) return status;
  return response.deleted() > 0;
}

Result<bool> EtcdClient::PutIfRevision(const std::string& key, const std::string& value,
                                       int64_t expected_mod_revision, int64_t lease) {
  const std::string what = "put " + QuoteKey(key) + " if at revision " + std::to_string(expected_mod_revision);
  if (expected_mod_revision < 0) return Status::InvalidArgument("etcd: " + what + ": revision is negative");
  etcdserverpb::TxnRequest txn;
  etcdserverpb::Compare& compare = *txn.add_compare();
  compare.set_key(key);
  compare.set_result(etcdserverpb::Compare::EQUAL);
  if (expected_mod_revision == 0) {  // absent: never created (a delete resets create_revision to 0)
    compare.set_target(etcdserverpb::Compare::CREATE);
    compare.set_create_revision(0);
  } else {
    compare.set_target(etcdserverpb::Compare::MOD);
    compare.set_mod_revision(expected_mod_revision);
  }
  etcdserverpb::PutRequest& put = *txn.add_success()->mutable_request_put();
  put.set_key(key);
  put.set_value(value);
  put.set_lease(lease);
  return CompareAndSwap(*endpoints_, what, txn);
}

Result<bool> EtcdClient::DeleteIfRevision(const std::string& key, int64_t expected_mod_revision) {
  const std::string what = "delete " + QuoteKey(key) + " if at revision " + std::to_string(expected_mod_revision);
  if (expected_mod_revision <= 0) return Status::InvalidArgument("etcd: " + what + ": revision must be positive");
  etcdserverpb::TxnRequest txn;
  etcdserverpb::Compare& compare = *txn.add_compare();
  compare.set_key(key);
  compare.set_result(etcdserverpb::Compare::EQUAL);
  compare.set_target(etcdserverpb::Compare::MOD);
  compare.set_mod_revision(expected_mod_revision);
  txn.add_success()->mutable_request_delete_range()->set_key(key);
  return CompareAndSwap(*endpoints_, what, txn);
}

Status EtcdClient::Compact(int64_t revision) {
  etcdserverpb::CompactionRequest request;
  request.set_revision(revision);
  return endpoints_->Call("compact at revision " + std::to_string(revision),
                          [&](size_t i, grpc::ClientContext* context) {
                            etcdserverpb::CompactionResponse response;
                            return endpoints_->kv(i).Compact(context, request, &response);
                          });
}

Result<EtcdLease> EtcdClient::GrantLease(int64_t ttl_seconds) {
  const std::string what = "grant a lease of " + std::to_string(ttl_seconds) + " s";
  if (ttl_seconds <= 0) return Status::InvalidArgument("etcd: " + what + ": the TTL must be positive");
  EtcdLease lease;
  lease.granted_at = Clock::now();  // before any attempt: the lease cannot expire earlier than this plus its TTL
  etcdserverpb::LeaseGrantRequest request;
  request.set_ttl(ttl_seconds);
  etcdserverpb::LeaseGrantResponse response;
  size_t answered = 0;
  const Status status = endpoints_->Call(what, [&](size_t i, grpc::ClientContext* context) {
    response.Clear();
    answered = i;
    return endpoints_->lease(i).LeaseGrant(context, request, &response);
  });
  if (!status.ok()) return status;
  if (!response.error().empty()) {
    return Status::Internal("etcd " + endpoints_->endpoint(answered) + ": " + what + ": " + response.error());
  }
  lease.id = response.id();
  lease.ttl_seconds = response.ttl();
  spdlog::debug("etcd: {} granted, TTL {} s", LeaseName(lease.id), lease.ttl_seconds);
  return lease;
}

Status EtcdClient::RevokeLease(int64_t lease_id) {
  etcdserverpb::LeaseRevokeRequest request;
  request.set_id(lease_id);
  Status unsure;
  const Status status = endpoints_->Call(
      "revoke " + LeaseName(lease_id),
      [&](size_t i, grpc::ClientContext* context) {
        etcdserverpb::LeaseRevokeResponse response;
        return endpoints_->lease(i).LeaseRevoke(context, request, &response);
      },
      &unsure);
  // Not found after an attempt that may have been applied: that attempt revoked it.
  if (status.code() == Status::Code::kNotFound && !unsure.ok()) return Status::Ok();
  return status;
}

std::unique_ptr<LeaseKeeper> EtcdClient::KeepAlive(const EtcdLease& lease, LeaseKeeper::LostCallback on_lost) const {
  return std::make_unique<LeaseKeeper>(endpoints_, lease, std::move(on_lost));
}

std::unique_ptr<PrefixWatcher> EtcdClient::WatchPrefix(const std::string& prefix, int64_t start_revision,
                                                       PrefixWatcher::BatchCallback on_batch) const {
  return std::make_unique<PrefixWatcher>(endpoints_, prefix, start_revision, std::move(on_batch));
}

std::string EtcdClient::current_endpoint() const { return endpoints_->endpoint(endpoints_->preferred()); }

}  // namespace lmd::server::cluster
