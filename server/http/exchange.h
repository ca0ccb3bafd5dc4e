// One HTTP request and its answer on a civetweb connection: the request's
// parts, its body (bounded), JSON answers, errors as google.rpc.Status JSON
// with the HTTP status of their gRPC code, and Server-Sent Events.
#ifndef PATHD_SERVER_HTTP_EXCHANGE_H_
#define PATHD_SERVER_HTTP_EXCHANGE_H_

#include <grpcpp/support/status.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "google/protobuf/message.h"

struct mg_connection;

namespace pathd::server {

// The HTTP status for a gRPC code, as grpc-gateway and Google's HTTP APIs
// map them (INVALID_ARGUMENT 400, NOT_FOUND 404, RESOURCE_EXHAUSTED 429...).
int HttpStatusOf(grpc::StatusCode code);

// A google.rpc.Status-shaped JSON body: {"code": N, "message": "...",
// "details": []}.
std::string StatusJson(grpc::StatusCode code, std::string_view message);

// gRPC's timeout header value ("250m", "2S", "1M": digits and one of
// H M S m u n, as the gRPC HTTP/2 protocol spells grpc-timeout).
absl::StatusOr<absl::Duration> ParseGrpcTimeout(std::string_view text);

// The protobuf JSON form pathctl --json prints (every field, default values
// included); one line unless `pretty`.
absl::StatusOr<std::string> ToJson(const google::protobuf::Message& message, bool pretty);

// Parses a JSON object into `message` (unknown fields are errors); an empty
// body is the empty message. The error names the problem for a 400.
absl::Status FromJson(std::string_view json, google::protobuf::Message& message);

class HttpExchange {
 public:
  HttpExchange(mg_connection* conn, int64_t max_body_bytes);
  HttpExchange(const HttpExchange&) = delete;
  HttpExchange& operator=(const HttpExchange&) = delete;

  const std::string& method() const { return method_; }
  // URL-decoded path, without the query.
  const std::string& path() const { return path_; }
  const std::string& remote_address() const { return remote_address_; }
  mg_connection* connection() const { return conn_; }
  // A header's value, case-insensitive name; nullopt when absent.
  std::optional<std::string> Header(const char* name) const;
  // The query's parameters, URL-decoded; a repeated name keeps its last value.
  const std::map<std::string, std::string>& query() const { return query_; }
  // Removes and returns a query parameter.
  std::optional<std::string> TakeQuery(const std::string& name);

  // The whole body. RESOURCE_EXHAUSTED (413) beyond max_body_bytes, before
  // reading further.
  absl::StatusOr<std::string> ReadBody();

  // Extra headers sent with the answer (before it is sent).
  void AddHeader(std::string name, std::string value);

  // A complete answer with Content-Length. Returns the HTTP status.
  int Send(int status, std::string_view content_type, std::string_view body);
  int SendJson(std::string_view json) { return Send(200, "application/json", json); }
  int SendError(const grpc::Status& status);
  int SendError(grpc::StatusCode code, std::string_view message) {
    return SendError(grpc::Status(code, std::string(message)));
  }

  // Server-Sent Events: the headers go with the first event. Each call is
  // one event; false once the client is gone. Thread-safe among themselves
  // (the keepalive thread writes comments while the handler writes events).
  bool SendEvent(std::string_view event, std::string_view data,
                 std::string_view id = {});
  // ": keepalive" once the stream has started; false when the write failed.
  bool SendKeepalive();
  // The last chunk of a started stream.
  void EndEvents();
  bool events_started() const;

 private:
  bool WriteChunkLocked(std::string_view text) ABSL_EXCLUSIVE_LOCKS_REQUIRED(write_mu_);

  mg_connection* const conn_;
  const int64_t max_body_bytes_;
  std::string method_;
  std::string path_;
  std::string remote_address_;
  std::map<std::string, std::string> query_;
  std::vector<std::pair<std::string, std::string>> extra_headers_;

  mutable absl::Mutex write_mu_;
  bool events_started_ ABSL_GUARDED_BY(write_mu_) = false;
  bool broken_ ABSL_GUARDED_BY(write_mu_) = false;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_HTTP_EXCHANGE_H_
