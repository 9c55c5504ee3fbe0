// CallRunner: what every RPC does around its own work. It refuses calls the
// handler found unauthorized, queues the work on the worker pool (refusing at once with
// RESOURCE_EXHAUSTED when the queue is full), skips work whose call was
// cancelled or whose deadline passed while it waited, finishes the call,
// and records metrics and one log line with a request id.
#pragma once

#include <atomic>
#include <functional>
#include <string>

#include <grpcpp/support/server_callback.h>
#include <grpcpp/server_context.h>

#include "core/status.h"
#include "server/auth.h"
#include "server/metrics.h"
#include "server/worker_pool.h"

namespace lmd::server {

class CallRunner {
 public:
  // All three must outlive the runner.
  CallRunner(WorkerPool* pool, const TokenAuthorizer* auth, CallMetrics* metrics);

  // Finishes a unary call with `allowed` if it is not OK (the handler's
  // authorization verdict), else runs `work` on the pool and finishes the
  // call with its status. `collection` is for logs ("" if none).
  grpc::ServerUnaryReactor* Unary(grpc::CallbackServerContext* context, const char* method,
                                  const std::string& collection, const Status& allowed,
                                  std::function<Status()> work);

  // The verdict for a call on `collection` with `access` (see auth.h): a
  // missing or unknown token first (UNAUTHENTICATED), then a bad collection
  // name (INVALID_ARGUMENT, e.g. an empty one), then the token's rights.
  Status Authorize(const grpc::CallbackServerContext* context, const std::string& collection, Access access) const;
  // The verdict for a server-wide call (every collection; Backup, Stats).
  Status AuthorizeServerWide(const grpc::CallbackServerContext* context, Access access) const;

  // The "authorization" metadata of a call ("" if absent).
  static std::string Authorization(const grpc::CallbackServerContext* context);

  // The client's "x-request-id" metadata, or a new id "r<number>".
  std::string RequestId(const grpc::CallbackServerContext* context);

  // Records and logs a finished call (also used by streaming calls).
  void Finished(const char* method, const std::string& request_id, const std::string& collection,
                const grpc::Status& status, double latency_ms);

  WorkerPool& pool() { return *pool_; }
  const TokenAuthorizer& auth() const { return *auth_; }

 private:
  WorkerPool* const pool_;
  const TokenAuthorizer* const auth_;
  CallMetrics* const metrics_;
  std::atomic<uint64_t> next_request_id_{1};
};

}  // namespace lmd::server
