#include "client/lmd_client.h"

#include <fstream>
#include <sstream>
#include <thread>

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

namespace lmd::client {
namespace {

Result<std::string> ReadPem(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Status::InvalidArgument("cannot read " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

Result<std::shared_ptr<grpc::ChannelCredentials>> MakeCredentials(const ClientOptions& options) {
  if (options.tls_root_ca_file.empty()) return grpc::InsecureChannelCredentials();
  grpc::SslCredentialsOptions ssl;
  Result<std::string> ca = ReadPem(options.tls_root_ca_file);
  if (!ca.ok()) return ca.status();
  ssl.pem_root_certs = *ca;
  if (!options.tls_cert_file.empty()) {
    Result<std::string> cert = ReadPem(options.tls_cert_file);
    if (!cert.ok()) return cert.status();
    Result<std::string> key = ReadPem(options.tls_key_file);
    if (!key.ok()) return key.status();
    ssl.pem_cert_chain = *cert;
    ssl.pem_private_key = *key;
  }
  return grpc::SslCredentials(ssl);
}

}  // namespace

Result<std::unique_ptr<LmdClient>> LmdClient::Create(const ClientOptions& options) {
  Result<std::shared_ptr<grpc::ChannelCredentials>> credentials = MakeCredentials(options);
  if (!credentials.ok()) return credentials.status();
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(options.max_message_bytes);
  args.SetMaxSendMessageSize(options.max_message_bytes);
  if (!options.tls_server_name.empty()) args.SetSslTargetNameOverride(options.tls_server_name);
  std::unique_ptr<LmdClient> client(new LmdClient(options));
  client->stub_ = v1::LmdService::NewStub(grpc::CreateCustomChannel(options.target, *credentials, args));
  return client;
}

std::unique_ptr<grpc::ClientContext> LmdClient::NewContext(const std::string& collection,
                                                           std::chrono::system_clock::time_point deadline) const {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(deadline);
  if (!options_.token.empty()) context->AddMetadata("authorization", "Bearer " + options_.token);
  if (!collection.empty()) context->AddMetadata("x-lmd-collection", collection);
  return context;
}

grpc::Status LmdClient::WithRetries(const std::string& collection,
                                    const std::function<grpc::Status(grpc::ClientContext*)>& call) const {
  const auto deadline = std::chrono::system_clock::now() + options_.deadline;
  auto backoff = options_.initial_backoff;
  for (int attempt = 1;; ++attempt) {
    auto context = NewContext(collection, deadline);
    const grpc::Status status = call(context.get());
    if (status.error_code() != grpc::StatusCode::UNAVAILABLE || attempt >= options_.max_attempts ||
        std::chrono::system_clock::now() + backoff >= deadline) {
      return status;
    }
    std::this_thread::sleep_for(backoff);
    backoff = std::min<std::chrono::milliseconds>(backoff * 2, std::chrono::seconds(2));
  }
}

grpc::Status LmdClient::InsertMaps(const v1::InsertMapsRequest& request, v1::InsertMapsResponse* response) const {
  const std::string collection = request.maps_size() > 0 ? request.maps(0).metadata().collection() : "";
  return WithRetries(collection, [&](grpc::ClientContext* c) { return stub_->InsertMaps(c, request, response); });
}

grpc::Status LmdClient::StreamInsertMaps(const std::vector<v1::InsertMapRequest>& requests,
                                         v1::InsertMapsResponse* response) const {
  const std::string collection = requests.empty() ? "" : requests.front().metadata().collection();
  auto context = NewContext(collection, std::chrono::system_clock::now() + options_.deadline);
  auto writer = stub_->StreamInsertMaps(context.get(), response);
  for (const auto& request : requests) {
    if (!writer->Write(request)) break;  // the server ended the stream; Finish says why
  }
  writer->WritesDone();
  return writer->Finish();
}

grpc::Status LmdClient::GetMap(const v1::GetMapRequest& request, v1::GetMapResponse* response) const {
  return WithRetries(request.collection(), [&](grpc::ClientContext* c) { return stub_->GetMap(c, request, response); });
}

grpc::Status LmdClient::DeleteMap(const v1::DeleteMapRequest& request) const {
  v1::DeleteMapResponse response;
  return WithRetries(request.collection(),
                     [&](grpc::ClientContext* c) { return stub_->DeleteMap(c, request, &response); });
}

grpc::Status LmdClient::ListMaps(const v1::ListMapsRequest& request, v1::ListMapsResponse* response) const {
  return WithRetries(request.collection(),
                     [&](grpc::ClientContext* c) { return stub_->ListMaps(c, request, response); });
}

grpc::Status LmdClient::Retrieve(const v1::RetrieveRequest& request, v1::RetrieveResponse* response) const {
  return WithRetries(request.collection(),
                     [&](grpc::ClientContext* c) { return stub_->Retrieve(c, request, response); });
}

grpc::Status LmdClient::DetectChanges(const v1::DetectChangesRequest& request,
                                      v1::DetectChangesResponse* response) const {
  return WithRetries(request.collection(),
                     [&](grpc::ClientContext* c) { return stub_->DetectChanges(c, request, response); });
}

grpc::Status LmdClient::ListCollections(v1::ListCollectionsResponse* response) const {
  return WithRetries("", [&](grpc::ClientContext* c) {
    return stub_->ListCollections(c, v1::ListCollectionsRequest(), response);
  });
}

grpc::Status LmdClient::Stats(const v1::StatsRequest& request, v1::StatsResponse* response) const {
  return WithRetries(request.collection(), [&](grpc::ClientContext* c) { return stub_->Stats(c, request, response); });
}

grpc::Status LmdClient::Backup(const v1::BackupRequest& request, v1::BackupResponse* response) const {
  return WithRetries("", [&](grpc::ClientContext* c) { return stub_->Backup(c, request, response); });
}

}  // namespace lmd::client
