#include "server/cluster/etcd_endpoints.h"

#include <algorithm>

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

namespace lmd::server::cluster {
namespace {

grpc::ChannelArguments ChannelArgs() {
  grpc::ChannelArguments args;
  // A member that comes back is reconnected within a second (gRPC's default
  // backoff grows to two minutes). The minimum is also gRPC's connect
  // timeout: a member that takes a connection but does not answer (stopped)
  // is given up on after a second.
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 100);
  args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 1000);
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 1000);
  // Pings find a hung member under a long-lived watch stream within 15 s.
  // etcd refuses pings more often than every 5 s (--grpc-keepalive-min-time).
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, 10000);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 5000);
  args.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);  // a quiet watch is still pinged
  // A prefix read returns the whole prefix in one message.
  args.SetMaxReceiveMessageSize(-1);
  return args;
}

// How long WaitPolling waits on one channel before it checks `stop` again.
constexpr auto kPollSlice = std::chrono::milliseconds(50);

bool Retryable(grpc::StatusCode code) {
  return code == grpc::StatusCode::UNAVAILABLE || code == grpc::StatusCode::DEADLINE_EXCEEDED;
}

}  // namespace

EtcdEndpoints::EtcdEndpoints(const EtcdClientOptions& options) : options_(options) {
  const grpc::ChannelArguments args = ChannelArgs();
  for (const std::string& endpoint : options_.endpoints) {
    Member member;
    member.channel = grpc::CreateCustomChannel(endpoint, grpc::InsecureChannelCredentials(), args);
    member.kv = etcdserverpb::KV::NewStub(member.channel);
    member.watch = etcdserverpb::Watch::NewStub(member.channel);
    member.lease = etcdserverpb::Lease::NewStub(member.channel);
    members_.push_back(std::move(member));
  }
}

bool EtcdEndpoints::Connected(size_t i, Clock::time_point deadline) const {
  grpc::Channel& channel = *members_[i].channel;
  grpc_connectivity_state state = channel.GetState(/*try_to_connect=*/true);
  while (state != GRPC_CHANNEL_READY) {
    if (state == GRPC_CHANNEL_TRANSIENT_FAILURE || state == GRPC_CHANNEL_SHUTDOWN) return false;
    if (!channel.WaitForStateChange(state, GrpcDeadline(deadline))) return false;
    state = channel.GetState(/*try_to_connect=*/true);
  }
  return true;
}

bool EtcdEndpoints::WaitPolling(Clock::time_point until, const std::function<bool()>& stop) const {
  for (size_t slice = 0;; ++slice) {
    if (stop && stop()) return false;
    const auto now = Clock::now();
    if (now >= until) return true;
    // A thread waiting on any channel polls every channel's sockets.
    grpc::Channel& channel = *members_[slice % members_.size()].channel;
    channel.WaitForStateChange(channel.GetState(/*try_to_connect=*/false),
                               GrpcDeadline(std::min<Clock::time_point>(until, now + kPollSlice)));
  }
}

