// UploadMap and DownloadMap: whole maps in bands of rows.
#include "server/rpc/map_transfer.h"

#include <algorithm>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/map/grid.h"
#include "core/status_macros.h"
#include "server/convert.h"
#include "server/grpc_status.h"
#include "server/request_log.h"

namespace pathd::server {

absl::Status UploadBudget::Reserve(int64_t cells) {
  int64_t held = held_.load();
  do {
    if (held + cells > max_cells_) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "uploads in progress hold %d cells; this upload's %d would pass the "
          "server's limit of %d cells (--max_map_cells); retry when they end",
          held, cells, max_cells_));
    }
  } while (!held_.compare_exchange_weak(held, held + cells));
  return absl::OkStatus();
}

namespace {

// Reads the header, then each band into the grid; creates the map when the
// client half-closes after the last row. The grid is allocated only after
// the header passed every check and the budget admitted it, so a refused
// upload costs nothing but its header.
class UploadReactor final
    : public grpc::ServerReadReactor<v1::UploadMapRequest> {
 public:
  UploadReactor(MapStore& store, UploadBudget& budget,
                v1::CreateMapResponse* response)
      : store_(store), budget_(budget), response_(response) {
    StartRead(&message_);
  }

  void OnReadDone(bool ok) override {
    if (!ok) {
      // The client half-closed (or the call broke: then Finish is a no-op
      // and OnDone follows).
      End(Complete());
      return;
    }
    absl::Status status = message_.has_header() ? OnHeader() : OnBand();
    if (!status.ok()) {
      End(status);
      return;
    }
    StartRead(&message_);
  }

  void OnDone() override {
    ReleaseCells();
    delete this;
  }

 private:
  absl::Status OnHeader() {
    if (grid_.has_value() || !name_.empty()) {
      return absl::InvalidArgumentError(
          "header: a second header; the header is the first message only");
    }
    const v1::UploadMapHeader& header = message_.header();
    name_ = header.name();
    if (absl::Status s = MapStore::ValidateName(header.name()); !s.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat("header.name: ", s.message()));
    }
    if (header.width() < 1 || header.width() > kMaxGridDimension ||
        header.height() < 1 || header.height() > kMaxGridDimension) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "header.width %d and header.height %d must be in 1..%d",
          header.width(), header.height(), kMaxGridDimension));
    }
    PATHD_RETURN_IF_ERROR(store_.CheckSize(header.width(), header.height()));
    absl::StatusOr<double> resolution =
        ResolutionFromProto(header.resolution());
    if (!resolution.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat("header.", resolution.status().message()));
    }
    absl::StatusOr<GridOrigin> origin = OriginFromProto(header.origin());
    if (!origin.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat("header.", origin.status().message()));
    }
    const int64_t cells = int64_t{header.width()} * header.height();
    PATHD_RETURN_IF_ERROR(budget_.Reserve(cells));
    reserved_ = cells;
    PATHD_ASSIGN_OR_RETURN(Grid grid,
                           Grid::Create(header.width(), header.height()));
    grid.set_resolution(*resolution);
    grid.set_origin(*origin);
    grid_ = std::move(grid);
    replace_ = header.replace();
    return absl::OkStatus();
  }

  absl::Status OnBand() {
    if (!grid_.has_value()) {
      return absl::InvalidArgumentError(
          message_.has_band()
              ? "band before the header; the first message must be a header"
              : "message 1 has neither header nor band");
    }
    if (!message_.has_band()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "message after row %d has neither header nor band", rows_));
    }
    const v1::CellBand& band = message_.band();
    const int32_t width = grid_->width();
    if (band.first_row() != rows_) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "band.first_row %d: expected %d (bands are sent top to bottom, each "
          "starting where the previous one ended)",
          band.first_row(), rows_));
    }
    const std::string& cells = band.cells();
    if (cells.empty() || cells.size() % static_cast<size_t>(width) != 0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "band.cells at row %d: %d bytes is not a positive whole number of "
          "rows of %d cells",
          band.first_row(), cells.size(), width));
    }
    const int64_t band_rows = static_cast<int64_t>(cells.size() / width);
    if (rows_ + band_rows > grid_->height()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "band.cells at row %d: %d rows pass the header.height of %d",
          band.first_row(), band_rows, grid_->height()));
    }
    std::copy(cells.begin(), cells.end(),
              grid_->mutable_cells().begin() + grid_->Index(0, rows_));
    rows_ += static_cast<int32_t>(band_rows);
    // The band's bytes are not needed any more; a 1 MiB buffer kept alive
    // per call is harmless, a large one would double the peak.
    message_.Clear();
    return absl::OkStatus();
  }

  absl::Status Complete() {
    if (!grid_.has_value()) {
      return absl::InvalidArgumentError(
          "the stream ended before its header; nothing was created");
    }
    if (rows_ != grid_->height()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "the stream ended after %d of header.height %d rows; nothing was "
          "created",
          rows_, grid_->height()));
    }
    // As CreateMap: returns once the map is durable (with --data_dir).
    absl::StatusOr<std::shared_ptr<const MapSnapshot>> snapshot =
        store_.Create(name_, *std::move(grid_), replace_);
    grid_.reset();
    PATHD_RETURN_IF_ERROR(snapshot.status());
    FillMapInfo(**snapshot, response_->mutable_info());
    return absl::OkStatus();
  }

  // The grid and its reservation go together.
  void ReleaseCells() {
    grid_.reset();
    if (reserved_ > 0) budget_.Release(reserved_);
    reserved_ = 0;
  }

  void End(const absl::Status& status) {
    // The cells are dropped before the call ends: a refused upload frees
    // its memory and its share of the budget now, not when gRPC gets round
    // to OnDone (the next upload may already be at its header).
    ReleaseCells();
    LogRequest("UploadMap", name_.empty() ? "-" : name_,
               absl::StrFormat("rows=%d version=%d", rows_,
                               response_->info().version()),
               status, received_, RequestLabels{.planner = {}, .stream = true});
    Finish(ToGrpcStatus(status));
  }

  MapStore& store_;
  UploadBudget& budget_;
  v1::CreateMapResponse* const response_;
  const absl::Time received_ = absl::Now();
  v1::UploadMapRequest message_;
  std::string name_;
  std::optional<Grid> grid_;
  bool replace_ = false;
  int32_t rows_ = 0;
  int64_t reserved_ = 0;
};

