// Implementation of the pathd client wrappers.
#include "client/client.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "grpcpp/create_channel.h"
#include "grpcpp/security/credentials.h"
#include "grpcpp/support/client_interceptor.h"
#include "proto/path_codec.h"

namespace pathd::client {
namespace {

// Runs one unary call about `map` (routed by kMapHeader; empty: a call about
// no map) with a fresh deadline. `call` is the stub method bound to its
// request: (ClientContext*, Response*) -> grpc::Status.
template <typename Response, typename Call>
absl::StatusOr<Response> InvokeOnMap(absl::Duration timeout,
                                     const std::string& map, Call&& call) {
  std::unique_ptr<grpc::ClientContext> context = MakeContext(timeout, map);
  Response response;
  grpc::Status status = std::forward<Call>(call)(context.get(), &response);
  if (!status.ok()) return FromGrpcStatus(status);
  return response;
}

// Requests that leave options.path_encoding unset ask for the packed path
// (the client unpacks it); a caller's explicit choice stands. False when
// the request was left as it is.
bool AskForPackedPath(v1::PlanOptions* options) {
  if (options->path_encoding() != v1::PATH_ENCODING_UNSPECIFIED) return false;
  options->set_path_encoding(v1::PATH_ENCODING_PACKED);
  return true;
}
bool AskForPackedPath(v1::PlanRequest* request) {
  return AskForPackedPath(request->mutable_options());
}
bool AskForPackedPath(v1::TripRequest* request) {
  return AskForPackedPath(request->mutable_options());
}
bool AskForPackedPath(v1::PlanBatchRequest* item) {
  return AskForPackedPath(item->mutable_request()->mutable_options());
}
bool AskForPackedPath(v1::NavigateRequest* request) {
  return request->has_open() && AskForPackedPath(request->mutable_open()->mutable_options());
}

// The readable path of a packed-only plan (UnpackPlanPath); DATA_LOSS when
// the server's bytes do not decode.
absl::Status UnpackPath(v1::PlanResponse* plan) {
  const absl::Status s = UnpackPlanPath(plan);
  if (s.ok()) return s;
  return absl::DataLossError(absl::StrCat("the server's packed path: ", s.message()));
}
absl::Status UnpackPath(v1::PlanStreamEvent* event) {
  return event->has_result() ? UnpackPath(event->mutable_result()) : absl::OkStatus();
}
absl::Status UnpackPath(v1::PlanBatchResponse* response) {
  return response->has_result() ? UnpackPath(response->mutable_result()) : absl::OkStatus();
}
absl::Status UnpackPath(v1::NavigateResponse* response) {
  return response->has_plan() ? UnpackPath(response->mutable_plan()) : absl::OkStatus();
}
absl::Status UnpackPath(v1::TripResponse* response) {
  return response->has_plan() ? UnpackPath(response->mutable_plan()) : absl::OkStatus();
}

// InvokeOnMap for a unary call whose answer carries a plan (Plan, Trip):
// `call` gets the request asking for a packed path, the answer comes back
// readable.
template <typename Response, typename Request, typename Call>
absl::StatusOr<Response> InvokePacked(absl::Duration timeout, Request request, Call&& call) {
  AskForPackedPath(&request);
  absl::StatusOr<Response> response = InvokeOnMap<Response>(
      timeout, request.map(), [&](grpc::ClientContext* context, Response* out) {
        return call(context, request, out);
      });
  if (!response.ok()) return response;
  if (absl::Status s = UnpackPath(&*response); !s.ok()) return s;
  return response;
}

// A stream whose plans go out asking for packed paths and come back
// readable: writes pass through AskForPackedPath, reads through UnpackPath.
// A read whose path does not decode is handed over packed, and Finish()
// then answers DATA_LOSS in place of an OK status.
template <typename Inner, typename Out>
class UnpackingStream : public Inner {
 public:
  explicit UnpackingStream(std::unique_ptr<Inner> inner) : inner_(std::move(inner)) {}

  void WaitForInitialMetadata() override { inner_->WaitForInitialMetadata(); }
  bool NextMessageSize(uint32_t* sz) override { return inner_->NextMessageSize(sz); }
  bool Read(Out* msg) override {
    if (!inner_->Read(msg)) return false;
    if (absl::Status s = UnpackPath(msg); !s.ok() && unpack_error_.ok()) unpack_error_ = s;
    return true;
  }
  grpc::Status Finish() override {
    grpc::Status status = inner_->Finish();
    if (!status.ok() || unpack_error_.ok()) return status;
    return grpc::Status(grpc::StatusCode::DATA_LOSS, std::string(unpack_error_.message()));
  }

