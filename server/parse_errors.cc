#include "server/parse_errors.h"

#include <string>

#include <google/protobuf/descriptor.h>

namespace lmd::server {
namespace {

using grpc::experimental::InterceptionHookPoints;

class ParseErrorInterceptor final : public grpc::experimental::Interceptor {
 public:
  explicit ParseErrorInterceptor(std::string request_type) : request_type_(std::move(request_type)) {}

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(InterceptionHookPoints::PRE_SEND_STATUS)) {
      const grpc::Status status = methods->GetSendStatus();
      if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED && status.error_message().empty()) {
        methods->ModifySendStatus(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                                               "the request does not parse as " + request_type_));
      }
    }
    methods->Proceed();
  }

 private:
  const std::string request_type_;
};

class ParseErrorFactory final : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  grpc::experimental::Interceptor* CreateServerInterceptor(grpc::experimental::ServerRpcInfo* info) override {
    // "/lmd.v1.LmdService/Retrieve" -> "lmd.v1.LmdService.Retrieve": only
    // methods of services compiled into lmdd; an unknown method stays
    // UNIMPLEMENTED.
    std::string name = info->method() == nullptr ? "" : info->method();
    if (name.size() < 2 || name[0] != '/') return nullptr;
    name = name.substr(1);
    const size_t slash = name.find('/');
    if (slash == std::string::npos) return nullptr;
    name[slash] = '.';
    const google::protobuf::MethodDescriptor* method =
        google::protobuf::DescriptorPool::generated_pool()->FindMethodByName(name);
    if (method == nullptr) return nullptr;
    return new ParseErrorInterceptor(method->input_type()->full_name());
  }
};

}  // namespace

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> ParseErrorInterceptors() {
  return std::make_unique<ParseErrorFactory>();
}

}  // namespace lmd::server
