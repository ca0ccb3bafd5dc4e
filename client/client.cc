// Implementation of the pathd client wrappers.
#include "client/client.h"

#include <algorithm>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "grpcpp/create_channel.h"
#include "grpcpp/security/credentials.h"

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

// The same for a call about no map (ListMaps, health): a load balancer
// routing by map sends it to any replica.
template <typename Response, typename Call>
absl::StatusOr<Response> Invoke(absl::Duration timeout, Call&& call) {
  return InvokeOnMap<Response>(timeout, "", std::forward<Call>(call));
}

}  // namespace

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
  return InvokeOnMap<v1::PlanResponse>(
      timeout_, request.map(),
      [&](grpc::ClientContext* context, v1::PlanResponse* response) {
        return planner_->Plan(context, request, response);
      });
}

absl::StatusOr<v1::CostToGoResponse> PathdClient::CostToGo(
    const v1::CostToGoRequest& request) const {
  return InvokeOnMap<v1::CostToGoResponse>(
      timeout_, request.map(),
      [&](grpc::ClientContext* context, v1::CostToGoResponse* response) {
        return planner_->CostToGo(context, request, response);
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

std::unique_ptr<
    grpc::ClientReaderWriterInterface<v1::NavigateRequest, v1::NavigateResponse>>
PathdClient::Navigate(grpc::ClientContext* context,
                      const std::string& map) const {
  SetMapHeader(*context, map);
  return planner_->Navigate(context);
}

std::unique_ptr<grpc::ClientReaderInterface<v1::PlanStreamEvent>>
PathdClient::PlanStream(grpc::ClientContext* context,
                        const v1::PlanRequest& request) const {
  SetMapHeader(*context, request.map());
  return planner_->PlanStream(context, request);
}

std::unique_ptr<grpc::ClientReaderWriterInterface<v1::PlanBatchRequest,
                                                  v1::PlanBatchResponse>>
PathdClient::PlanBatch(grpc::ClientContext* context,
                       const std::string& map) const {
  SetMapHeader(*context, map);
  return planner_->PlanBatch(context);
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
