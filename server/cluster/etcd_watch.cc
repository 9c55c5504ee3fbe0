#include "server/cluster/etcd_watch.h"

#include <algorithm>

#include <spdlog/spdlog.h>

#include "server/cluster/etcd_endpoints.h"

namespace lmd::server::cluster {
namespace {

// Pause before reopening a stream that failed before etcd accepted the
// watch, doubled on each failure in a row.
constexpr auto kMinPause = std::chrono::milliseconds(100);
constexpr auto kMaxPause = std::chrono::milliseconds(1000);

}  // namespace

PrefixWatcher::PrefixWatcher(std::shared_ptr<EtcdEndpoints> endpoints, std::string prefix, int64_t start_revision,
                             BatchCallback on_batch)
    : endpoints_(std::move(endpoints)),
      prefix_(std::move(prefix)),
      on_batch_(std::move(on_batch)),
      next_revision_(std::max<int64_t>(start_revision, 0)),
      thread_([this] { Run(); }) {}

PrefixWatcher::~PrefixWatcher() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
    if (stream_ != nullptr) stream_->TryCancel();
  }
  thread_.join();
}

int64_t PrefixWatcher::next_revision() const {
  std::lock_guard<std::mutex> lock(mu_);
  return next_revision_;
}

void PrefixWatcher::Run() {
  size_t i = endpoints_->preferred();
  auto pause = kMinPause;
  bool reload = false;
  while (!stopping()) {
    Status failure;
    bool healthy = false;  // the endpoint had been working: its failure is news
    if (reload) {
      failure = Reload(i);
      reload = !failure.ok();
    }
    if (!reload) {
      const StreamEnd end = Follow(i);
      if (stopping()) return;
      if (end.compacted) {
        reload = true;
        continue;  // at the same endpoint, at once
      }
      failure = end.status;
      healthy = end.created;
    }
    const size_t next = (i + 1) % endpoints_->size();
    if (healthy) {
      spdlog::warn("{}; watching again at {} from revision {}", failure.message(), endpoints_->endpoint(next),
                   next_revision());
      pause = kMinPause;
    } else {
      spdlog::debug("{}; trying {} in {} ms", failure.message(), endpoints_->endpoint(next), pause.count());
      if (!endpoints_->WaitPolling(Clock::now() + pause, [this] { return stopping(); })) return;
      pause = std::min(pause * 2, kMaxPause);
    }
    i = next;
  }
}

PrefixWatcher::StreamEnd PrefixWatcher::Follow(size_t i) {
  const std::string what = "watch prefix " + QuoteKey(prefix_);
  grpc::ClientContext context;
  context.AddMetadata(kRequireLeaderKey, kRequireLeaderValue);
  etcdserverpb::WatchRequest request;
  etcdserverpb::WatchCreateRequest& create = *request.mutable_create_request();
  create.set_key(PrefixRangeKey(prefix_));
  create.set_range_end(PrefixRangeEnd(prefix_));
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stopping_) return {};
    stream_ = &context;
    create.set_start_revision(next_revision_);
  }
  auto stream = endpoints_->watch(i).Watch(&context);
  StreamEnd end;
  etcdserverpb::WatchResponse response;
  bool ours = false;  // we end the stream: its status says nothing
  if (stream->Write(request)) {
    while (!ours && stream->Read(&response)) {
      if (response.compact_revision() != 0) {
        spdlog::warn("etcd {}: history before revision {} is compacted; the watcher of prefix {} at revision {} "
                     "reloads it",
                     endpoints_->endpoint(i), response.compact_revision(), QuoteKey(prefix_), next_revision());
        end.compacted = ours = true;
      } else if (response.canceled()) {
        end.status = endpoints_->ToStatus(
            i, what, grpc::Status(grpc::StatusCode::CANCELLED, "etcd canceled it: " + response.cancel_reason()));
        ours = true;
      } else if (response.created()) {
        end.created = true;
        std::lock_guard<std::mutex> lock(mu_);
        if (next_revision_ == 0) next_revision_ = response.header().revision() + 1;
      } else {
        WatchBatch batch;
        const int64_t from = next_revision();
        for (const mvccpb::Event& event : response.events()) {
          if (event.kv().mod_revision() < from) continue;  // delivered already
          batch.events.push_back({event.type() == mvccpb::Event::DELETE ? WatchEvent::Type::kDelete
                                                                         : WatchEvent::Type::kPut,
                                  event.kv().key(), event.kv().value(), event.kv().mod_revision()});
        }
        if (batch.events.empty()) continue;  // a progress report
        batch.revision = batch.events.back().mod_revision;
        {
          std::lock_guard<std::mutex> lock(mu_);
          next_revision_ = batch.revision + 1;
        }
        on_batch_(batch);
      }
    }
  }
  if (ours) context.TryCancel();
  const grpc::Status status = stream->Finish();
  {
    std::lock_guard<std::mutex> lock(mu_);
    stream_ = nullptr;
  }
  if (!ours) {
    end.status = endpoints_->ToStatus(
        i, what, status.ok() ? grpc::Status(grpc::StatusCode::UNAVAILABLE, "the stream ended") : status);
  }
  return end;
}

Status PrefixWatcher::Reload(size_t i) {
  grpc::ClientContext context;
  context.set_deadline(
      GrpcDeadline(Clock::now() + std::chrono::milliseconds(endpoints_->options().call_timeout_ms)));
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stopping_) return Status::Cancelled("etcd: the watcher of prefix " + QuoteKey(prefix_) + " is stopping");
    stream_ = &context;
  }
  etcdserverpb::RangeRequest request;
  request.set_key(PrefixRangeKey(prefix_));
  request.set_range_end(PrefixRangeEnd(prefix_));
  etcdserverpb::RangeResponse response;
  const grpc::Status status = endpoints_->kv(i).Range(&context, request, &response);
  {
    std::lock_guard<std::mutex> lock(mu_);
    stream_ = nullptr;
  }
  if (!status.ok()) return endpoints_->ToStatus(i, "reload prefix " + QuoteKey(prefix_), status);
  WatchBatch batch;
  batch.reset = true;
  batch.revision = response.header().revision();
  for (const mvccpb::KeyValue& kv : response.kvs()) {
    batch.events.push_back({WatchEvent::Type::kPut, kv.key(), kv.value(), kv.mod_revision()});
  }
  {
    std::lock_guard<std::mutex> lock(mu_);
    next_revision_ = batch.revision + 1;
  }
  on_batch_(batch);
  return Status::Ok();
}

bool PrefixWatcher::stopping() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stopping_;
}

}  // namespace lmd::server::cluster
