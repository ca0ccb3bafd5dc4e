// MapService implementation.
#include "server/rpc/map_service.h"

#include <filesystem>
#include <optional>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/map_io/map_io.h"
#include "core/status_macros.h"
#include "server/convert.h"
#include "server/grpc_status.h"
#include "server/storage/map_dir.h"
#include "server/request_log.h"

namespace pathd::server {
namespace {

grpc::ServerUnaryReactor* Answer(grpc::CallbackServerContext* context,
                                 const absl::Status& status) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(ToGrpcStatus(status));
  return reactor;
}

// Raw and Moving AI maps carry no world pose, so the request supplies it.
absl::Status ApplyRequestPose(const v1::CreateMapRequest& request, Grid& grid) {
  PATHD_ASSIGN_OR_RETURN(const double resolution,
                         ResolutionFromProto(request.resolution()));
  PATHD_ASSIGN_OR_RETURN(const GridOrigin origin, OriginFromProto(request.origin()));
  grid.set_resolution(resolution);
  grid.set_origin(origin);
  return absl::OkStatus();
}

}  // namespace

MapServiceImpl::MapServiceImpl(MapStore& store, std::string map_dir,
                               MapWatchers::Options watch_options,
                               int64_t max_message_bytes,
                               const TokenAuthenticator* authenticator)
    : store_(store),
      map_dir_(std::move(map_dir)),
      watchers_(store, watch_options),
      uploads_(store.max_cells()),
      max_message_bytes_(max_message_bytes),
      authenticator_(authenticator) {}

absl::StatusOr<Grid> MapServiceImpl::BuildGrid(
    const v1::CreateMapRequest& request) const {
  switch (request.source_case()) {
    case v1::CreateMapRequest::kRaw: {
      PATHD_ASSIGN_OR_RETURN(Grid grid, GridFromRawCells(request.raw(), store_));
      PATHD_RETURN_IF_ERROR(ApplyRequestPose(request, grid));
      return grid;
    }
    case v1::CreateMapRequest::kMovingaiText: {
      PATHD_ASSIGN_OR_RETURN(
          Grid grid, ParseMovingAiMap(request.movingai_text(), "movingai_text",
                                      store_.max_cells()));
      PATHD_RETURN_IF_ERROR(ApplyRequestPose(request, grid));
      return grid;
    }
    case v1::CreateMapRequest::kRosMap: {
      PATHD_ASSIGN_OR_RETURN(
          const RosMapMetadata metadata,
          ParseRosMapYaml(request.ros_map().yaml(), "ros_map.yaml"));
      return ParseRosMap(metadata, request.ros_map().image(), "ros_map.image",
                         store_.max_cells());
    }
    case v1::CreateMapRequest::kMapDirFile: {
      const std::string& file = request.map_dir_file();
      PATHD_ASSIGN_OR_RETURN(Grid grid,
                             LoadMapDirFile(map_dir_, file, store_.max_cells()));
      // A ROS YAML brings its own pose; a Moving AI file takes the request's.
      if (std::filesystem::path(file).extension() == ".map") {
        PATHD_RETURN_IF_ERROR(ApplyRequestPose(request, grid));
      }
      return grid;
    }
    case v1::CreateMapRequest::SOURCE_NOT_SET:
      break;
  }
  return absl::InvalidArgumentError(
      "source is not set (give raw, movingai_text, ros_map or map_dir_file)");
}

absl::Status MapServiceImpl::DoCreateMap(const v1::CreateMapRequest& request,
                                         v1::CreateMapResponse* response) {
  // Checked first so a bad name is not reported after an expensive parse.
  PATHD_RETURN_IF_ERROR(MapStore::ValidateName(request.name()));
  absl::StatusOr<Grid> built = BuildGrid(request);
  if (absl::IsResourceExhausted(built.status())) {
    // The readers know their limit only as a number; say which flag sets it.
    return absl::ResourceExhaustedError(
        absl::StrCat(built.status().message(), " (--max_map_cells)"));
  }
  PATHD_ASSIGN_OR_RETURN(Grid grid, std::move(built));
  PATHD_ASSIGN_OR_RETURN(
      const std::shared_ptr<const MapSnapshot> snapshot,
      store_.Create(request.name(), std::move(grid), request.replace()));
  FillMapInfo(*snapshot, response->mutable_info());
  return absl::OkStatus();
}

grpc::ServerUnaryReactor* MapServiceImpl::CreateMap(
    grpc::CallbackServerContext* context, const v1::CreateMapRequest* request,
    v1::CreateMapResponse* response) {
  if (auto* refused = RefuseUnauthorized(authenticator_, context, kMethodCreateMap)) {
    return refused;
  }
  const absl::Time received = absl::Now();
  const absl::Status status = DoCreateMap(*request, response);
  LogRequest("CreateMap", request->name(),
             absl::StrFormat("version=%d", response->info().version()), status,
             received);
  return Answer(context, status);
}

