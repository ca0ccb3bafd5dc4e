// Turns gRPC's answer to a request that does not parse into one that says so.
// The callback API answers such a request (malformed bytes, or a proto3
// `string` field holding invalid UTF-8) with UNIMPLEMENTED and no message, as
// if the method did not exist; this interceptor replaces that status with
// INVALID_ARGUMENT naming the method and the likely causes.
#ifndef PATHD_SERVER_PARSE_ERROR_INTERCEPTOR_H_
#define PATHD_SERVER_PARSE_ERROR_INTERCEPTOR_H_

#include <grpcpp/support/server_interceptor.h>

namespace pathd::server {

// Creates one interceptor per unary and server-streaming call (the calls whose
// single request gRPC parses before the handler runs). Client- and
// bidi-streaming calls get none: there a message that does not parse reaches
// the handler as the end of the client's stream, and gRPC tells the
// interceptor nothing that separates the two. Thread-safe.
class ParseErrorInterceptorFactory final
    : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_PARSE_ERROR_INTERCEPTOR_H_