 protected:
  std::unique_ptr<Inner> inner_;
  absl::Status unpack_error_;
};

template <typename In, typename Out>
class UnpackingBidiStream final
    : public UnpackingStream<grpc::ClientReaderWriterInterface<In, Out>, Out> {
 public:
  using UnpackingStream<grpc::ClientReaderWriterInterface<In, Out>, Out>::UnpackingStream;

  bool WritesDone() override { return this->inner_->WritesDone(); }
  bool Write(const In& msg, grpc::WriteOptions options) override {
    In packed = msg;
    if (!AskForPackedPath(&packed)) return this->inner_->Write(msg, options);
    return this->inner_->Write(packed, options);
  }
};

// Adds "authorization: Bearer <token>" to the initial metadata of every call
// on its channel, unary and streaming alike.
class BearerTokenInterceptor : public grpc::experimental::Interceptor {
 public:
  explicit BearerTokenInterceptor(std::shared_ptr<const std::string> header)
      : header_(std::move(header)) {}

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(
            grpc::experimental::InterceptionHookPoints::PRE_SEND_INITIAL_METADATA)) {
      methods->GetSendInitialMetadata()->emplace("authorization", *header_);
    }
    methods->Proceed();
  }

 private:
  std::shared_ptr<const std::string> header_;
};

class BearerTokenInterceptorFactory
    : public grpc::experimental::ClientInterceptorFactoryInterface {
 public:
  explicit BearerTokenInterceptorFactory(const std::string& token)
      : header_(std::make_shared<const std::string>(absl::StrCat("Bearer ", token))) {}

  grpc::experimental::Interceptor* CreateClientInterceptor(
      grpc::experimental::ClientRpcInfo* /*info*/) override {
    return new BearerTokenInterceptor(header_);
  }

 private:
  std::shared_ptr<const std::string> header_;
};

// A file named by flag `flag`, with the flag in the error message.
absl::StatusOr<std::string> ReadFlagFile(absl::string_view flag,
                                         const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    return absl::NotFoundError(
        absl::StrCat("--", flag, ": cannot open ", path, ": ", std::strerror(errno)));
  }
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    return absl::InternalError(absl::StrCat("--", flag, ": error reading ", path));
  }
  return text.str();
}

// Visible ASCII only: what a Bearer token in an HTTP/2 header can hold.
bool IsTokenText(absl::string_view token) {
  return !token.empty() && std::all_of(token.begin(), token.end(), [](char c) {
    return c >= 0x21 && c <= 0x7e;
  });
}

// The same for a call about no map (ListMaps, health): a load balancer
// routing by map sends it to any replica.
template <typename Response, typename Call>
absl::StatusOr<Response> Invoke(absl::Duration timeout, Call&& call) {
  return InvokeOnMap<Response>(timeout, "", std::forward<Call>(call));
}

}  // namespace

absl::StatusOr<ClientCredentials> LoadClientCredentials(
    const CredentialSources& sources) {
  if (sources.tls_cert.empty() != sources.tls_key.empty()) {
    return absl::InvalidArgumentError(
        "--tls_cert and --tls_key must be given together (mutual TLS)");
  }
  if (sources.tls_ca.empty()) {
    for (const auto& [flag, value] :
         {std::pair<absl::string_view, const std::string&>{"tls_cert", sources.tls_cert},
          {"tls_server_name", sources.tls_server_name}}) {
      if (!value.empty()) {
        return absl::InvalidArgumentError(absl::StrCat(
            "--", flag, " needs --tls_ca (the CA that signed the server's "
            "certificate), which turns TLS on"));
      }
    }
  }
  if (!sources.token.empty() && !sources.token_file.empty()) {
    return absl::InvalidArgumentError("give --token or --token_file, not both");
  }
  ClientCredentials credentials;
  credentials.tls_server_name = sources.tls_server_name;
  if (!sources.tls_ca.empty()) {
    absl::StatusOr<std::string> pem = ReadFlagFile("tls_ca", sources.tls_ca);
    if (!pem.ok()) return pem.status();
    credentials.tls_ca_pem = *std::move(pem);
  }
  if (!sources.tls_cert.empty()) {
    absl::StatusOr<std::string> cert = ReadFlagFile("tls_cert", sources.tls_cert);
    if (!cert.ok()) return cert.status();
    absl::StatusOr<std::string> key = ReadFlagFile("tls_key", sources.tls_key);
    if (!key.ok()) return key.status();
    credentials.tls_cert_pem = *std::move(cert);
    credentials.tls_key_pem = *std::move(key);
  }
  absl::string_view flag = "token";
  std::string token = sources.token;
  if (!sources.token_file.empty()) {
    flag = "token_file";
    absl::StatusOr<std::string> text = ReadFlagFile(flag, sources.token_file);
    if (!text.ok()) return text.status();
    token = std::string(absl::StripAsciiWhitespace(*text));
    if (token.empty()) {
      return absl::InvalidArgumentError(
          absl::StrCat("--token_file: ", sources.token_file, " is empty"));
    }
  }
  if (!token.empty() && !IsTokenText(token)) {
    // Describes the token without printing it.
    return absl::InvalidArgumentError(absl::StrCat(
        "--", flag, ": a token may hold only visible ASCII characters (no "
        "spaces or line breaks inside)"));
  }
  credentials.token = std::move(token);
  return credentials;
}

