#include "client/lmd_client.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <string_view>
#include <thread>

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include "core/util/host_port.h"
#include "proto/metadata_keys.h"

namespace lmd::client {
namespace {

using Stub = v1::LmdService::Stub;

// Whether `text` holds a PEM block whose label ends with `label`
// ("CERTIFICATE"; "PRIVATE KEY" also matches "RSA PRIVATE KEY").
bool HasPemBlock(const std::string& text, const std::string& label) {
  const std::string begin = "-----BEGIN ";
  for (size_t at = text.find(begin); at != std::string::npos; at = text.find(begin, at + 1)) {
    const size_t start = at + begin.size();
    const size_t end = text.find("-----", start);
    if (end == std::string::npos) return false;
    const std::string_view found(text.data() + start, end - start);
    if (found.size() >= label.size() && found.substr(found.size() - label.size()) == label) return true;
  }
  return false;
}

// The PEM file at `path` (`what` it should be, for errors), refused unless it
// holds a `label` block: gRPC would only fail at the first call, with log
// lines and "empty address list" that do not name the file.
Result<std::string> ReadPem(const std::string& path, const std::string& what, const std::string& label) {
  std::ifstream in(path);
  if (!in) return Status::InvalidArgument("cannot read the " + what + " file " + path + ": " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (!in.good() && !in.eof()) return Status::InvalidArgument("cannot read the " + what + " file " + path);
  if (!HasPemBlock(text.str(), label)) {
    return Status::InvalidArgument("the " + what + " file " + path + " holds no PEM " + label +
                                   " (-----BEGIN " + label + "-----)");
  }
  return text.str();
}

Result<std::shared_ptr<grpc::ChannelCredentials>> MakeCredentials(const ClientOptions& options) {
  if (options.tls_cert_file.empty() != options.tls_key_file.empty()) {
    return Status::InvalidArgument("a TLS client certificate (tls_cert_file) and its key (tls_key_file) go together");
  }
  if (options.tls_root_ca_file.empty()) {
    if (!options.tls_cert_file.empty()) {
      return Status::InvalidArgument("a TLS client certificate needs tls_root_ca_file, which turns TLS on");
    }
    return grpc::InsecureChannelCredentials();
  }
  grpc::SslCredentialsOptions ssl;
  Result<std::string> ca = ReadPem(options.tls_root_ca_file, "TLS CA certificate", "CERTIFICATE");
  if (!ca.ok()) return ca.status();
  ssl.pem_root_certs = *ca;
  if (!options.tls_cert_file.empty()) {
    Result<std::string> cert = ReadPem(options.tls_cert_file, "TLS client certificate", "CERTIFICATE");
    if (!cert.ok()) return cert.status();
    Result<std::string> key = ReadPem(options.tls_key_file, "TLS client key", "PRIVATE KEY");
    if (!key.ok()) return key.status();
    ssl.pem_cert_chain = *cert;
    ssl.pem_private_key = *key;
  }
  return grpc::SslCredentials(ssl);
}

// Whether `value` may be sent as a gRPC header value (printable ASCII);
// gRPC aborts the process on any other byte.
bool HeaderSafe(const std::string& value) {
  return std::all_of(value.begin(), value.end(), [](char c) { return c >= 0x20 && c <= 0x7e; });
}

// Whether a failed call is worth repeating: lmdd (or the way to it) was
// unavailable, or lmdd's queue was full.
bool Retryable(const grpc::Status& status, const grpc::ClientContext& context) {
  if (status.error_code() == grpc::StatusCode::UNAVAILABLE) return true;
  if (status.error_code() != grpc::StatusCode::RESOURCE_EXHAUSTED) return false;
  return context.GetServerTrailingMetadata().count(kBusyMetadata) != 0;
}

// `backoff` scaled by a random factor in [0.5, 1.5).
std::chrono::milliseconds Jittered(std::chrono::milliseconds backoff) {
  thread_local std::mt19937 random(std::random_device{}());
  std::uniform_real_distribution<double> factor(0.5, 1.5);
  return std::chrono::milliseconds(static_cast<long>(static_cast<double>(backoff.count()) * factor(random)));
}

// 128 random bits in hex: unique enough that two robots' inserts never share one.
std::string RandomRequestId() {
  thread_local std::mt19937_64 random(std::random_device{}() ^ (uint64_t{std::random_device{}()} << 32));
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%016llx%016llx", static_cast<unsigned long long>(random()),
                static_cast<unsigned long long>(random()));
  return buffer;
}

}  // namespace

Result<std::unique_ptr<LmdClient>> LmdClient::Create(const ClientOptions& options) {
  const Result<HostPort> target = ParseHostPort(options.target, 1, "server address");
  if (!target.ok()) return target.status();
  if (!HeaderSafe(options.token)) return Status::InvalidArgument("the token must be printable ASCII");
  Result<std::shared_ptr<grpc::ChannelCredentials>> credentials = MakeCredentials(options);
  if (!credentials.ok()) return credentials.status();
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(options.max_message_bytes);
  args.SetMaxSendMessageSize(options.max_message_bytes);
  if (!options.tls_server_name.empty()) args.SetSslTargetNameOverride(options.tls_server_name);
  std::unique_ptr<LmdClient> client(new LmdClient(options));
  client->stub_ = v1::LmdService::NewStub(grpc::CreateCustomChannel(options.target, *credentials, args));
  if (options.route) {
    const std::string token = options.token;
    client->routes_ = std::make_unique<ClusterRoutes>(options.target, *credentials, args, [token](grpc::ClientContext* c) {
      c->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
      if (!token.empty()) c->AddMetadata("authorization", "Bearer " + token);
    });
  }
  return client;
}

std::unique_ptr<grpc::ClientContext> LmdClient::NewContext(const std::string& collection,
                                                           std::chrono::system_clock::time_point deadline) const {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(deadline);
  if (!options_.token.empty()) context->AddMetadata("authorization", "Bearer " + options_.token);
  // A name that cannot be a header is no collection: lmdd says why.
  if (!collection.empty() && HeaderSafe(collection)) context->AddMetadata(kCollectionMetadata, collection);
  return context;
}

grpc::Status LmdClient::WithRetries(const std::string& collection, const Call& call, bool retry, int* attempts,
                                    bool write) const {
  const auto deadline = std::chrono::system_clock::now() + options_.deadline;
  auto backoff = options_.initial_backoff;
  for (int attempt = 1;; ++attempt) {
    if (attempts != nullptr) *attempts = attempt;
    auto context = NewContext(collection, deadline);
    Stub* stub = routes_ ? routes_->For(collection, write) : stub_.get();
    const grpc::Status status = call(context.get(), stub);
    if (routes_ && status.error_code() == grpc::StatusCode::UNAVAILABLE) routes_->Failed(stub);
    const auto wait = Jittered(backoff);
    if (!retry || !Retryable(status, *context) || attempt >= options_.max_attempts ||
        std::chrono::system_clock::now() + wait >= deadline) {
      return status;
    }
    std::this_thread::sleep_for(wait);
    backoff = std::min<std::chrono::milliseconds>(backoff * 2, std::chrono::seconds(2));
  }
}

grpc::Status LmdClient::InsertMaps(const v1::InsertMapsRequest& request, v1::InsertMapsResponse* response) const {
  const std::string collection = request.maps_size() > 0 ? request.maps(0).metadata().collection() : "";
  // A retry of maps lmdd names itself is safe with a request id: lmdd
  // answers a repeated one without storing the maps again.
  const bool every_id_given = std::all_of(request.maps().begin(), request.maps().end(),
                                          [](const v1::InsertMapRequest& m) { return !m.metadata().map_id().empty(); });
  v1::InsertMapsRequest with_id;
  const v1::InsertMapsRequest* sent = &request;
  if (!every_id_given && request.request_id().empty()) {
    with_id = request;
    with_id.set_request_id(RandomRequestId());
    sent = &with_id;
  }
  return WithRetries(
      collection, [&](grpc::ClientContext* c, Stub* s) { return s->InsertMaps(c, *sent, response); }, true, nullptr,
      /*write=*/true);
}

grpc::Status LmdClient::StreamInsertMaps(const std::vector<v1::InsertMapRequest>& requests,
                                         v1::InsertMapsResponse* response) const {
  const std::string collection = requests.empty() ? "" : requests.front().metadata().collection();
  // With a request id on every map lmdd names itself, a retried stream
  // stores each map once: the maps stored before the failure are replayed.
  std::vector<v1::InsertMapRequest> sent = requests;
  for (v1::InsertMapRequest& request : sent) {
    if (request.metadata().map_id().empty() && request.request_id().empty()) request.set_request_id(RandomRequestId());
  }
  auto stream = [&](grpc::ClientContext* context, Stub* stub) {
    response->Clear();
    auto writer = stub->StreamInsertMaps(context, response);
    for (const auto& request : sent) {
      if (!writer->Write(request)) break;  // the server ended the stream; Finish says why
    }
    writer->WritesDone();
    const grpc::Status status = writer->Finish();
    if (!status.ok()) {
      response->clear_maps();
      const auto& trailers = context->GetServerTrailingMetadata();
      const auto stored = trailers.find(kStoredMapsMetadata);
      const size_t count = stored == trailers.end() ? 0
                                                    : std::strtoul(std::string(stored->second.data(),
                                                                               stored->second.size()).c_str(),
                                                                   nullptr, 10);
      for (size_t i = 0; i < std::min(count, sent.size()); ++i) *response->add_maps() = sent[i].metadata();
    }
    return status;
  };
  return WithRetries(collection, stream, true, nullptr, /*write=*/true);  // a stream goes to the primary
}

grpc::Status LmdClient::GetMap(const v1::GetMapRequest& request, v1::GetMapResponse* response) const {
  return WithRetries(request.collection(), [&](grpc::ClientContext* c, Stub* s) { return s->GetMap(c, request, response); });
}

grpc::Status LmdClient::DeleteMap(const v1::DeleteMapRequest& request) const {
  v1::DeleteMapResponse response;
  int attempts = 0;
  const grpc::Status status = WithRetries(
      request.collection(), [&](grpc::ClientContext* c, Stub* s) { return s->DeleteMap(c, request, &response); }, true,
      &attempts, /*write=*/true);
  // A retry that finds the map gone: an earlier attempt deleted it.
  if (status.error_code() == grpc::StatusCode::NOT_FOUND && attempts > 1) return grpc::Status::OK;
  return status;
}

grpc::Status LmdClient::ListMaps(const v1::ListMapsRequest& request, v1::ListMapsResponse* response) const {
  return WithRetries(request.collection(),
                     [&](grpc::ClientContext* c, Stub* s) { return s->ListMaps(c, request, response); });
}

grpc::Status LmdClient::Retrieve(const v1::RetrieveRequest& request, v1::RetrieveResponse* response) const {
  return WithRetries(request.collection(),
                     [&](grpc::ClientContext* c, Stub* s) { return s->Retrieve(c, request, response); });
}

grpc::Status LmdClient::DetectChanges(const v1::DetectChangesRequest& request,
                                      v1::DetectChangesResponse* response) const {
  return WithRetries(request.collection(),
                     [&](grpc::ClientContext* c, Stub* s) { return s->DetectChanges(c, request, response); });
}

grpc::Status LmdClient::ListCollections(v1::ListCollectionsResponse* response) const {
  return WithRetries("", [&](grpc::ClientContext* c, Stub* s) {
    return s->ListCollections(c, v1::ListCollectionsRequest(), response);
  });
}

grpc::Status LmdClient::Stats(const v1::StatsRequest& request, v1::StatsResponse* response) const {
  return WithRetries(request.collection(), [&](grpc::ClientContext* c, Stub* s) { return s->Stats(c, request, response); });
}

grpc::Status LmdClient::Cluster(v1::ClusterResponse* response) const {
  const v1::ClusterRequest request;
  return WithRetries("", [&](grpc::ClientContext* c, Stub* s) { return s->Cluster(c, request, response); });
}

grpc::Status LmdClient::SetReplication(const v1::SetReplicationRequest& request,
                                       v1::SetReplicationResponse* response) const {
  return WithRetries(request.collection(),
                     [&](grpc::ClientContext* c, Stub* s) { return s->SetReplication(c, request, response); });
}

grpc::Status LmdClient::Backup(const v1::BackupRequest& request, v1::BackupResponse* response) const {
  // Not retried: a lost answer would make the retry fail on the directory
  // the first attempt created.
  return WithRetries("", [&](grpc::ClientContext* c, Stub* s) { return s->Backup(c, request, response); }, false);
}

}  // namespace lmd::client
