// pathd.v1.MapService: create, inspect, update and delete the maps held by
// the MapStore. Every call is cheap enough (at most one parse or one map
// copy) to answer inline on gRPC's callback thread.
#ifndef PATHD_SERVER_RPC_MAP_SERVICE_H_
#define PATHD_SERVER_RPC_MAP_SERVICE_H_

#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "server/auth.h"
#include "server/map_store.h"
#include "server/rpc/map_transfer.h"
#include "server/rpc/watch_map.h"

namespace pathd::server {

// Thread-safe (maps live in the MapStore, WatchMap streams in MapWatchers).
// `store` must outlive it.
class MapServiceImpl final : public v1::MapService::CallbackService {
 public:
  // map_dir: the --map_dir used for CreateMap.map_dir_file; empty = none.
  // max_message_bytes: the largest GetMap response (--max_message_bytes; 0:
  // unchecked). Registers WatchMap's store listener, so construct before
  // serving. `authenticator` checks every call's token (--auth_tokens);
  // null = none; it must outlive the service.
  MapServiceImpl(MapStore& store, std::string map_dir,
                 MapWatchers::Options watch_options = {},
                 int64_t max_message_bytes = 0,
                 const TokenAuthenticator* authenticator = nullptr);

  grpc::ServerUnaryReactor* CreateMap(grpc::CallbackServerContext* context,
                                      const v1::CreateMapRequest* request,
                                      v1::CreateMapResponse* response) override;
  grpc::ServerUnaryReactor* GetMap(grpc::CallbackServerContext* context,
                                   const v1::GetMapRequest* request,
                                   v1::GetMapResponse* response) override;
  grpc::ServerUnaryReactor* ListMaps(grpc::CallbackServerContext* context,
                                     const v1::ListMapsRequest* request,
                                     v1::ListMapsResponse* response) override;
  grpc::ServerUnaryReactor* DeleteMap(grpc::CallbackServerContext* context,
                                      const v1::DeleteMapRequest* request,
                                      v1::DeleteMapResponse* response) override;
  grpc::ServerUnaryReactor* UpdateMap(grpc::CallbackServerContext* context,
                                      const v1::UpdateMapRequest* request,
                                      v1::UpdateMapResponse* response) override;
  grpc::ServerWriteReactor<v1::MapEvent>* WatchMap(
      grpc::CallbackServerContext* context,
      const v1::WatchMapRequest* request) override;
  grpc::ServerReadReactor<v1::UploadMapRequest>* UploadMap(
      grpc::CallbackServerContext* context,
      v1::CreateMapResponse* response) override;
  grpc::ServerWriteReactor<v1::DownloadMapResponse>* DownloadMap(
      grpc::CallbackServerContext* context,
      const v1::DownloadMapRequest* request) override;

  // Ends every WatchMap stream with UNAVAILABLE and refuses new ones.
  void ShutdownWatchers() { watchers_.Shutdown(); }
  const MapWatchers& watchers() const { return watchers_; }

 private:
  // The grid a CreateMap request describes, with resolution and origin set.
  absl::StatusOr<Grid> BuildGrid(const v1::CreateMapRequest& request) const;
  absl::Status DoCreateMap(const v1::CreateMapRequest& request,
                           v1::CreateMapResponse* response);
  absl::Status DoGetMap(const v1::GetMapRequest& request,
                        v1::GetMapResponse* response) const;

  MapStore& store_;
  const std::string map_dir_;
  MapWatchers watchers_;
  // Cells of the UploadMap calls in progress (at most --max_map_cells).
  UploadBudget uploads_;
  const int64_t max_message_bytes_;
  const TokenAuthenticator* const authenticator_;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_MAP_SERVICE_H_
