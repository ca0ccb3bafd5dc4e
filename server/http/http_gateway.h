// The HTTP/JSON face of pathd (--http_address): one route per RPC, each
// request turned into the same gRPC call over the server's in-process
// channel, so auth, limits, deadlines, metrics and every error message are
// the gRPC service's own. Server streams (WatchMap, PlanStream, Navigate)
// come back as Server-Sent Events. The viewer page (server/http/web/) is
// served at "/". docs/http.md is the contract; docs/decisions.md says why
// civetweb and why a forwarding gateway.
#ifndef PATHD_SERVER_HTTP_HTTP_GATEWAY_H_
#define PATHD_SERVER_HTTP_HTTP_GATEWAY_H_

#include <grpcpp/channel.h>

#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "absl/time/time.h"

namespace pathd::server {

struct HttpGatewayOptions {
  // host:port (IPv6 as [addr]:port); port 0 picks a free port.
  std::string address;
  // Server-Sent Event streams open at once (WatchMap, PlanStream, Navigate);
  // further ones get 429 RESOURCE_EXHAUSTED. Each holds one HTTP thread, and
  // the server runs this many plus kUnaryThreads.
  int max_streams = 16;
  // Largest request body; larger ones get 413 without being parsed.
  int64_t max_body_bytes = int64_t{64} << 20;
  // How often an idle stream gets an SSE comment, which is also how a
  // vanished client is noticed (the write fails and the call is cancelled).
  absl::Duration keepalive = absl::Seconds(15);
  // The "pathd-replica" value of gRPC answers, sent as the X-Pathd-Replica
  // header; empty = not sent.
  std::string replica_name;
};

class HttpGateway {
 public:
  // HTTP threads for requests that are not streams.
  static constexpr int kUnaryThreads = 16;

  // Listens on options.address and forwards to `channel` (the gRPC server's
  // in-process channel). UNAVAILABLE when the address cannot be bound,
  // INVALID_ARGUMENT when it is malformed.
  static absl::StatusOr<std::unique_ptr<HttpGateway>> Start(
      HttpGatewayOptions options, std::shared_ptr<grpc::Channel> channel);

  // Stop() if it has not run.
  ~HttpGateway();
  HttpGateway(const HttpGateway&) = delete;
  HttpGateway& operator=(const HttpGateway&) = delete;

  // The bound port.
  int port() const;

  // Refuses new requests (503 UNAVAILABLE) and cancels open streams, whose
  // clients get an end event; calls in flight go on. Idempotent.
  void BeginShutdown();
  // BeginShutdown, then waits for every request handler to return (their
  // gRPC calls end when the gRPC server shuts down) and closes the listener.
  // Idempotent.
  void Stop();

  class Impl;

 private:
  explicit HttpGateway(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_HTTP_HTTP_GATEWAY_H_
