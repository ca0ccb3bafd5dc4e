// A small C++ client for pathd: channel set-up, per-call deadlines, and typed
// wrappers around the MapService, PlannerService and gRPC health stubs that
// return absl::StatusOr instead of grpc::Status + out-parameter.
#ifndef PATHD_CLIENT_CLIENT_H_
#define PATHD_CLIENT_CLIENT_H_

#include <memory>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "grpcpp/channel.h"
#include "grpcpp/client_context.h"
#include "grpcpp/support/channel_arguments.h"
#include "grpcpp/support/status.h"
#include "grpcpp/support/sync_stream.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"

namespace pathd::client {

// Address pathctl and the client use when none is given.
inline constexpr char kDefaultServerAddress[] = "127.0.0.1:50051";
// Deadline of every call unless the caller picks another.
inline constexpr absl::Duration kDefaultTimeout = absl::Seconds(10);
// Request metadata naming the map a call works on. A load balancer in front
// of several pathd replicas hashes on it so every call for one map reaches
// the replica that holds the map (docker/nginx/pathd.conf.template).
inline constexpr char kMapHeader[] = "x-pathd-map";
// Response metadata (initial, or trailing for an error answered without a
// response) naming the replica that served the call: pathd's --replica_name.
inline constexpr char kReplicaHeader[] = "pathd-replica";

// Opens a channel to `address` ("host:port", or any gRPC target URI).
// Plaintext, no token; the overload below adds TLS and a token.
std::shared_ptr<grpc::Channel> MakeChannel(const std::string& address);

// How a client reaches a pathd that uses TLS and / or tokens. All empty =
// plaintext without a token, as MakeChannel(address).
struct ClientCredentials {
  // PEM CA certificate(s) the server's certificate must chain to; non-empty
  // turns TLS on.
  std::string tls_ca_pem;
  // PEM client certificate chain and key, for a server with --tls_client_ca
  // (mutual TLS); both or neither, and only with tls_ca_pem.
  std::string tls_cert_pem;
  std::string tls_key_pem;
  // The name the server's certificate must carry when it differs from the
  // address's host (e.g. the certificate says "pathd.internal" and the
  // client dials an IP); empty = the address's host.
  std::string tls_server_name;
  // Sent as "authorization: Bearer <token>" on every call, streams included;
  // empty = none. Without TLS anyone on the network path can read it.
  std::string token;
};

// Where ClientCredentials come from, as pathctl's flags name them: file
// paths (tls_*), the token itself or a file holding it.
struct CredentialSources {
  std::string tls_ca;
  std::string tls_cert;
  std::string tls_key;
  std::string tls_server_name;
  std::string token;
  // One line holding the token (surrounding whitespace ignored); preferred
  // over `token`, since a command line is visible to other local users.
  std::string token_file;
};

// Reads the files `sources` names. INVALID_ARGUMENT naming the flags for a
// cert without key (or the reverse), a client certificate, key or server
// name without tls_ca, both token and token_file, or a token that is empty
// or has characters a header cannot carry; NOT_FOUND / INTERNAL naming the
// file when one cannot be read. Messages never contain the token.
absl::StatusOr<ClientCredentials> LoadClientCredentials(
    const CredentialSources& sources);

// Opens a channel to `address` with `credentials`: TLS when tls_ca_pem is
// set, the token added to every call by a client interceptor. An interceptor
// rather than gRPC call credentials, because gRPC refuses to send call
// credentials over a plaintext channel, and pathd accepts tokens on both.
std::shared_ptr<grpc::Channel> MakeChannel(const std::string& address,
                                           const ClientCredentials& credentials,
                                           grpc::ChannelArguments args = {});

// True when `address` names this machine (localhost, 127.x, [::1], unix:),
// where a token sent without TLS never crosses a network.
bool IsLoopbackAddress(const std::string& address);

// A context whose deadline is `timeout` from now. Returned by pointer because
// grpc::ClientContext can be neither copied nor moved.
std::unique_ptr<grpc::ClientContext> MakeContext(absl::Duration timeout);
// The same with kMapHeader set to `map` (not set when `map` is empty).
std::unique_ptr<grpc::ClientContext> MakeContext(absl::Duration timeout,
                                                 const std::string& map);

// Adds kMapHeader = `map` to a context whose call has not started; nothing
// when `map` is empty. For code that calls the stubs directly.
void SetMapHeader(grpc::ClientContext& context, const std::string& map);

// The replica that answered a finished call on `context` (kReplicaHeader from
// the initial or else the trailing metadata); empty when the server sent none.
std::string ServedBy(const grpc::ClientContext& context);

// The same code (gRPC and Abseil share numbering) and message.
absl::Status FromGrpcStatus(const grpc::Status& status);

// Typed calls to one pathd server. Every call gets its own deadline of
// `timeout`, and every call that names a map carries it in kMapHeader, so the
// same client works through a load balancer routing by map. Thread-safe: the
// stubs are, and the object is immutable after construction.
class PathdClient {
 public:
  explicit PathdClient(std::shared_ptr<grpc::ChannelInterface> channel,
                       absl::Duration timeout = kDefaultTimeout);
  // Connects to `address` with MakeChannel.
  explicit PathdClient(const std::string& address,
                       absl::Duration timeout = kDefaultTimeout);