std::shared_ptr<grpc::Channel> MakeChannel(const std::string& address,
                                           const ClientCredentials& credentials,
                                           grpc::ChannelArguments args) {
  // As in MakeChannel(address): whole maps and cost-to-go fields exceed
  // gRPC's default 4 MiB receive limit.
  args.SetMaxReceiveMessageSize(-1);
  std::shared_ptr<grpc::ChannelCredentials> transport =
      grpc::InsecureChannelCredentials();
  if (!credentials.tls_ca_pem.empty()) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = credentials.tls_ca_pem;
    ssl.pem_cert_chain = credentials.tls_cert_pem;
    ssl.pem_private_key = credentials.tls_key_pem;
    transport = grpc::SslCredentials(ssl);
    if (!credentials.tls_server_name.empty()) {
      args.SetSslTargetNameOverride(credentials.tls_server_name);
    }
  }
  std::vector<std::unique_ptr<grpc::experimental::ClientInterceptorFactoryInterface>>
      interceptors;
  if (!credentials.token.empty()) {
    interceptors.push_back(
        std::make_unique<BearerTokenInterceptorFactory>(credentials.token));
  }
  return grpc::experimental::CreateCustomChannelWithInterceptors(
      address, transport, args, std::move(interceptors));
}

bool IsLoopbackAddress(const std::string& address) {
  absl::string_view host = address;
  if (absl::StartsWith(host, "unix:") || absl::StartsWith(host, "unix-abstract:")) {
    return true;
  }
  absl::ConsumePrefix(&host, "dns:///");
  absl::ConsumePrefix(&host, "ipv4:");
  absl::ConsumePrefix(&host, "ipv6:");
  if (absl::StartsWith(host, "[::1]")) return true;
  host = host.substr(0, host.rfind(':'));
  return host == "localhost" || absl::StartsWith(host, "127.");
}

std::shared_ptr<grpc::Channel> MakeChannel(const std::string& address) {
  grpc::ChannelArguments args;
  // Responses carrying a whole cost-to-go field (8 bytes per cell) or a whole
  // map exceed gRPC's default 4 MiB receive limit.
  args.SetMaxReceiveMessageSize(-1);
  return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args);
}

std::unique_ptr<grpc::ClientContext> MakeContext(absl::Duration timeout) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(absl::ToChronoTime(absl::Now() + timeout));
  return context;
}

std::unique_ptr<grpc::ClientContext> MakeContext(absl::Duration timeout,
                                                 const std::string& map) {
  std::unique_ptr<grpc::ClientContext> context = MakeContext(timeout);
  SetMapHeader(*context, map);
  return context;
}

void SetMapHeader(grpc::ClientContext& context, const std::string& map) {
  // gRPC fails the whole call locally (INTERNAL) on a metadata value outside
  // printable ASCII. Such a name is not a valid map name, so any replica
  // answers it with the INVALID_ARGUMENT that says why: leave it unrouted.
  const bool printable = std::all_of(map.begin(), map.end(), [](char c) {
    return c >= 0x20 && c <= 0x7e;
  });
  if (map.empty() || !printable) return;
  context.AddMetadata(kMapHeader, map);
}

