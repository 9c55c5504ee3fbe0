#include "client/lmd_client.h"

#include <grpcpp/create_channel.h>

namespace lmd::client {

LmdClient::LmdClient(const ClientOptions& options) : options_(options) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(options.max_message_bytes);
  args.SetMaxSendMessageSize(options.max_message_bytes);
  stub_ = v1::LmdService::NewStub(
      grpc::CreateCustomChannel(options.target, grpc::InsecureChannelCredentials(), args));
}

std::unique_ptr<grpc::ClientContext> LmdClient::NewContext() const {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + options_.deadline);
  return context;
}

grpc::Status LmdClient::InsertMaps(const v1::InsertMapsRequest& request, v1::InsertMapsResponse* response) const {
  return stub_->InsertMaps(NewContext().get(), request, response);
}

grpc::Status LmdClient::StreamInsertMaps(const std::vector<v1::InsertMapRequest>& requests,
                                         v1::InsertMapsResponse* response) const {
  auto context = NewContext();
  auto writer = stub_->StreamInsertMaps(context.get(), response);
  for (const auto& request : requests) {
    if (!writer->Write(request)) break;  // the server ended the stream; Finish says why
  }
  writer->WritesDone();
  return writer->Finish();
}

grpc::Status LmdClient::GetMap(const v1::GetMapRequest& request, v1::GetMapResponse* response) const {
  return stub_->GetMap(NewContext().get(), request, response);
}

grpc::Status LmdClient::DeleteMap(const v1::DeleteMapRequest& request) const {
  v1::DeleteMapResponse response;
  return stub_->DeleteMap(NewContext().get(), request, &response);
}

grpc::Status LmdClient::ListMaps(const v1::ListMapsRequest& request, v1::ListMapsResponse* response) const {
  return stub_->ListMaps(NewContext().get(), request, response);
}

grpc::Status LmdClient::Retrieve(const v1::RetrieveRequest& request, v1::RetrieveResponse* response) const {
  return stub_->Retrieve(NewContext().get(), request, response);
}

grpc::Status LmdClient::DetectChanges(const v1::DetectChangesRequest& request,
                                      v1::DetectChangesResponse* response) const {
  return stub_->DetectChanges(NewContext().get(), request, response);
}

grpc::Status LmdClient::ListCollections(v1::ListCollectionsResponse* response) const {
  return stub_->ListCollections(NewContext().get(), v1::ListCollectionsRequest(), response);
}

grpc::Status LmdClient::Stats(const v1::StatsRequest& request, v1::StatsResponse* response) const {
  return stub_->Stats(NewContext().get(), request, response);
}

}  // namespace lmd::client