  absl::Duration timeout() const { return timeout_; }

  // MapService. Errors are the server's status, see map_service.proto.
  absl::StatusOr<v1::CreateMapResponse> CreateMap(
      const v1::CreateMapRequest& request) const;
  absl::StatusOr<v1::GetMapResponse> GetMap(
      const v1::GetMapRequest& request) const;
  absl::StatusOr<v1::ListMapsResponse> ListMaps() const;
  absl::StatusOr<v1::DeleteMapResponse> DeleteMap(
      const std::string& name) const;
  absl::StatusOr<v1::UpdateMapResponse> UpdateMap(
      const v1::UpdateMapRequest& request) const;

  // UploadMap: `header`, then `cells` (width * height row-major cost bytes)
  // in bands of whole rows of at most `band_bytes` (at least one row each).
  // For maps too large for one CreateMap message; the server's errors as in
  // map_service.proto (INVALID_ARGUMENT when `cells` does not match the
  // header). The deadline is the client's timeout plus one second per
  // kTransferBytesPerSecond of cells.
  absl::StatusOr<v1::CreateMapResponse> UploadMap(
      const v1::UploadMapHeader& header, std::string_view cells,
      int64_t band_bytes = kUploadBandBytes) const;
  // DownloadMap: the metadata and every band, assembled into one
  // GetMapResponse with its cells (any size, no message over 1 MiB of
  // cells). Asks GetMap for the size first to set the deadline as UploadMap
  // does. NOT_FOUND for an unknown map; INTERNAL when the bands do not tile
  // the map.
  absl::StatusOr<v1::GetMapResponse> DownloadMap(const std::string& name) const;
  // Band size UploadMap uses by default: under gRPC's default 4 MiB limit,
  // so any pathd accepts it.
  static constexpr int64_t kUploadBandBytes = int64_t{1} << 20;
  // Transfer rate the streamed calls' deadlines allow for (slow links wait
  // longer through a larger --timeout).
  static constexpr int64_t kTransferBytesPerSecond = int64_t{16} << 20;

