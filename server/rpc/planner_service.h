// pathd.v1.PlannerService: the CallbackService whose handlers check the
// caller's token and hand each RPC to its own file under server/rpc/
// (plan_call, plan_stream, plan_batch, cost_to_go, is_path_valid, navigate).
// A plan is validated on the gRPC thread, then run on the worker pool against
// the map snapshot current when the request arrived, and answered from the
// worker.
#ifndef PATHD_SERVER_RPC_PLANNER_SERVICE_H_
#define PATHD_SERVER_RPC_PLANNER_SERVICE_H_

#include <cstdint>
#include <functional>

#include "absl/time/time.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/auth.h"
#include "server/incremental_cache.h"
#include "server/derived_cache.h"
#include "server/inflation_cache.h"
#include "server/map_store.h"
#include "server/rpc/arena_allocator.h"
#include "server/rpc/navigate.h"
#include "server/worker_pool.h"

namespace pathd::server {

struct PlanDeps;

// Trailing metadata key of a rejected Plan or PlanStream call: the typed
// reason, as a v1::PlanOutcome name (e.g. "PLAN_OUTCOME_START_OCCUPIED").
inline constexpr char kPlanOutcomeMetadataKey[] = "pathd-plan-outcome";

// Thread-safe. `store`, `pool`, `inflation` and `cache` must outlive the
// service, and the pool must be shut down (so every accepted job has answered)
// before the service and the gRPC server that owns the calls go away.
class PlannerServiceImpl final : public v1::PlannerService::CallbackService {
 public:
  struct Options {
    // Cap on expansions per request (--max_expansions); 0 = unlimited.
    int64_t max_expansions = 0;
    // Most points a Plan may return (RESOURCE_EXHAUSTED beyond) and most
    // poses an IsPathValid request may hold (INVALID_ARGUMENT beyond)
    // (--max_path_points).
    int64_t max_path_points = int64_t{1} << 20;
    // Most cells of a cost-to-go field returned in one message: a Plan's
    // return_cost_to_go map, a CostToGo window (--max_cost_to_go_cells).
    int64_t max_cost_to_go_cells = int64_t{1} << 22;
    // Table: most sources x destinations (--max_table_entries).
    int64_t max_table_entries = 250'000;
    // Trip: most waypoints (--max_trip_stops).
    int64_t max_trip_stops = 256;
    // PlanFleet: most robots (--max_fleet_robots).
    int64_t max_fleet_robots = 1000;
    // gRPC's send limit (--max_message_bytes); a Plan or CostToGo response
    // above it answers RESOURCE_EXHAUSTED naming the flag instead of gRPC's
    // bare "Sent message larger than max". 0 = not checked.
    int64_t max_message_bytes = 0;
    // PlanStream: least time between two progress events
    // (--progress_interval).
    absl::Duration progress_interval = absl::Milliseconds(100);
    // PlanBatch: items per stream read but not yet answered
    // (--batch_max_inflight); 0 = twice the worker threads.
    int batch_max_inflight = 0;
    // Most cells PlanResponse.expanded holds (--max_returned_expansions).
    int64_t max_returned_expansions = 1'000'000;
    // Checks every call's token (--auth_tokens); null = none. Must outlive
    // the service.
    const TokenAuthenticator* authenticator = nullptr;
    // Per-version derived representations for the geometric planners; null
    // = built per query. Must outlive the service.
    DerivedCache* derived = nullptr;
  };

  PlannerServiceImpl(const MapStore& store, WorkerPool& pool,
                     InflationCache& inflation, IncrementalCache& cache,
                     NavigationSessions& sessions,
                     Options options);

  // Errors as documented in planner_service.proto; the job is dropped without
  // running when the deadline passed or the client cancelled while queued.
  // PLANNER_SPM and PLANNER_DSTAR_LITE go through the incremental cache.
  grpc::ServerUnaryReactor* Plan(grpc::CallbackServerContext* context,
                                 const v1::PlanRequest* request,
                                 v1::PlanResponse* response) override;

  // The cached shortest path map's field, on a worker like Plan.
  grpc::ServerUnaryReactor* CostToGo(grpc::CallbackServerContext* context,
                                     const v1::CostToGoRequest* request,
                                     v1::CostToGoResponse* response) override;

  // Answers on the gRPC thread (O(path)), or with a robot radius on a worker,
  // which may have to inflate the map first.
  grpc::ServerUnaryReactor* IsPathValid(
      grpc::CallbackServerContext* context,
      const v1::IsPathValidRequest* request,
      v1::IsPathValidResponse* response) override;

  // Answers on the gRPC thread: it only copies counters.
  grpc::ServerUnaryReactor* GetCacheStats(grpc::CallbackServerContext* context,
                                          const v1::GetCacheStatsRequest* request,
                                          v1::GetCacheStatsResponse* response) override;

  // Answers on the gRPC thread: it copies each session's last answer.
  grpc::ServerUnaryReactor* ListSessions(grpc::CallbackServerContext* context,
                                         const v1::ListSessionsRequest* request,
                                         v1::ListSessionsResponse* response) override;

  // Plan with progress events (planner_service.proto); the plan runs on the
  // pool like Plan's, and its stop condition reports the progress.
  grpc::ServerWriteReactor<v1::PlanStreamEvent>* PlanStream(
      grpc::CallbackServerContext* context, const v1::PlanRequest* request) override;

  // Many plans on one stream, each validated on the gRPC thread and run on
  // the pool as Plan's; at most options.batch_max_inflight per stream.
  grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>* PlanBatch(
      grpc::CallbackServerContext* context) override;

  // The fleet map queries (server/rpc/fleet_queries.h), on the pool like
  // Plan.
  grpc::ServerUnaryReactor* Table(grpc::CallbackServerContext* context,
                                  const v1::TableRequest* request,
                                  v1::TableResponse* response) override;
  grpc::ServerUnaryReactor* Nearest(grpc::CallbackServerContext* context,
                                    const v1::NearestRequest* request,
                                    v1::NearestResponse* response) override;
  grpc::ServerUnaryReactor* Trip(grpc::CallbackServerContext* context,
                                 const v1::TripRequest* request,
                                 v1::TripResponse* response) override;
  grpc::ServerUnaryReactor* Isochrone(grpc::CallbackServerContext* context,
                                      const v1::IsochroneRequest* request,
                                      v1::IsochroneResponse* response) override;
  grpc::ServerUnaryReactor* PlanFleet(grpc::CallbackServerContext* context,
                                      const v1::PlanFleetRequest* request,
                                      v1::PlanFleetResponse* response) override;

  // A D* Lite session (server/rpc/navigate.h).
  grpc::ServerBidiReactor<v1::NavigateRequest, v1::NavigateResponse>* Navigate(
      grpc::CallbackServerContext* context) override;

 private:
  // What the RPC files need from the service.
  PlanDeps Deps() const;

  const MapStore& store_;
  WorkerPool& pool_;
  InflationCache& inflation_;
  IncrementalCache& cache_;
  NavigationSessions& sessions_;
  const Options options_;
  // Plan's request and response, on one arena per call.
  ArenaMessageAllocator<v1::PlanRequest, v1::PlanResponse> plan_allocator_;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_PLANNER_SERVICE_H_