absl::Status MapServiceImpl::DoGetMap(const v1::GetMapRequest& request,
                                      v1::GetMapResponse* response) const {
  PATHD_ASSIGN_OR_RETURN(const std::shared_ptr<const MapSnapshot> snapshot,
                         store_.Get(request.name()));
  FillMapInfo(*snapshot, response->mutable_info());
  if (request.include_cells()) {
    const std::vector<uint8_t>& cells = snapshot->grid->cells();
    // Checked before the copy: gRPC's own refusal ("Sent message larger than
    // max") names neither the response nor the flag. The bytes field costs
    // its length plus a tag and a length varint of at most 6 bytes.
    const size_t bytes = response->ByteSizeLong() + cells.size() + 6;
    if (max_message_bytes_ > 0 && bytes > static_cast<size_t>(max_message_bytes_)) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "the cells of map '%s' (%d x %d) make a %d-byte response, more than "
          "the limit of %d bytes (--max_message_bytes); DownloadMap streams it "
          "in bands",
          snapshot->name, snapshot->grid->width(), snapshot->grid->height(), bytes,
          max_message_bytes_));
    }
    response->set_cells(reinterpret_cast<const char*>(cells.data()), cells.size());
  }
  return absl::OkStatus();
}

grpc::ServerUnaryReactor* MapServiceImpl::GetMap(grpc::CallbackServerContext* context,
                                                 const v1::GetMapRequest* request,
                                                 v1::GetMapResponse* response) {
  if (auto* refused = RefuseUnauthorized(authenticator_, context, kMethodGetMap)) {
    return refused;
  }
  const absl::Time received = absl::Now();
  const absl::Status status = DoGetMap(*request, response);
  LogRequest("GetMap", request->name(), "", status, received);
  return Answer(context, status);
}

grpc::ServerUnaryReactor* MapServiceImpl::ListMaps(
    grpc::CallbackServerContext* context, const v1::ListMapsRequest* /*request*/,
    v1::ListMapsResponse* response) {
  if (auto* refused = RefuseUnauthorized(authenticator_, context, kMethodListMaps)) {
    return refused;
  }
  const absl::Time received = absl::Now();
  for (const auto& snapshot : store_.List()) {
    FillMapInfo(*snapshot, response->add_maps());
  }
  LogRequest("ListMaps", "-", absl::StrFormat("maps=%d", response->maps_size()),
             absl::OkStatus(), received);
  return Answer(context, absl::OkStatus());
}

grpc::ServerUnaryReactor* MapServiceImpl::DeleteMap(
    grpc::CallbackServerContext* context, const v1::DeleteMapRequest* request,
    v1::DeleteMapResponse* response) {
  if (auto* refused = RefuseUnauthorized(authenticator_, context, kMethodDeleteMap)) {
    return refused;
  }
  const absl::Time received = absl::Now();
  absl::StatusOr<uint64_t> last = store_.Delete(request->name());
  if (last.ok()) response->set_last_version(*last);
  LogRequest("DeleteMap", request->name(), "", last.status(), received);
  return Answer(context, last.status());
}

grpc::ServerUnaryReactor* MapServiceImpl::UpdateMap(
    grpc::CallbackServerContext* context, const v1::UpdateMapRequest* request,
    v1::UpdateMapResponse* response) {
  if (auto* refused = RefuseUnauthorized(authenticator_, context, kMethodUpdateMap)) {
    return refused;
  }
  const absl::Time received = absl::Now();
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  // Answers on whichever thread the update completes: this one for an error
  // or without --data_dir, the journal's completion thread once the new
  // version is durable, so no gRPC callback thread waits for fdatasync.
  auto finish = [reactor, request, response,
                 received](const absl::StatusOr<MapUpdateResult>& result) {
    if (result.ok()) {
      response->set_version(result->snapshot->version);
      response->set_cells_changed(result->cells_changed);
    }
    LogRequest("UpdateMap", request->name(),
               absl::StrFormat("changes=%d version=%d", request->changes_size(),
                               response->version()),
               result.status(), received);
    reactor->Finish(ToGrpcStatus(result.status()));
  };
  absl::StatusOr<std::vector<MapChange>> changes = MapChangesFromProto(request->changes());
  if (!changes.ok()) {
    finish(changes.status());
    return reactor;
  }
  std::optional<uint64_t> expected;
  if (request->has_expected_version()) expected = request->expected_version();
  store_.UpdateAsync(request->name(), *changes, expected, std::move(finish));
  return reactor;
}

grpc::ServerWriteReactor<v1::MapEvent>* MapServiceImpl::WatchMap(
    grpc::CallbackServerContext* context, const v1::WatchMapRequest* request) {
  if (auto* refused = RefuseUnauthorized<grpc::ServerWriteReactor<v1::MapEvent>>(
          authenticator_, context, kMethodWatchMap)) {
    return refused;
  }
  return watchers_.Start(context, *request);
}

grpc::ServerReadReactor<v1::UploadMapRequest>* MapServiceImpl::UploadMap(
    grpc::CallbackServerContext* context, v1::CreateMapResponse* response) {
  if (auto* refused =
          RefuseUnauthorized<grpc::ServerReadReactor<v1::UploadMapRequest>>(
              authenticator_, context, kMethodUploadMap)) {
    return refused;
  }
  return StartUploadMap(store_, uploads_, response);
}

grpc::ServerWriteReactor<v1::DownloadMapResponse>* MapServiceImpl::DownloadMap(
    grpc::CallbackServerContext* context, const v1::DownloadMapRequest* request) {
  if (auto* refused =
          RefuseUnauthorized<grpc::ServerWriteReactor<v1::DownloadMapResponse>>(
              authenticator_, context, kMethodDownloadMap)) {
    return refused;
  }
  return StartDownloadMap(store_, *request);
}

}  // namespace pathd::server