  // PlannerService. "No path" is an OK response with found = false.
  //
  // Packed paths: every call here whose answer carries a plan (Plan, Trip,
  // PlanStream, PlanBatch, Navigate) sends requests that leave
  // options.path_encoding unset as PATH_ENCODING_PACKED, and answers come
  // back with path and world_path filled from packed_path (UnpackPlanPath in
  // proto/path_codec.h), so callers see what a readable answer holds. A
  // request's explicit encoding stands (READABLE, BOTH: nothing to unpack).
  // A packed path that does not decode is DATA_LOSS (streams: from Finish()).
  absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) const;
  absl::StatusOr<v1::CostToGoResponse> CostToGo(
      const v1::CostToGoRequest& request) const;
  absl::StatusOr<v1::GetCacheStatsResponse> GetCacheStats() const;
  // The open Navigate sessions of `map` (every map when empty).
  absl::StatusOr<v1::ListSessionsResponse> ListSessions(const std::string& map) const;
  // Fleet map queries. Unreachable pairs, "none within the distance" and
  // "no trip" are OK responses.
  absl::StatusOr<v1::TableResponse> Table(const v1::TableRequest& request) const;
  absl::StatusOr<v1::NearestResponse> Nearest(const v1::NearestRequest& request) const;
  absl::StatusOr<v1::TripResponse> Trip(const v1::TripRequest& request) const;
  absl::StatusOr<v1::IsochroneResponse> Isochrone(
      const v1::IsochroneRequest& request) const;
  // Conflict-free timed paths for many robots; "no plan" (found = false)
  // is an OK response.
  absl::StatusOr<v1::PlanFleetResponse> PlanFleet(const v1::PlanFleetRequest& request) const;
  // An invalid path is an OK response with valid = false.
  absl::StatusOr<v1::IsPathValidResponse> IsPathValid(
      const v1::IsPathValidRequest& request) const;

  // Opens a Navigate stream on `context`, which the caller owns and must keep
  // alive until the stream's Finish() returned. Unlike the unary calls no
  // deadline is set: a session lasts as long as the robot drives, so the
  // caller bounds each wait itself (and cancels through `context`). `map` is
  // the map the session's NavigateOpen will name: the stream is routed before
  // its first message is sent.
  std::unique_ptr<grpc::ClientReaderWriterInterface<v1::NavigateRequest,
                                                    v1::NavigateResponse>>
  Navigate(grpc::ClientContext* context, const std::string& map) const;

  // Opens a WatchMap stream on `context` (caller-owned, alive until the
  // reader's Finish() returned). No deadline is set: a watch lasts until the
  // map is deleted or the caller cancels through `context`.
  std::unique_ptr<grpc::ClientReaderInterface<v1::MapEvent>> WatchMap(
      grpc::ClientContext* context, const v1::WatchMapRequest& request) const;

  // Opens a PlanStream call on `context` (caller-owned, alive until the
  // reader's Finish() returned; the caller sets its deadline): progress
  // events, then one final event.
  std::unique_ptr<grpc::ClientReaderInterface<v1::PlanStreamEvent>> PlanStream(
      grpc::ClientContext* context, const v1::PlanRequest& request) const;

  // Opens a PlanBatch stream on `context` (caller-owned, alive until the
  // stream's Finish() returned; the caller sets its deadline). Writes may
  // block while the server holds the stream at its in-flight bound, so write
  // from one thread and read the answers from another. The whole stream is
  // routed by `map` (normally its items' map): through a balancer that routes
  // by map, items naming a map held by another replica answer NOT_FOUND.
  std::unique_ptr<grpc::ClientReaderWriterInterface<v1::PlanBatchRequest,
                                                    v1::PlanBatchResponse>>
  PlanBatch(grpc::ClientContext* context, const std::string& map) const;

  // grpc.health.v1.Health/Check; `service` empty asks about the whole server.
  absl::StatusOr<grpc::health::v1::HealthCheckResponse> CheckHealth(
      const std::string& service = "") const;

 private:
  absl::Duration timeout_;
  std::unique_ptr<v1::MapService::StubInterface> maps_;
  std::unique_ptr<v1::PlannerService::StubInterface> planner_;
  std::unique_ptr<grpc::health::v1::Health::StubInterface> health_;
};

}  // namespace pathd::client

#endif  // PATHD_CLIENT_CLIENT_H_
