// ParseErrorInterceptorFactory.
#include "server/parse_error_interceptor.h"

#include <string>
#include <string_view>
#include <utility>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "server/request_log.h"

namespace pathd::server {
namespace {

using grpc::experimental::InterceptionHookPoints;

class ParseErrorInterceptor final : public grpc::experimental::Interceptor {
 public:
  explicit ParseErrorInterceptor(std::string method)
      : method_(std::move(method)), received_(absl::Now()) {}

  void Intercept(
      grpc::experimental::InterceptorBatchMethods* methods) override {
    // For these call types gRPC parses the one request before the handler
    // runs and reports a failure as a null message here.
    if (methods->QueryInterceptionHookPoint(
            InterceptionHookPoints::POST_RECV_MESSAGE) &&
        methods->GetRecvMessage() == nullptr) {
      unparsed_ = true;
    }
    if (unparsed_ &&
        methods->QueryInterceptionHookPoint(
            InterceptionHookPoints::PRE_SEND_STATUS) &&
        methods->GetSendStatus().error_code() ==
            grpc::StatusCode::UNIMPLEMENTED) {
      const std::string message = absl::StrFormat(
          "the request to %s does not parse as its protobuf message: malformed "
          "bytes, or a string field (map name, request_id, ...) that is not "
          "valid UTF-8",
          method_);
      methods->ModifySendStatus(
          grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, message));
      // The handler never ran, so nothing else logs the request.
      const std::string_view path = method_;
      LogRequest(path.substr(path.rfind('/') + 1), "-", "unparsable request",
                 absl::InvalidArgumentError(message), received_);
    }
    methods->Proceed();
  }

 private:
  const std::string method_;
  const absl::Time received_;
  bool unparsed_ = false;
};

}  // namespace

grpc::experimental::Interceptor*
ParseErrorInterceptorFactory::CreateServerInterceptor(
    grpc::experimental::ServerRpcInfo* info) {
  switch (info->type()) {
    case grpc::experimental::ServerRpcInfo::Type::UNARY:
    case grpc::experimental::ServerRpcInfo::Type::SERVER_STREAMING:
      return new ParseErrorInterceptor(info->method());
    default:
      return nullptr;
  }
}

}  // namespace pathd::server