std::string ServedBy(const grpc::ClientContext& context) {
  for (const auto* metadata : {&context.GetServerInitialMetadata(),
                               &context.GetServerTrailingMetadata()}) {
    auto it = metadata->find(kReplicaHeader);
    if (it != metadata->end()) {
      return std::string(it->second.data(), it->second.size());
    }
  }
  return "";
}

absl::Status FromGrpcStatus(const grpc::Status& status) {
  // grpc::StatusCode and absl::StatusCode use the same numbers (both follow
  // google.rpc.Code), so the cast keeps the code exactly.
  const auto code = static_cast<absl::StatusCode>(status.error_code());
  // gRPC's own size refusal names no setting. MakeChannel's receive limit is
  // off and its send limit is gRPC's default (none), so on pathctl's channel
  // it is the server's limit.
  if (code == absl::StatusCode::kResourceExhausted &&
      absl::StrContains(status.error_message(), "message larger than max")) {
    return absl::Status(
        code, absl::StrCat(status.error_message(),
                           "; pathd's message size limit is set by "
                           "--max_message_bytes"));
  }
  return absl::Status(code, status.error_message());
}

PathdClient::PathdClient(std::shared_ptr<grpc::ChannelInterface> channel,
                         absl::Duration timeout)
    : timeout_(timeout),
      maps_(v1::MapService::NewStub(channel)),
      planner_(v1::PlannerService::NewStub(channel)),
      health_(grpc::health::v1::Health::NewStub(channel)) {}

PathdClient::PathdClient(const std::string& address, absl::Duration timeout)
    : PathdClient(MakeChannel(address), timeout) {}

absl::StatusOr<v1::CreateMapResponse> PathdClient::CreateMap(
    const v1::CreateMapRequest& request) const {
  return InvokeOnMap<v1::CreateMapResponse>(
      timeout_, request.name(),
      [&](grpc::ClientContext* context, v1::CreateMapResponse* response) {
        return maps_->CreateMap(context, request, response);
      });
}

absl::StatusOr<v1::GetMapResponse> PathdClient::GetMap(
    const v1::GetMapRequest& request) const {
  return InvokeOnMap<v1::GetMapResponse>(
      timeout_, request.name(),
      [&](grpc::ClientContext* context, v1::GetMapResponse* response) {
        return maps_->GetMap(context, request, response);
      });
}

namespace {

// A streamed transfer of `bytes` cells gets the client's timeout plus the
// time the bytes take at kTransferBytesPerSecond.
absl::Duration TransferTimeout(absl::Duration timeout, int64_t bytes) {
  return timeout + absl::Seconds(static_cast<double>(bytes) /
                                 PathdClient::kTransferBytesPerSecond);
}

}  // namespace

absl::StatusOr<v1::CreateMapResponse> PathdClient::UploadMap(
    const v1::UploadMapHeader& header, std::string_view cells,
    int64_t band_bytes) const {
  std::unique_ptr<grpc::ClientContext> context = MakeContext(
      TransferTimeout(timeout_, static_cast<int64_t>(cells.size())), header.name());
  v1::CreateMapResponse response;
  std::unique_ptr<grpc::ClientWriterInterface<v1::UploadMapRequest>> writer =
      maps_->UploadMap(context.get(), &response);
  v1::UploadMapRequest message;
  *message.mutable_header() = header;
  // A failed write means the server has finished the call (with the error
  // Finish reports): stop sending.
  bool open = writer->Write(message);
  const size_t width = header.width() > 0 ? static_cast<size_t>(header.width()) : 1;
  const size_t rows_per_band =
      std::max<size_t>(1, static_cast<size_t>(std::max<int64_t>(band_bytes, 1)) / width);
  for (size_t offset = 0; open && offset < cells.size();) {
    const size_t length = std::min(rows_per_band * width, cells.size() - offset);
    message.Clear();
    v1::CellBand* band = message.mutable_band();
    band->set_first_row(static_cast<int32_t>(offset / width));
    band->set_cells(cells.data() + offset, length);
    open = writer->Write(message);
    offset += length;
  }
  if (open) writer->WritesDone();
  const grpc::Status status = writer->Finish();
  if (!status.ok()) return FromGrpcStatus(status);
  return response;
}

