#include "server/cluster/lease_keeper.h"

#include <algorithm>

#include <spdlog/spdlog.h>

#include "server/cluster/etcd_endpoints.h"

namespace lmd::server::cluster {
namespace {

// Pause before a renewal at the next endpoint after one failed.
constexpr auto kRetryPause = std::chrono::milliseconds(100);

}  // namespace

LeaseKeeper::LeaseKeeper(std::shared_ptr<EtcdEndpoints> endpoints, EtcdLease lease, LostCallback on_lost)
    : endpoints_(std::move(endpoints)), lease_(lease), on_lost_(std::move(on_lost)), thread_([this] { Run(); }) {}

LeaseKeeper::~LeaseKeeper() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
    if (renewal_ != nullptr) renewal_->TryCancel();
  }
  wake_.notify_all();
  // From on_lost the thread is ours: it returns without touching the keeper.
  if (thread_.get_id() == std::this_thread::get_id()) {
    thread_.detach();
  } else {
    thread_.join();
  }
}

bool LeaseKeeper::lost() const {
  std::lock_guard<std::mutex> lock(mu_);
  return lost_;
}

void LeaseKeeper::Run() {
  const auto ttl = std::chrono::seconds(lease_.ttl_seconds);
  const auto interval = std::chrono::milliseconds(lease_.ttl_seconds * 1000 / 3);
  const auto timeout = std::chrono::milliseconds(endpoints_->options().call_timeout_ms);
  Clock::time_point expires = lease_.granted_at + ttl;
  size_t i = endpoints_->preferred();
  Status last_error;
  while (true) {
    const Clock::time_point sent = Clock::now();
    if (sent >= expires) {
      return Lose(Status::DeadlineExceeded("etcd: " + LeaseName(lease_.id) + " (TTL " +
                                           std::to_string(lease_.ttl_seconds) +
                                           " s) expired before it could be renewed: " + last_error.message()));
    }
    const Result<int64_t> renewed = Renew(i, std::min(sent + timeout, expires));
    if (stopping()) return;  // the renewal was cancelled
    if (renewed.ok()) {
      if (*renewed <= 0) {
        return Lose(Status::NotFound("etcd " + endpoints_->endpoint(i) + ": " + LeaseName(lease_.id) +
                                     " has expired or was revoked (keep-alive answered TTL " +
                                     std::to_string(*renewed) + ")"));
      }
      // etcd renewed it when it got the request, which was after `sent`.
      expires = sent + std::chrono::seconds(*renewed);
      if (!last_error.ok()) {
        spdlog::warn("etcd: {} renewed at {} again", LeaseName(lease_.id), endpoints_->endpoint(i));
        last_error = Status::Ok();
      }
      if (!SleepUntil(sent + interval)) return;
      continue;
    }
    // The first failure after a success is news; retries until expiry are not.
    const size_t next = (i + 1) % endpoints_->size();
    if (last_error.ok()) {
      spdlog::warn("{}; renewing at {} next", renewed.status().message(), endpoints_->endpoint(next));
    } else {
      spdlog::debug("{}; renewing at {} next", renewed.status().message(), endpoints_->endpoint(next));
    }
    last_error = renewed.status();
    i = next;
    if (!endpoints_->WaitPolling(std::min(Clock::now() + kRetryPause, expires), [this] { return stopping(); })) return;
  }
}

Result<int64_t> LeaseKeeper::Renew(size_t i, Clock::time_point deadline) {
  grpc::ClientContext context;
  context.set_deadline(GrpcDeadline(deadline));
  context.AddMetadata(kRequireLeaderKey, kRequireLeaderValue);
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stopping_) return Status::Cancelled("etcd: the keeper of " + LeaseName(lease_.id) + " is stopping");
    renewal_ = &context;
  }
  auto stream = endpoints_->lease(i).LeaseKeepAlive(&context);
  etcdserverpb::LeaseKeepAliveRequest request;
  request.set_id(lease_.id);
  etcdserverpb::LeaseKeepAliveResponse response;
  const bool answered = stream->Write(request) && stream->WritesDone() && stream->Read(&response);
  grpc::Status status = stream->Finish();
  {
    std::lock_guard<std::mutex> lock(mu_);
    renewal_ = nullptr;
  }
  if (answered) return response.ttl();
  if (status.ok()) status = grpc::Status(grpc::StatusCode::UNAVAILABLE, "the stream ended without an answer");
  return endpoints_->ToStatus(i, "keep-alive of " + LeaseName(lease_.id), status);
}

bool LeaseKeeper::stopping() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stopping_;
}

bool LeaseKeeper::SleepUntil(Clock::time_point until) {
  std::unique_lock<std::mutex> lock(mu_);
  return !wake_.wait_until(lock, until, [this] { return stopping_; });
}

void LeaseKeeper::Lose(const Status& why) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stopping_) return;
    lost_ = true;
  }
  spdlog::warn("{}", why.message());
  // on_lost may destroy the keeper: keep the callback here, touch nothing after.
  const LostCallback on_lost = std::move(on_lost_);
  if (on_lost) on_lost(why);
}

}  // namespace lmd::server::cluster
