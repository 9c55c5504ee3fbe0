// What grpcurl relies on: server reflection lists lmd's service and the
// health service and can describe both; grpc.health.v1 answers SERVING.
// Reflection's messages are not installed as C++ headers, so the requests are
// encoded by hand (they are tiny) and the answers searched for names.
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/impl/client_unary_call.h>

#include <gtest/gtest.h>

#include "grpc/health/v1/health.pb.h"
#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

// One ServerReflectionRequest whose oneof field `field` holds `value`, sent on
// a fresh reflection stream; returns the raw ServerReflectionResponse.
std::string AskReflection(const std::string& address, int field, const std::string& value) {
  std::string request;
  request.push_back(static_cast<char>(field << 3 | 2));  // length-delimited
  request.push_back(static_cast<char>(value.size()));     // values here are < 128 bytes
  request += value;

  auto channel = grpc::CreateChannel(address, grpc::InsecureChannelCredentials());
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  grpc::CompletionQueue queue;
  void* tag = nullptr;
  bool ok = false;
  auto call = stub.PrepareCall(&context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &queue);
  call->StartCall(reinterpret_cast<void*>(1));
  queue.Next(&tag, &ok);
  grpc::Slice slice(request);
  grpc::ByteBuffer send(&slice, 1);
  call->Write(send, reinterpret_cast<void*>(2));
  queue.Next(&tag, &ok);
  grpc::ByteBuffer received;
  call->Read(&received, reinterpret_cast<void*>(3));
  queue.Next(&tag, &ok);
  std::string response;
  if (ok) {
    std::vector<grpc::Slice> slices;
    (void)received.Dump(&slices);
    for (const auto& s : slices) response.append(reinterpret_cast<const char*>(s.begin()), s.size());
  }
  call->WritesDone(reinterpret_cast<void*>(4));
  queue.Next(&tag, &ok);
  grpc::Status status;
  call->Finish(&status, reinterpret_cast<void*>(5));
  queue.Next(&tag, &ok);
  queue.Shutdown();
  while (queue.Next(&tag, &ok)) {
  }
  return response;
}

TEST(ReflectionTest, ListsTheLmdAndHealthServices) {
  TempDir dir;
  TestServer server(dir.path());
  const std::string services = AskReflection(server.address(), /*list_services=*/7, "");
  EXPECT_NE(services.find("lmd.v1.LmdService"), std::string::npos);
  EXPECT_NE(services.find("grpc.health.v1.Health"), std::string::npos);
}

TEST(ReflectionTest, DescribesTheHealthServiceAndLmdMessages) {
  TempDir dir;
  TestServer server(dir.path());
  const std::string health = AskReflection(server.address(), /*file_containing_symbol=*/4, "grpc.health.v1.Health");
  EXPECT_NE(health.find("grpc/health/v1/health.proto"), std::string::npos);
  const std::string lmd = AskReflection(server.address(), 4, "lmd.v1.RetrieveRequest");
  EXPECT_NE(lmd.find("lmd/v1/lmd.proto"), std::string::npos);
  const std::string unknown = AskReflection(server.address(), 4, "no.such.Symbol");
  EXPECT_EQ(unknown.find(".proto"), std::string::npos);
}

// grpc.health.v1 Check of `service` ("": the whole server).
grpc::Status CheckHealth(const std::string& address, const std::string& service,
                         grpc::health::v1::HealthCheckResponse* response) {
  auto channel = grpc::CreateChannel(address, grpc::InsecureChannelCredentials());
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  // Health's service stubs are not generated here, so the call is made by name.
  return grpc::internal::BlockingUnaryCall(
      channel.get(), grpc::internal::RpcMethod("/grpc.health.v1.Health/Check", grpc::internal::RpcMethod::NORMAL_RPC),
      &context, request, response);
}

TEST(HealthTest, ReportsServing) {
  TempDir dir;
  TestServer server(dir.path());
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status status = CheckHealth(server.address(), "", &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.status(), grpc::health::v1::HealthCheckResponse::SERVING);
}

// Probes that name the service (grpc_health_probe -service, Kubernetes'
// grpc probe's service field) get its status, not NOT_FOUND.
TEST(HealthTest, ReportsTheLmdServiceByName) {
  TempDir dir;
  TestServer server(dir.path());
  grpc::health::v1::HealthCheckResponse response;
  grpc::Status status = CheckHealth(server.address(), "lmd.v1.LmdService", &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.status(), grpc::health::v1::HealthCheckResponse::SERVING);
  EXPECT_EQ(CheckHealth(server.address(), "no.such.Service", &response).error_code(), grpc::StatusCode::NOT_FOUND);
}

}  // namespace
}  // namespace lmd::testing
