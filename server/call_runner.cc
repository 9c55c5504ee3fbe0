#include "server/call_runner.h"

#include <chrono>

#include <spdlog/spdlog.h>

#include "proto/metadata_keys.h"
#include "server/grpc_status.h"
#include "server/validate.h"

namespace lmd::server {
namespace {

double MillisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

std::string Metadata(const grpc::CallbackServerContext* context, const std::string& key) {
  const auto& metadata = context->client_metadata();
  const auto it = metadata.find(key);
  return it == metadata.end() ? "" : std::string(it->second.data(), it->second.size());
}

}  // namespace

CallRunner::CallRunner(WorkerPool* pool, const TokenAuthorizer* auth, CallMetrics* metrics)
    : pool_(pool), auth_(auth), metrics_(metrics) {}

std::string CallRunner::Authorization(const grpc::CallbackServerContext* context) {
  return Metadata(context, "authorization");
}

Status CallRunner::Authorize(const grpc::CallbackServerContext* context, const std::string& collection,
                             Access access) const {
  const std::string authorization = Authorization(context);
  Status status = auth_->Authenticate(authorization);
  if (status.ok()) status = ValidateCollectionName(collection);
  return status.ok() ? auth_->Check(authorization, collection, access) : status;
}

Status CallRunner::AuthorizeServerWide(const grpc::CallbackServerContext* context, Access access) const {
  return auth_->Check(Authorization(context), "", access);
}

std::string CallRunner::RequestId(const grpc::CallbackServerContext* context) {
  std::string id = Metadata(context, "x-request-id");
  if (id.empty() || id.size() > 64) id = "r" + std::to_string(next_request_id_++);
  return id;
}

void CallRunner::Finished(const char* method, const std::string& request_id, const std::string& collection,
                          const grpc::Status& status, double latency_ms) {
  metrics_->Record(method, status.error_code(), latency_ms);
  const auto level = status.ok() ? spdlog::level::debug
                     : status.error_code() == grpc::StatusCode::INTERNAL ? spdlog::level::err
                                                                         : spdlog::level::info;
  spdlog::log(level, "call rid={} method={} collection={} code={} ms={:.2f}{}{}", request_id, method,
              collection.empty() ? "-" : collection, static_cast<int>(status.error_code()), latency_ms,
              status.ok() ? "" : " error=", status.error_message());
}

grpc::ServerUnaryReactor* CallRunner::Unary(grpc::CallbackServerContext* context, const char* method,
                                            const std::string& collection, const Status& allowed,
                                            std::function<Status()> work) {
  const auto start = std::chrono::steady_clock::now();
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  const std::string request_id = RequestId(context);
  auto finish = [this, reactor, method, request_id, collection, start](const grpc::Status& status) {
    Finished(method, request_id, collection, status, MillisecondsSince(start));
    reactor->Finish(status);
  };

  if (!allowed.ok()) {
    finish(ToGrpcStatus(allowed));
    return reactor;
  }
  auto task = [context, work = std::move(work), finish] {
    if (context->IsCancelled()) return finish(grpc::Status(grpc::StatusCode::CANCELLED, "call cancelled"));
    if (std::chrono::system_clock::now() > context->deadline()) {
      return finish(grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "deadline passed while queued"));
    }
    finish(ToGrpcStatus(work()));
  };
  if (!pool_->TrySubmit(std::move(task))) {
    context->AddTrailingMetadata(kBusyMetadata, "1");
    finish(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                        "server busy: max_queued_calls calls are already waiting; retry later"));
  }
  return reactor;
}

}  // namespace lmd::server
