// lmd_health_probe: asks an lmdd (or any gRPC server) grpc.health.v1.Health/Check
// and exits 0 when the answer is SERVING, 1 otherwise (one line on stderr says
// why), 2 on a usage error. For container health checks and Kubernetes exec
// probes:
//
//   lmd_health_probe [--addr HOST:PORT] [--timeout SECONDS] [--service NAME]
//                    [--tls-ca PEM [--tls-cert PEM --tls-key PEM] [--tls-server-name NAME]]
//
// The health service's stubs are not generated here, so the call is made by
// its method name with the generated messages.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <grpcpp/grpcpp.h>
#include <grpcpp/impl/client_unary_call.h>
#include <grpcpp/impl/codegen/proto_utils.h>  // SerializationTraits for protobuf messages

#include "grpc/health/v1/health.pb.h"

namespace {

constexpr char kUsage[] =
    "usage: lmd_health_probe [--addr HOST:PORT] [--timeout SECONDS] [--service NAME]\n"
    "                        [--tls-ca PEM [--tls-cert PEM --tls-key PEM] [--tls-server-name NAME]]\n"
    "Calls grpc.health.v1.Health/Check; exit 0 when SERVING, 1 otherwise, 2 on a usage error.\n"
    "Defaults: --addr 127.0.0.1:50051 --timeout 3 --service \"\" (the whole server); plaintext\n"
    "unless --tls-ca is given.\n";

struct Options {
  std::string addr = "127.0.0.1:50051";
  double timeout_s = 3.0;
  std::string service;
  std::string tls_ca;
  std::string tls_cert;
  std::string tls_key;
  std::string tls_server_name;
};

int Usage(const std::string& message) {
  std::fprintf(stderr, "lmd_health_probe: %s\n%s", message.c_str(), kUsage);
  return 2;
}

bool ReadFile(const std::string& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream text;
  text << in.rdbuf();
  *out = text.str();
  return static_cast<bool>(in) || in.eof();
}

const char* CodeName(grpc::StatusCode code) {
  static const char* const kNames[] = {"OK", "CANCELLED", "UNKNOWN", "INVALID_ARGUMENT", "DEADLINE_EXCEEDED",
                                       "NOT_FOUND", "ALREADY_EXISTS", "PERMISSION_DENIED", "RESOURCE_EXHAUSTED",
                                       "FAILED_PRECONDITION", "ABORTED", "OUT_OF_RANGE", "UNIMPLEMENTED",
                                       "INTERNAL", "UNAVAILABLE", "DATA_LOSS", "UNAUTHENTICATED"};
  const int c = static_cast<int>(code);
  return c >= 0 && c <= 16 ? kNames[c] : "UNKNOWN";
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "-h" || flag == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (i + 1 >= argc) return Usage(flag + " needs a value");
    const std::string value = argv[++i];
    if (flag == "--addr") {
      options.addr = value;
    } else if (flag == "--timeout") {
      char* end = nullptr;
      options.timeout_s = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || *end != '\0' || !(options.timeout_s > 0) || options.timeout_s > 3600) {
        return Usage("--timeout wants seconds in (0, 3600], got '" + value + "'");
      }
    } else if (flag == "--service") {
      options.service = value;
    } else if (flag == "--tls-ca") {
      options.tls_ca = value;
    } else if (flag == "--tls-cert") {
      options.tls_cert = value;
    } else if (flag == "--tls-key") {
      options.tls_key = value;
    } else if (flag == "--tls-server-name") {
      options.tls_server_name = value;
    } else {
      return Usage("unknown flag " + flag);
    }
  }
  if (options.tls_cert.empty() != options.tls_key.empty()) return Usage("--tls-cert and --tls-key go together");
  if (!options.tls_cert.empty() && options.tls_ca.empty()) return Usage("--tls-cert needs --tls-ca");

  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  grpc::ChannelArguments arguments;
  if (!options.tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    if (!ReadFile(options.tls_ca, &ssl.pem_root_certs)) {
      std::fprintf(stderr, "lmd_health_probe: cannot read %s\n", options.tls_ca.c_str());
      return 1;
    }
    if (!options.tls_cert.empty() && (!ReadFile(options.tls_cert, &ssl.pem_cert_chain) ||
                                      !ReadFile(options.tls_key, &ssl.pem_private_key))) {
      std::fprintf(stderr, "lmd_health_probe: cannot read %s or %s\n", options.tls_cert.c_str(),
                   options.tls_key.c_str());
      return 1;
    }
    credentials = grpc::SslCredentials(ssl);
    if (!options.tls_server_name.empty()) {
      arguments.SetSslTargetNameOverride(options.tls_server_name);
    }
  }
  // One attempt: a probe reports what it sees, its caller decides on retries.
  arguments.SetInt(GRPC_ARG_ENABLE_RETRIES, 0);
  auto channel = grpc::CreateCustomChannel(options.addr, credentials, arguments);

  grpc::health::v1::HealthCheckRequest request;
  request.set_service(options.service);
  grpc::health::v1::HealthCheckResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() +
                       std::chrono::microseconds(static_cast<int64_t>(options.timeout_s * 1e6)));
  const grpc::Status status = grpc::internal::BlockingUnaryCall(
      channel.get(), grpc::internal::RpcMethod("/grpc.health.v1.Health/Check", grpc::internal::RpcMethod::NORMAL_RPC),
      &context, request, &response);
  if (!status.ok()) {
    std::fprintf(stderr, "lmd_health_probe: %s: %s: %s\n", options.addr.c_str(), CodeName(status.error_code()),
                 status.error_message().empty() ? "(no message)" : status.error_message().c_str());
    return 1;
  }
  if (response.status() != grpc::health::v1::HealthCheckResponse::SERVING) {
    std::fprintf(stderr, "lmd_health_probe: %s: %s\n", options.addr.c_str(),
                 grpc::health::v1::HealthCheckResponse::ServingStatus_Name(response.status()).c_str());
    return 1;
  }
  return 0;
}