Status EtcdEndpoints::Call(const std::string& what, const Attempt& attempt, Status* unsure) {
  const auto timeout = std::chrono::milliseconds(options_.call_timeout_ms);
  const auto give_up = Clock::now() + std::chrono::milliseconds(options_.retry_budget_ms);
  const size_t first = preferred();
  Status last;
  Status first_unsure;
  auto pause = std::chrono::milliseconds(50);
  for (int round = 0;; ++round) {
    for (size_t k = 0; k < size(); ++k) {
      const size_t i = (first + k) % size();
      if ((round > 0 || k > 0) && Clock::now() >= give_up) break;
      const auto deadline = Clock::now() + timeout;
      if (!Connected(i, deadline)) {
        last = Status::Unavailable("etcd " + endpoint(i) + " unavailable: " + what + ": cannot connect");
        spdlog::debug("{}; trying the next endpoint", last.message());
        continue;
      }
      grpc::ClientContext context;
      context.set_deadline(GrpcDeadline(deadline));
      context.AddMetadata(kRequireLeaderKey, kRequireLeaderValue);
      const grpc::Status status = attempt(i, &context);
      if (status.ok()) {
        if (i != first) {
          spdlog::warn("etcd: calls move from {} to {} ({})", endpoint(first), endpoint(i), last.message());
          preferred_.store(i);
        }
        if (unsure != nullptr) *unsure = first_unsure;
        return Status::Ok();
      }
      last = ToStatus(i, what, status);
      if (!Retryable(status.error_code())) {
        if (unsure != nullptr) *unsure = first_unsure;
        return last;
      }
      // It was sent, so etcd may have applied it; unless the member refused it
      // up front for want of a leader (etcd's ErrGRPCNoLeader, under "hasleader").
      if (first_unsure.ok() && status.error_message() != "etcdserver: no leader") first_unsure = last;
      spdlog::debug("{}; trying the next endpoint", last.message());
    }
    const auto now = Clock::now();
    if (now >= give_up) break;
    WaitPolling(std::min<Clock::time_point>(now + pause, give_up));
    pause = std::min(pause * 2, std::chrono::milliseconds(500));
  }
  if (unsure != nullptr) *unsure = first_unsure;
  return last;
}

Status EtcdEndpoints::ToStatus(size_t i, const std::string& what, const grpc::Status& status) const {
  const std::string where = "etcd " + endpoint(i);
  const std::string tail = what + ": " + status.error_message();
  switch (status.error_code()) {
    case grpc::StatusCode::OK: return Status::Ok();
    case grpc::StatusCode::UNAVAILABLE: return Status::Unavailable(where + " unavailable: " + tail);
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return Status::DeadlineExceeded(where + " timed out after " + std::to_string(options_.call_timeout_ms) +
                                      " ms: " + tail);
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::OUT_OF_RANGE: return Status::InvalidArgument(where + ": " + tail);
    case grpc::StatusCode::NOT_FOUND: return Status::NotFound(where + ": " + tail);
    case grpc::StatusCode::ALREADY_EXISTS: return Status::AlreadyExists(where + ": " + tail);
    case grpc::StatusCode::FAILED_PRECONDITION: return Status::FailedPrecondition(where + ": " + tail);
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return Status::ResourceExhausted(where + ": " + tail);
    case grpc::StatusCode::PERMISSION_DENIED: return Status::PermissionDenied(where + ": " + tail);
    case grpc::StatusCode::UNAUTHENTICATED: return Status::Unauthenticated(where + ": " + tail);
    case grpc::StatusCode::CANCELLED: return Status::Cancelled(where + ": " + tail);
    case grpc::StatusCode::DATA_LOSS: return Status::Corruption(where + ": " + tail);
    default: return Status::Internal(where + ": " + tail);
  }
}

std::chrono::system_clock::time_point GrpcDeadline(Clock::time_point deadline) {
  return std::chrono::system_clock::now() +
         std::chrono::duration_cast<std::chrono::system_clock::duration>(deadline - Clock::now());
}

std::string PrefixRangeEnd(const std::string& prefix) {
  std::string end = prefix;
  while (!end.empty()) {
    const auto last = static_cast<unsigned char>(end.back());
    if (last < 0xff) {
      end.back() = static_cast<char>(last + 1);
      return end;
    }
    end.pop_back();
  }
  return std::string(1, '\0');
}

std::string PrefixRangeKey(const std::string& prefix) { return prefix.empty() ? std::string(1, '\0') : prefix; }

std::string QuoteKey(const std::string& key) {
  std::string quoted = "\"";
  for (const char c : key) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7f && c != '"' && c != '\\') {
      quoted += c;
    } else {
      quoted += fmt::format("\\x{:02x}", byte);
    }
  }
  return quoted + "\"";
}

std::string LeaseName(int64_t lease_id) { return fmt::format("lease {:x}", lease_id); }

}  // namespace lmd::server::cluster
