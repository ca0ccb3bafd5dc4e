// The fleet map queries: Table (many-to-many costs), Nearest (the nearest
// cell a robot may occupy), Trip (the order to visit stops, then its legs)
// and Isochrone (the region within a cost budget, as polygons). Each is
// decoded and checked on the gRPC thread like Plan (the one DecodePlanQuery
// for its cost options; positions named sources[i], waypoints[i], ...), then
// run on the worker pool through core/fleet (server/rpc/unary_call.h).
#ifndef PATHD_SERVER_RPC_FLEET_QUERIES_H_
#define PATHD_SERVER_RPC_FLEET_QUERIES_H_

#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/rpc/plan_call.h"

namespace pathd::server {

// The RPCs (errors as documented in planner_service.proto).
grpc::ServerUnaryReactor* ServeTable(const PlanDeps& deps,
                                     grpc::CallbackServerContext* context,
                                     const v1::TableRequest* request,
                                     v1::TableResponse* response);
grpc::ServerUnaryReactor* ServeNearest(const PlanDeps& deps,
                                       grpc::CallbackServerContext* context,
                                       const v1::NearestRequest* request,
                                       v1::NearestResponse* response);
grpc::ServerUnaryReactor* ServeTrip(const PlanDeps& deps,
                                    grpc::CallbackServerContext* context,
                                    const v1::TripRequest* request,
                                    v1::TripResponse* response);
grpc::ServerUnaryReactor* ServeIsochrone(const PlanDeps& deps,
                                         grpc::CallbackServerContext* context,
                                         const v1::IsochroneRequest* request,
                                         v1::IsochroneResponse* response);
// In fleet_plan.cc.
grpc::ServerUnaryReactor* ServePlanFleet(const PlanDeps& deps,
                                         grpc::CallbackServerContext* context,
                                         const v1::PlanFleetRequest* request,
                                         v1::PlanFleetResponse* response);

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_FLEET_QUERIES_H_
