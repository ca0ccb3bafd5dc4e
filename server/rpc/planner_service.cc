// PlannerService: one handler per RPC, each checking the caller's token and
// handing the call to its file (server/rpc/plan_call.cc, plan_stream.cc,
// plan_batch.cc, cost_to_go.cc, is_path_valid.cc, navigate.cc).
#include "server/rpc/planner_service.h"

#include <string>
#include <utility>

#include "absl/time/clock.h"
#include "server/request_log.h"
#include "server/rpc/cost_to_go.h"
#include "server/rpc/fleet_queries.h"
#include "server/rpc/is_path_valid.h"
#include "server/rpc/plan_batch.h"
#include "server/rpc/plan_call.h"
#include "server/rpc/plan_stream.h"

namespace pathd::server {
namespace {

void FillCacheStats(IncrementalCache::Kind kind, const IncrementalCache::Stats& s,
                    v1::CacheStats* out) {
  out->set_name(std::string(IncrementalCache::KindName(kind)));
  out->set_entries(s.entries);
  out->set_bytes(s.bytes);
  out->set_budget_bytes(s.budget_bytes);
  out->set_hits(s.hits);
  out->set_misses(s.misses);
  out->set_evictions(s.evictions);
  out->set_repairs(s.repairs);
  out->set_rebuilds(s.rebuilds);
}

}  // namespace

PlannerServiceImpl::PlannerServiceImpl(const MapStore& store, WorkerPool& pool,
                                       InflationCache& inflation,
                                       IncrementalCache& cache,
                                       NavigationSessions& sessions, Options options)
    : store_(store),
      pool_(pool),
      inflation_(inflation),
      cache_(cache),
      sessions_(sessions),
      options_(std::move(options)) {
  SetMessageAllocatorFor_Plan(&plan_allocator_);
}

PlanDeps PlannerServiceImpl::Deps() const {
  return PlanDeps{store_, pool_, inflation_, cache_, options_};
}

grpc::ServerBidiReactor<v1::NavigateRequest, v1::NavigateResponse>*
PlannerServiceImpl::Navigate(grpc::CallbackServerContext* context) {
  if (auto* refused = RefuseUnauthorized<
          grpc::ServerBidiReactor<v1::NavigateRequest, v1::NavigateResponse>>(
          options_.authenticator, context, kMethodNavigate)) {
    return refused;
  }
  // Decided now, while the call's metadata is at hand; the session applies
  // it to each observation that would write the shared map.
  return sessions_.Start(context, Authorize(options_.authenticator, *context,
                                            kNavigateSharedObservation));
}

grpc::ServerUnaryReactor* PlannerServiceImpl::Plan(
    grpc::CallbackServerContext* context, const v1::PlanRequest* request,
    v1::PlanResponse* response) {
  if (auto* refused = RefuseUnauthorized(options_.authenticator, context, kMethodPlan)) {
    return refused;
  }
  return ServePlan(Deps(), context, request, response);
}

grpc::ServerUnaryReactor* PlannerServiceImpl::CostToGo(
    grpc::CallbackServerContext* context, const v1::CostToGoRequest* request,
    v1::CostToGoResponse* response) {
  if (auto* refused =
          RefuseUnauthorized(options_.authenticator, context, kMethodCostToGo)) {
    return refused;
  }
  return ServeCostToGo(Deps(), context, request, response);
}

grpc::ServerUnaryReactor* PlannerServiceImpl::IsPathValid(
    grpc::CallbackServerContext* context, const v1::IsPathValidRequest* request,
    v1::IsPathValidResponse* response) {
  if (auto* refused =
          RefuseUnauthorized(options_.authenticator, context, kMethodIsPathValid)) {
    return refused;
  }
  return ServeIsPathValid(Deps(), context, request, response);
}

grpc::ServerUnaryReactor* PlannerServiceImpl::GetCacheStats(
    grpc::CallbackServerContext* context, const v1::GetCacheStatsRequest* /*request*/,
    v1::GetCacheStatsResponse* response) {
  if (auto* refused =
          RefuseUnauthorized(options_.authenticator, context, kMethodGetCacheStats)) {
    return refused;
  }
  const absl::Time received = absl::Now();
  for (const IncrementalCache::Kind kind :
       {IncrementalCache::Kind::kSpm, IncrementalCache::Kind::kDStarLite}) {
    FillCacheStats(kind, cache_.stats(kind), response->add_caches());
  }
  response->set_sessions(sessions_.count());
  response->set_session_bytes(sessions_.bytes());
  LogRequest("GetCacheStats", "-", "", absl::OkStatus(), received);
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

grpc::ServerUnaryReactor* PlannerServiceImpl::ListSessions(
    grpc::CallbackServerContext* context, const v1::ListSessionsRequest* request,
    v1::ListSessionsResponse* response) {
  if (auto* refused =
          RefuseUnauthorized(options_.authenticator, context, kMethodListSessions)) {
    return refused;
  }
  const absl::Time received = absl::Now();
  sessions_.List(request->map(), *response);
  LogRequest("ListSessions", request->map().empty() ? "-" : request->map(), "",
             absl::OkStatus(), received);
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

grpc::ServerWriteReactor<v1::PlanStreamEvent>* PlannerServiceImpl::PlanStream(
    grpc::CallbackServerContext* context, const v1::PlanRequest* request) {
  if (auto* refused = RefuseUnauthorized<grpc::ServerWriteReactor<v1::PlanStreamEvent>>(
          options_.authenticator, context, kMethodPlanStream)) {
    return refused;
  }
  return ServePlanStream(Deps(), options_.progress_interval, context, request);
}

grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>*
PlannerServiceImpl::PlanBatch(grpc::CallbackServerContext* context) {
  if (auto* refused = RefuseUnauthorized<
          grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>>(
          options_.authenticator, context, kMethodPlanBatch)) {
    return refused;
  }
  const size_t max_inflight =
      options_.batch_max_inflight > 0
          ? static_cast<size_t>(options_.batch_max_inflight)
          : static_cast<size_t>(2 * pool_.threads());
  return ServePlanBatch(Deps(), max_inflight, context);
}

grpc::ServerUnaryReactor* PlannerServiceImpl::Table(
    grpc::CallbackServerContext* context, const v1::TableRequest* request,
    v1::TableResponse* response) {
  if (auto* refused = RefuseUnauthorized(options_.authenticator, context, kMethodTable)) {
    return refused;
  }
  return ServeTable(Deps(), context, request, response);
}

grpc::ServerUnaryReactor* PlannerServiceImpl::Nearest(
    grpc::CallbackServerContext* context, const v1::NearestRequest* request,
    v1::NearestResponse* response) {
  if (auto* refused = RefuseUnauthorized(options_.authenticator, context, kMethodNearest)) {
    return refused;
  }
  return ServeNearest(Deps(), context, request, response);
}

grpc::ServerUnaryReactor* PlannerServiceImpl::Trip(
    grpc::CallbackServerContext* context, const v1::TripRequest* request,
    v1::TripResponse* response) {
  if (auto* refused = RefuseUnauthorized(options_.authenticator, context, kMethodTrip)) {
    return refused;
  }
  return ServeTrip(Deps(), context, request, response);
}

grpc::ServerUnaryReactor* PlannerServiceImpl::Isochrone(
    grpc::CallbackServerContext* context, const v1::IsochroneRequest* request,
    v1::IsochroneResponse* response) {
  if (auto* refused = RefuseUnauthorized(options_.authenticator, context, kMethodIsochrone)) {
    return refused;
  }
  return ServeIsochrone(Deps(), context, request, response);
}

grpc::ServerUnaryReactor* PlannerServiceImpl::PlanFleet(
    grpc::CallbackServerContext* context, const v1::PlanFleetRequest* request,
    v1::PlanFleetResponse* response) {
  if (auto* refused = RefuseUnauthorized(options_.authenticator, context, kMethodPlanFleet)) {
    return refused;
  }
  return ServePlanFleet(Deps(), context, request, response);
}

}  // namespace pathd::server
