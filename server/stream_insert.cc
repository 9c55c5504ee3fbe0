#include "server/stream_insert.h"

#include <grpcpp/impl/codegen/proto_utils.h>

#include "proto/metadata_keys.h"
#include "server/grpc_status.h"
#include "server/lmd_service.h"

namespace lmd::server {

StreamInsertReactor::StreamInsertReactor(grpc::CallbackServerContext* context, grpc::ByteBuffer* response,
                                         LmdServiceImpl* service, CallRunner* runner)
    : context_(context),
      wire_response_(response),
      service_(service),
      runner_(runner),
      request_id_(runner->RequestId(context)) {
  StartRead(&wire_request_);
}

void StreamInsertReactor::OnReadDone(bool ok) {
  if (!ok) {  // the client finished the stream (or the call was cancelled)
    Done(context_->IsCancelled() ? Status::Cancelled("call cancelled") : Status::Ok());
    return;
  }
  request_.Clear();
  if (!grpc::SerializationTraits<v1::InsertMapRequest>::Deserialize(&wire_request_, &request_).ok()) {
    Done(Status::InvalidArgument("message " + std::to_string(index_) + " of the stream does not parse as " +
                                 v1::InsertMapRequest::descriptor()->full_name()));
    return;
  }
  if (!runner_->pool().TrySubmit([this] { Store(); })) {
    context_->AddTrailingMetadata(kBusyMetadata, "1");
    Done(Status::ResourceExhausted("server busy: max_queued_calls calls are already waiting; retry later"));
  }
}

void StreamInsertReactor::Store() {
  Status status = runner_->Authorize(context_, request_.metadata().collection(), Access::kWrite);
  if (status.ok()) status = service_->Insert({&request_}, index_, request_.request_id(), &response_);
  if (!status.ok()) return Done(status);
  ++index_;
  StartRead(&wire_request_);
}

void StreamInsertReactor::Done(const Status& status) {
  grpc::Status result = ToGrpcStatus(status);
  if (result.ok()) {
    bool own_buffer = false;
    result = grpc::SerializationTraits<v1::InsertMapsResponse>::Serialize(response_, wire_response_, &own_buffer);
  }
  if (!result.ok()) {
    // gRPC sends no response message with an error: say how many of the
    // stream's maps (its first ones, in order) are stored all the same.
    context_->AddTrailingMetadata(kStoredMapsMetadata, std::to_string(index_));
    if (index_ > 0) {
      result = grpc::Status(result.error_code(), result.error_message() + " (the stream's first " +
                                                     std::to_string(index_) + " maps are stored)");
    }
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  runner_->Finished("StreamInsertMaps", request_id_, "", result, ms);
  Finish(result);
}

}  // namespace lmd::server