// Sends the metadata, then bands of at most kDownloadBandBytes, one write at
// a time (the next band is built when the previous one is on its way).
class DownloadReactor final
    : public grpc::ServerWriteReactor<v1::DownloadMapResponse> {
 public:
  DownloadReactor(const MapStore& store, const v1::DownloadMapRequest& request)
      : name_(request.name()) {
    absl::StatusOr<std::shared_ptr<const MapSnapshot>> snapshot =
        store.Get(request.name());
    if (!snapshot.ok()) {
      End(snapshot.status());
      return;
    }
    snapshot_ = *std::move(snapshot);
    const int32_t width = snapshot_->grid->width();
    rows_per_band_ = static_cast<int32_t>(std::clamp<int64_t>(
        kDownloadBandBytes / width, 1, snapshot_->grid->height()));
    FillMapInfo(*snapshot_, message_.mutable_info());
    StartWrite(&message_);
  }

  void OnWriteDone(bool ok) override {
    if (!ok) {
      // The client went away; nothing more can be sent.
      End(absl::CancelledError("the client stopped reading"));
      return;
    }
    const Grid& grid = *snapshot_->grid;
    if (next_row_ >= grid.height()) {
      End(absl::OkStatus());
      return;
    }
    const int32_t rows = std::min(rows_per_band_, grid.height() - next_row_);
    message_.Clear();
    v1::CellBand* band = message_.mutable_band();
    band->set_first_row(next_row_);
    band->set_cells(reinterpret_cast<const char*>(grid.cells().data() +
                                                  grid.Index(0, next_row_)),
                    static_cast<size_t>(rows) * grid.width());
    next_row_ += rows;
    StartWrite(&message_);
  }

  void OnDone() override { delete this; }

 private:
  void End(const absl::Status& status) {
    LogRequest("DownloadMap", name_, absl::StrFormat("rows=%d", next_row_),
               status, received_, RequestLabels{.planner = {}, .stream = true});
    snapshot_.reset();
    Finish(ToGrpcStatus(status));
  }

  const std::string name_;
  const absl::Time received_ = absl::Now();
  std::shared_ptr<const MapSnapshot> snapshot_;
  v1::DownloadMapResponse message_;
  int32_t rows_per_band_ = 1;
  int32_t next_row_ = 0;
};

}  // namespace

grpc::ServerReadReactor<v1::UploadMapRequest>* StartUploadMap(
    MapStore& store, UploadBudget& budget, v1::CreateMapResponse* response) {
  return new UploadReactor(store, budget, response);
}

grpc::ServerWriteReactor<v1::DownloadMapResponse>* StartDownloadMap(
    const MapStore& store, const v1::DownloadMapRequest& request) {
  return new DownloadReactor(store, request);
}

}  // namespace pathd::server
