#include "server/parse_errors.h"

#include <chrono>
#include <string>

#include <google/protobuf/descriptor.h>

namespace lmd::server {
namespace {

using grpc::experimental::InterceptionHookPoints;

class ParseErrorInterceptor final : public grpc::experimental::Interceptor {
 public:
  ParseErrorInterceptor(std::string method, std::string request_type, const ParseErrorReport& report)
      : method_(std::move(method)), request_type_(std::move(request_type)), report_(report) {}

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(InterceptionHookPoints::PRE_SEND_STATUS)) {
      const grpc::Status status = methods->GetSendStatus();
      if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED && status.error_message().empty()) {
        const grpc::Status rewritten(grpc::StatusCode::INVALID_ARGUMENT, "the request does not parse as " + request_type_);
        methods->ModifySendStatus(rewritten);
        if (report_) {
          report_(method_, rewritten,
                  std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count());
        }
      }
    }
    methods->Proceed();
  }

 private:
  const std::string method_;
  const std::string request_type_;
  const ParseErrorReport& report_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

class ParseErrorFactory final : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  explicit ParseErrorFactory(ParseErrorReport report) : report_(std::move(report)) {}

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
    return new ParseErrorInterceptor(method->name(), method->input_type()->full_name(), report_);
  }

 private:
  const ParseErrorReport report_;  // outlives the interceptors: the server owns the factory
};

}  // namespace

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> ParseErrorInterceptors(ParseErrorReport report) {
  return std::make_unique<ParseErrorFactory>(std::move(report));
}

}  // namespace lmd::server
