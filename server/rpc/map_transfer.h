// MapService's streamed transfers of whole maps, for maps larger than one
// message: UploadMap (header, then bands of rows, into one new map) and
// DownloadMap (metadata, then bands of rows of one snapshot).
#ifndef PATHD_SERVER_RPC_MAP_TRANSFER_H_
#define PATHD_SERVER_RPC_MAP_TRANSFER_H_

#include <grpcpp/support/server_callback.h>

#include <atomic>
#include <cstdint>

#include "absl/status/status.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "server/map_store.h"

namespace pathd::server {

// Most cell bytes one DownloadMap band carries (at least one row is sent
// whatever the width): far under any sensible --max_message_bytes and
// gRPC's 4 MiB default receive limit, so every client reads the bands with
// default channel settings.
inline constexpr int64_t kDownloadBandBytes = int64_t{1} << 20;

// Cells held by uploads in progress, bounded by the store's max_cells:
// admission happens at the header, before the grid is allocated.
// Thread-safe.
class UploadBudget {
 public:
  explicit UploadBudget(int64_t max_cells) : max_cells_(max_cells) {}
  // Reserves `cells` or returns RESOURCE_EXHAUSTED naming --max_map_cells.
  absl::Status Reserve(int64_t cells);
  void Release(int64_t cells) { held_.fetch_sub(cells); }
  int64_t held() const { return held_.load(); }

 private:
  const int64_t max_cells_;
  std::atomic<int64_t> held_{0};
};

// A reactor for one UploadMap call; deletes itself when the call is done.
// `store` and `budget` must outlive the call.
grpc::ServerReadReactor<v1::UploadMapRequest>* StartUploadMap(
    MapStore& store, UploadBudget& budget, v1::CreateMapResponse* response);

// A reactor for one DownloadMap call; deletes itself when the call is done.
// `store` must outlive the call.
grpc::ServerWriteReactor<v1::DownloadMapResponse>* StartDownloadMap(
    const MapStore& store, const v1::DownloadMapRequest& request);

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_MAP_TRANSFER_H_