absl::StatusOr<v1::GetMapResponse> PathdClient::DownloadMap(
    const std::string& name) const {
  v1::GetMapRequest info_request;
  info_request.set_name(name);
  absl::StatusOr<v1::GetMapResponse> info = GetMap(info_request);
  if (!info.ok()) return info.status();
  const int64_t size = int64_t{info->info().width()} * info->info().height();
  std::unique_ptr<grpc::ClientContext> context =
      MakeContext(TransferTimeout(timeout_, size), name);
  v1::DownloadMapRequest request;
  request.set_name(name);
  std::unique_ptr<grpc::ClientReaderInterface<v1::DownloadMapResponse>> reader =
      maps_->DownloadMap(context.get(), request);
  v1::GetMapResponse assembled;
  v1::DownloadMapResponse message;
  std::string* cells = assembled.mutable_cells();
  int64_t expected = -1;
  absl::Status shape;
  while (reader->Read(&message)) {
    if (message.has_info()) {
      *assembled.mutable_info() = message.info();
      expected = int64_t{message.info().width()} * message.info().height();
      cells->reserve(static_cast<size_t>(expected));
      continue;
    }
    const v1::CellBand& band = message.band();
    const int64_t width = assembled.info().width();
    if (shape.ok() && (expected < 0 || width <= 0 ||
                       int64_t{band.first_row()} * width !=
                           static_cast<int64_t>(cells->size()))) {
      shape = absl::InternalError(absl::StrCat(
          "DownloadMap of '", name, "': band at row ", band.first_row(),
          " does not continue the ", cells->size(), " bytes received"));
    }
    if (shape.ok()) cells->append(band.cells());
  }
  const grpc::Status status = reader->Finish();
  if (!status.ok()) return FromGrpcStatus(status);
  if (!shape.ok()) return shape;
  if (static_cast<int64_t>(cells->size()) != expected) {
    return absl::InternalError(absl::StrCat("DownloadMap of '", name, "': got ",
                                            cells->size(), " cell bytes, expected ",
                                            expected));
  }
  return assembled;
}

absl::StatusOr<v1::ListMapsResponse> PathdClient::ListMaps() const {
  return Invoke<v1::ListMapsResponse>(
      timeout_,
      [&](grpc::ClientContext* context, v1::ListMapsResponse* response) {
        return maps_->ListMaps(context, v1::ListMapsRequest(), response);
      });
}

absl::StatusOr<v1::DeleteMapResponse> PathdClient::DeleteMap(
    const std::string& name) const {
  v1::DeleteMapRequest request;
  request.set_name(name);
  return InvokeOnMap<v1::DeleteMapResponse>(
      timeout_, name,
      [&](grpc::ClientContext* context, v1::DeleteMapResponse* response) {
        return maps_->DeleteMap(context, request, response);
      });
}

absl::StatusOr<v1::UpdateMapResponse> PathdClient::UpdateMap(
    const v1::UpdateMapRequest& request) const {
  return InvokeOnMap<v1::UpdateMapResponse>(
      timeout_, request.name(),
      [&](grpc::ClientContext* context, v1::UpdateMapResponse* response) {
        return maps_->UpdateMap(context, request, response);
      });
}

absl::StatusOr<v1::PlanResponse> PathdClient::Plan(
    const v1::PlanRequest& request) const {
  return InvokePacked<v1::PlanResponse>(
      timeout_, request,
      [&](grpc::ClientContext* context, const v1::PlanRequest& packed,
          v1::PlanResponse* response) { return planner_->Plan(context, packed, response); });
}

absl::StatusOr<v1::CostToGoResponse> PathdClient::CostToGo(
    const v1::CostToGoRequest& request) const {
  return InvokeOnMap<v1::CostToGoResponse>(
      timeout_, request.map(),
      [&](grpc::ClientContext* context, v1::CostToGoResponse* response) {
        return planner_->CostToGo(context, request, response);
      });
}

absl::StatusOr<v1::TableResponse> PathdClient::Table(const v1::TableRequest& request) const {
  return InvokeOnMap<v1::TableResponse>(
      timeout_, request.map(),
      [&](grpc::ClientContext* context, v1::TableResponse* response) {
        return planner_->Table(context, request, response);
      });
}

absl::StatusOr<v1::NearestResponse> PathdClient::Nearest(const v1::NearestRequest& request) const {
  return InvokeOnMap<v1::NearestResponse>(
      timeout_, request.map(),
      [&](grpc::ClientContext* context, v1::NearestResponse* response) {
        return planner_->Nearest(context, request, response);
      });
}

