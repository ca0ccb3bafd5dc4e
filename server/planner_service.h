// pathd.v1.PlannerService: validates a plan request on the gRPC thread, then
// runs the planner on the worker pool against the map snapshot current when
// the request arrived, and answers from the worker.
#ifndef PATHD_SERVER_PLANNER_SERVICE_H_
#define PATHD_SERVER_PLANNER_SERVICE_H_

#include <cstdint>
#include <functional>

#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/incremental_cache.h"
#include "server/inflation_cache.h"
#include "server/map_store.h"
#include "server/navigation.h"
#include "server/worker_pool.h"

namespace pathd::server {

// Thread-safe. `store`, `pool`, `inflation` and `cache` must outlive the
// service, and the pool must be shut down (so every accepted job has answered)
// before the service and the gRPC server that owns the calls go away.
class PlannerServiceImpl final : public v1::PlannerService::CallbackService {
 public:
  struct Options {
    // Cap on expansions per request (--max_expansions); 0 = unlimited.
    int64_t max_expansions = 0;
    // Most cells PlanResponse.expanded holds (--max_returned_expansions).
    int64_t max_returned_expansions = 1'000'000;
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

  // A D* Lite session (server/navigation.h).
  grpc::ServerBidiReactor<v1::NavigateRequest, v1::NavigateResponse>* Navigate(
      grpc::CallbackServerContext* context) override;

 private:
  const MapStore& store_;
  WorkerPool& pool_;
  InflationCache& inflation_;
  IncrementalCache& cache_;
  NavigationSessions& sessions_;
  const Options options_;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_PLANNER_SERVICE_H_
