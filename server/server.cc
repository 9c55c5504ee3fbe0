#include "server/server.h"

#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server.h>
#include <grpcpp/server_builder.h>
#include <spdlog/spdlog.h>

#include "core/util/host_port.h"
#include "grpc/health/v1/health.pb.h"
#include "server/auth.h"
#include "server/call_runner.h"
#include "server/cluster/cluster_node.h"
#include "server/cluster/replica_service.h"
#include "server/lmd_service.h"
#include "server/indexing.h"
#include "server/map_store.h"
#include "server/metrics.h"
#include "server/metrics_http.h"
#include "server/parse_errors.h"
#include "server/worker_pool.h"

namespace lmd::server {
namespace {

Result<std::string> ReadFile(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) return Status::InvalidArgument("cannot read " + what + " " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Plain-text credentials, or TLS when a certificate and key are configured.
Result<std::shared_ptr<grpc::ServerCredentials>> MakeCredentials(const ServerConfig& config) {
  if (config.tls_cert_file.empty() != config.tls_key_file.empty()) {
    return Status::InvalidArgument("TLS needs both tls_cert_file and tls_key_file");
  }
  if (config.tls_cert_file.empty()) {
    if (!config.tls_client_ca_file.empty()) return Status::InvalidArgument("tls_client_ca_file needs tls_cert_file");
    return grpc::InsecureServerCredentials();
  }
  Result<std::string> cert = ReadFile(config.tls_cert_file, "tls_cert_file");
  if (!cert.ok()) return cert.status();
  Result<std::string> key = ReadFile(config.tls_key_file, "tls_key_file");
  if (!key.ok()) return key.status();
  grpc::SslServerCredentialsOptions options(GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE);
  options.pem_key_cert_pairs.push_back({*key, *cert});
  if (!config.tls_client_ca_file.empty()) {
    Result<std::string> ca = ReadFile(config.tls_client_ca_file, "tls_client_ca_file");
    if (!ca.ok()) return ca.status();
    options.pem_root_certs = *ca;
    options.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(options);
}

// Why gRPC could not listen on `address`, which it logs but does not return:
// what binding the address ourselves says ("Address already in use").
std::string WhyCannotListen(const HostPort& address) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  addrinfo* found = nullptr;
  const int resolved = getaddrinfo(address.host.c_str(), std::to_string(address.port).c_str(), &hints, &found);
  if (resolved != 0) return gai_strerror(resolved);
  std::string reason = "address in use or not available";  // if it binds now, it did not a moment ago
  for (const addrinfo* a = found; a != nullptr; a = a->ai_next) {
    const int fd = socket(a->ai_family, a->ai_socktype, a->ai_protocol);
    const int one = 1;
    const bool bound = fd >= 0 && setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) == 0 &&  // as gRPC does
                       bind(fd, a->ai_addr, a->ai_addrlen) == 0;
    if (!bound) reason = std::strerror(errno);
    if (fd >= 0) close(fd);
    if (!bound) break;
  }
  freeaddrinfo(found);
  return reason;
}

}  // namespace

LmdServer::LmdServer() = default;

Result<std::unique_ptr<LmdServer>> LmdServer::Start(const ServerConfig& config) {
  const Result<HostPort> listen = ParseHostPort(config.listen, 0, "listen address");
  if (!listen.ok()) return listen.status();
  const bool secured = !config.tls_cert_file.empty() && !config.tokens_file.empty();
  if (!IsLoopbackAddress(config.listen) && !secured && !config.allow_insecure_remote) {
    return Status::InvalidArgument("refusing to serve on " + config.listen +
                                   " without TLS and tokens; listen on loopback, configure tls_cert_file and "
                                   "tokens_file, or set allow_insecure_remote");
  }
  Result<std::shared_ptr<grpc::ServerCredentials>> credentials = MakeCredentials(config);
  if (!credentials.ok()) return credentials.status();

  std::unique_ptr<LmdServer> server(new LmdServer());
  server->auth_ = std::make_unique<TokenAuthorizer>();
  if (!config.tokens_file.empty()) {
    Result<TokenAuthorizer> auth = TokenAuthorizer::LoadFile(config.tokens_file);
    if (!auth.ok()) return auth.status();
    *server->auth_ = std::move(auth).value();
  }
  MapStoreOptions store_options;
  store_options.data_dir = config.data_dir;
  store_options.sync_writes = config.sync_writes;
  store_options.indexing = ProductIndexing(config.inner_words, config.paper_index);
  Result<std::unique_ptr<MapStore>> store = MapStore::Open(store_options);
  if (!store.ok()) return store.status();
  server->store_ = std::move(store).value();

  const size_t threads = config.worker_threads ? config.worker_threads : std::thread::hardware_concurrency();
  server->metrics_ = std::make_unique<CallMetrics>();
  Result<std::unique_ptr<WorkerPool>> pool = WorkerPool::Start(threads, config.max_queued_calls);
  if (!pool.ok()) return pool.status();
  server->pool_ = std::move(pool).value();
  server->runner_ = std::make_unique<CallRunner>(server->pool_.get(), server->auth_.get(), server->metrics_.get());
  server->service_ = std::make_unique<LmdServiceImpl>(config, server->store_.get(), server->runner_.get(),
                                                      server->metrics_.get());
  if (!config.cluster_etcd.empty()) {
    LmdServer* self = server.get();
    Result<std::unique_ptr<cluster::ClusterNode>> node = cluster::ClusterNode::Start(config, server->store_.get(), [self] {
      std::lock_guard<std::mutex> lock(self->health_mu_);
      if (self->health_open_) self->server_->GetHealthCheckService()->SetServingStatus(true);
    });
    if (!node.ok()) {
      server->store_->Close();
      return node.status();
    }
    server->cluster_ = std::move(node).value();
    server->service_->SetCluster(server->cluster_.get());
    server->replica_service_ = std::make_unique<cluster::ReplicaService>(server->cluster_.get(), server->auth_.get());
  }

  // Reflection serves descriptors from the generated pool; the built-in health
  // service has none, so its messages are linked in from lmd_proto here.
  grpc::health::v1::HealthCheckRequest::descriptor();
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();

  grpc::ServerBuilder builder;
  builder.AddListeningPort(config.listen, *credentials, &server->port_);
  builder.SetMaxReceiveMessageSize(config.max_message_bytes);
  // gRPC sets SO_REUSEPORT by default: a second lmdd on the same port would
  // start and take half the calls to its own store. Refuse the port instead.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.SetMaxSendMessageSize(config.max_message_bytes);
  builder.RegisterService(server->service_.get());
  if (server->replica_service_) builder.RegisterService(server->replica_service_.get());
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> interceptors;
  CallRunner* runner = server->runner_.get();
  interceptors.push_back(ParseErrorInterceptors(  // requests that do not parse: INVALID_ARGUMENT
      [runner](const std::string& method, const grpc::Status& status, double ms) {
        runner->Finished(method.c_str(), "-", "", status, ms);
      }));
  builder.experimental().SetInterceptorCreators(std::move(interceptors));
  server->server_ = builder.BuildAndStart();
  if (!server->server_ || server->port_ == 0) {
    if (server->cluster_) server->cluster_->Stop();
    server->store_->Close();
    return Status::Internal("cannot listen on " + config.listen + ": " + WhyCannotListen(*listen));
  }
  {
    std::lock_guard<std::mutex> lock(server->health_mu_);
    server->health_open_ = true;
    const bool serving = !server->cluster_ || server->cluster_->ready();
    grpc::HealthCheckServiceInterface* health = server->server_->GetHealthCheckService();
    // Checks may name the service (Check(service="lmd.v1.LmdService")) as
    // well as ask for the whole server (""); every later SetServingStatus
    // without a name sets both.
    health->SetServingStatus(v1::LmdService::service_full_name(), serving);
    health->SetServingStatus(serving);
  }

  if (!config.metrics_listen.empty()) {
    const LmdServiceImpl* service = server->service_.get();
    const MapStore* store_ptr = server->store_.get();
    const CallMetrics* metrics = server->metrics_.get();
    Result<std::unique_ptr<MetricsHttpServer>> http = MetricsHttpServer::Start(config.metrics_listen, [=] {
      const CallMetrics::PreparedCache cache{service->prepared_maps().misses(), service->prepared_maps().bytes()};
      return metrics->PrometheusText(store_ptr->ListCollections(), service->uptime_s(), cache, ProcessCpuSeconds());
    });
    if (!http.ok()) {
      server->Shutdown(std::chrono::milliseconds(0));
      return http.status();
    }
    server->metrics_http_ = std::move(http).value();
  }
  spdlog::info("lmdd serving on port {} ({}, tokens {}, {} worker threads, data dir {})", server->port_,
               config.tls_cert_file.empty() ? "plaintext" : "TLS", server->auth_->enabled() ? "on" : "off", threads,
               config.data_dir);
  return server;
}

LmdServer::~LmdServer() { Shutdown(); }

int LmdServer::metrics_port() const { return metrics_http_ ? metrics_http_->port() : 0; }

void LmdServer::Wait() { server_->Wait(); }

void LmdServer::Shutdown(std::chrono::milliseconds grace) {
  if (stopped_ || !server_) return;
  stopped_ = true;
  spdlog::info("lmdd shutting down (grace {} ms)", grace.count());
  {
    std::lock_guard<std::mutex> lock(health_mu_);
    health_open_ = false;
    server_->GetHealthCheckService()->SetServingStatus(false);
  }
  // Leaving the cluster first hands this node's primaries over at once.
  if (cluster_) cluster_->Stop();
  server_->Shutdown(std::chrono::system_clock::now() + grace);
  metrics_http_.reset();
  pool_.reset();  // runs what is queued, joins the workers
  Status closed = store_->Close();
  if (!closed.ok()) spdlog::error("{}", closed.ToString());
  spdlog::info("lmdd stopped");
}

}  // namespace lmd::server