absl::StatusOr<v1::TripResponse> PathdClient::Trip(const v1::TripRequest& request) const {
  return InvokePacked<v1::TripResponse>(
      timeout_, request,
      [&](grpc::ClientContext* context, const v1::TripRequest& packed,
          v1::TripResponse* response) { return planner_->Trip(context, packed, response); });
}

absl::StatusOr<v1::IsochroneResponse> PathdClient::Isochrone(const v1::IsochroneRequest& request) const {
  return InvokeOnMap<v1::IsochroneResponse>(
      timeout_, request.map(),
      [&](grpc::ClientContext* context, v1::IsochroneResponse* response) {
        return planner_->Isochrone(context, request, response);
      });
}

absl::StatusOr<v1::PlanFleetResponse> PathdClient::PlanFleet(
    const v1::PlanFleetRequest& request) const {
  return InvokeOnMap<v1::PlanFleetResponse>(
      timeout_, request.map(),
      [&](grpc::ClientContext* context, v1::PlanFleetResponse* response) {
        return planner_->PlanFleet(context, request, response);
      });
}

absl::StatusOr<v1::IsPathValidResponse> PathdClient::IsPathValid(
    const v1::IsPathValidRequest& request) const {
  return InvokeOnMap<v1::IsPathValidResponse>(
      timeout_, request.map(),
      [&](grpc::ClientContext* context, v1::IsPathValidResponse* response) {
        return planner_->IsPathValid(context, request, response);
      });
}

absl::StatusOr<v1::GetCacheStatsResponse> PathdClient::GetCacheStats() const {
  return Invoke<v1::GetCacheStatsResponse>(
      timeout_,
      [&](grpc::ClientContext* context, v1::GetCacheStatsResponse* response) {
        return planner_->GetCacheStats(context, v1::GetCacheStatsRequest(),
                                       response);
      });
}

absl::StatusOr<v1::ListSessionsResponse> PathdClient::ListSessions(
    const std::string& map) const {
  v1::ListSessionsRequest request;
  request.set_map(map);
  return Invoke<v1::ListSessionsResponse>(
      timeout_, [&](grpc::ClientContext* context, v1::ListSessionsResponse* response) {
        return planner_->ListSessions(context, request, response);
      });
}

std::unique_ptr<
    grpc::ClientReaderWriterInterface<v1::NavigateRequest, v1::NavigateResponse>>
PathdClient::Navigate(grpc::ClientContext* context,
                      const std::string& map) const {
  SetMapHeader(*context, map);
  return std::make_unique<UnpackingBidiStream<v1::NavigateRequest, v1::NavigateResponse>>(
      planner_->Navigate(context));
}

std::unique_ptr<grpc::ClientReaderInterface<v1::PlanStreamEvent>>
PathdClient::PlanStream(grpc::ClientContext* context,
                        const v1::PlanRequest& request) const {
  SetMapHeader(*context, request.map());
  v1::PlanRequest packed = request;
  AskForPackedPath(&packed);
  return std::make_unique<
      UnpackingStream<grpc::ClientReaderInterface<v1::PlanStreamEvent>, v1::PlanStreamEvent>>(
      planner_->PlanStream(context, packed));
}

std::unique_ptr<grpc::ClientReaderWriterInterface<v1::PlanBatchRequest,
                                                  v1::PlanBatchResponse>>
PathdClient::PlanBatch(grpc::ClientContext* context,
                       const std::string& map) const {
  SetMapHeader(*context, map);
  return std::make_unique<UnpackingBidiStream<v1::PlanBatchRequest, v1::PlanBatchResponse>>(
      planner_->PlanBatch(context));
}

std::unique_ptr<grpc::ClientReaderInterface<v1::MapEvent>>
PathdClient::WatchMap(grpc::ClientContext* context,
                      const v1::WatchMapRequest& request) const {
  SetMapHeader(*context, request.name());
  return maps_->WatchMap(context, request);
}

absl::StatusOr<grpc::health::v1::HealthCheckResponse> PathdClient::CheckHealth(
    const std::string& service) const {
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  return Invoke<grpc::health::v1::HealthCheckResponse>(
      timeout_, [&](grpc::ClientContext* context,
                    grpc::health::v1::HealthCheckResponse* response) {
        return health_->Check(context, request, response);
      });
}

}  // namespace pathd::client
