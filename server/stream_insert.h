// StreamInsertReactor: the client-streaming insert. Each message is one map:
// authorized, validated and written on the worker pool, one at a time and in
// stream order, before the next message is read. The first failure ends the
// call with its status; maps written before it stay stored and are listed in
// the response. The messages are read as bytes and parsed here: gRPC's typed
// reader ends the stream at a message that does not parse as if the client
// had finished it, and the call would end OK with the maps after it lost.
#pragma once

#include <chrono>
#include <string>

#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/server_callback.h>

#include "lmd/v1/lmd.pb.h"
#include "server/call_runner.h"

namespace lmd::server {

class LmdServiceImpl;

class StreamInsertReactor : public grpc::ServerReadReactor<grpc::ByteBuffer> {
 public:
  // `response`: where the InsertMapsResponse is serialized once the stream ends well.
  StreamInsertReactor(grpc::CallbackServerContext* context, grpc::ByteBuffer* response, LmdServiceImpl* service,
                      CallRunner* runner);

  void OnReadDone(bool ok) override;
  void OnDone() override { delete this; }

 private:
  void Store();  // runs on the worker pool
  void Done(const Status& status);

  grpc::CallbackServerContext* const context_;
  grpc::ByteBuffer* const wire_response_;
  LmdServiceImpl* const service_;
  CallRunner* const runner_;
  const std::string request_id_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  grpc::ByteBuffer wire_request_;  // the message being read
  v1::InsertMapRequest request_;   // ... once parsed
  v1::InsertMapsResponse response_;
  size_t index_ = 0;
};

}  // namespace lmd::server
