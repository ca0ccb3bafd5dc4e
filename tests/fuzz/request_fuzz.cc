// Fuzz target: the request -> core translation of the services
// (server/convert.h) and what the service runs before and after planning.
// The first byte picks the message (PlanRequest, UpdateMapRequest,
// CreateMapRequest, by value mod 3); the rest is its binary serialisation.
// Each input gets a fresh MapStore holding two small maps, so inputs do not
// depend on each other. Plans run for real, under a small expansion budget
// standing in for --max_expansions. Besides "no crash, no UB", a found path
// must be a legal path between the endpoints asked for, an update must equal
// the changes applied cell by cell, and a map_dir file must never be read
// from outside the directory.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "google/protobuf/stubs/logging.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/search/endpoints.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map/inflation.h"
#include "core/map_io/map_io.h"
#include "core/postprocess/path_simplify.h"
#include "core/planning/plan_query.h"
#include "core/postprocess/plan_through.h"
#include "core/search/planner.h"
#include "core/search/search_scratch.h"
#include "pathd/v1/map_service.pb.h"
#include "pathd/v1/planner_service.pb.h"
#include "proto/path_codec.h"
#include "server/convert.h"
#include "server/storage/map_dir.h"
#include "server/map_store.h"
#include "tests/fuzz/fuzz_check.h"

namespace pathd::server {
namespace {

namespace fs = std::filesystem;

// Small enough that every planner on every map finishes in microseconds, big
// enough for the limit checks to be reached by plausible requests.
constexpr int64_t kMaxMapCells = 4096;
constexpr int64_t kMaxExpansions = 4096;
constexpr size_t kMaxRecordedExpansions = 256;

// "weighted": 24 x 20, resolution 0.25, a rotated origin, every kind of cost
// (free, weighted, inscribed, lethal, unknown) from a fixed LCG, with (0, 0),
// (23, 19), (12, 10) and (5, 15) free. "open": 8 x 8 free cells at the
// default pose.
std::unique_ptr<MapStore> MakeStore() {
  auto store = std::make_unique<MapStore>(kMaxMapCells);
  Grid weighted = *Grid::Create(24, 20);
  uint32_t state = 12345;
  for (int32_t y = 0; y < weighted.height(); ++y) {
    for (int32_t x = 0; x < weighted.width(); ++x) {
      state = state * 1103515245u + 12345u;
      const uint32_t r = (state >> 16) % 100;
      const uint8_t cost = r < 55   ? kFreeCost
                           : r < 75 ? static_cast<uint8_t>(1 + (state >> 8) % 252)
                           : r < 80 ? kInscribedCost
                           : r < 95 ? kLethalCost
                                    : kUnknownCost;
      weighted.set_cost(x, y, cost);
    }
  }
  // Known free cells for the seed requests to plan between.
  for (const Cell c : {Cell{0, 0}, Cell{23, 19}, Cell{12, 10}, Cell{5, 15}}) {
    weighted.set_cost(c, kFreeCost);
  }
  weighted.set_resolution(0.25);
  weighted.set_origin(GridOrigin{-2.5, 1.0, 0.4});
  PATHD_FUZZ_CHECK(store->Create("weighted", std::move(weighted), false).ok(),
                   "store set-up");
  PATHD_FUZZ_CHECK(store->Create("open", *Grid::Create(8, 8), false).ok(),
                   "store set-up");
  return store;
}

// A --map_dir with a few small maps, a file in a subfolder, and two ways out
// of it that LoadMapDirFile must refuse: a symlink to a map beside the
// directory, and a YAML naming an image beside it. Created once per process
// under the temp folder, removed at exit.
class MapDir {
 public:
  static const MapDir& Get() {
    static const MapDir* dir = new MapDir();
    return *dir;
  }
  const std::string& path() const { return dir_; }

 private:
  MapDir() {
    std::string pattern = (fs::temp_directory_path() / "pathd_fuzz_XXXXXX").string();
    PATHD_FUZZ_CHECK(mkdtemp(pattern.data()) != nullptr, "mkdtemp");
    root_ = pattern;
    dir_ = (fs::path(root_) / "maps").string();
    fs::create_directories(fs::path(dir_) / "sub");
    const std::string map = "type octile\nheight 3\nwidth 4\nmap\n.@..\n..@.\n....\n";
    Write(fs::path(root_) / "outside.map", map);
    Write(fs::path(root_) / "outside.pgm", "P2\n2 1\n255\n0 255\n");
    Write(fs::path(dir_) / "small.map", map);
    Write(fs::path(dir_) / "sub" / "inner.map", map);
    Write(fs::path(dir_) / "ros.pgm", "P2\n3 2\n255\n0 128 255\n255 255 0\n");
    Write(fs::path(dir_) / "ros.yaml",
          "image: ros.pgm\nresolution: 0.1\norigin: [1.0, -2.0, 0.0]\n");
    Write(fs::path(dir_) / "escape.yaml",
          "image: ../outside.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n");
    fs::create_symlink("../outside.map", fs::path(dir_) / "escape.map");
    std::atexit([] { fs::remove_all(Get().root_); });
  }

  static void Write(const fs::path& path, std::string_view text) {
    std::ofstream(path, std::ios::binary) << text;
  }

  std::string root_;
  std::string dir_;
};

void CheckPlanResult(const Grid& grid, const PlanRequest& request,
                     const PlanResult& result, int64_t max_expansions) {
  if (result.found()) {
    PATHD_FUZZ_CHECK(!result.path.empty(), "found path is not empty");
    PATHD_FUZZ_CHECK(result.path.front() == request.start, "path starts at start");
    PATHD_FUZZ_CHECK(result.path.back() == request.goal, "path ends at goal");
    const PathMeasure m = MeasureResultPath(grid, result, request.cost);
    PATHD_FUZZ_CHECK(m.valid, "found path is legal");
  }
  v1::PlanResponse response;
  FillPlanResponse(result, request, grid, max_expansions, v1::PATH_ENCODING_BOTH, &response);
  PATHD_FUZZ_CHECK(response.path_size() == static_cast<int>(result.path.size()),
                   "response carries the path");
  PATHD_FUZZ_CHECK(response.world_path_size() == response.path_size(),
                   "a world point per cell");
  const absl::StatusOr<std::vector<PackedCell>> packed = DecodePackedPath(response.packed_path());
  PATHD_FUZZ_CHECK(packed.ok() && packed->size() == result.path.size(), "packed path decodes");
  for (size_t i = 0; i < packed->size(); ++i) {
    PATHD_FUZZ_CHECK((*packed)[i] == (PackedCell{result.path[i].x, result.path[i].y}),
                     "packed path equals the path");
  }
}

// What a Plan runs (server/rpc/plan_call.cc): DecodePlanQuery, the façade's
// CheckPlanQuery and RunPlanQuery, and the response builder, with the
// incremental planners run from scratch from the registry instead of through
// the server's cache.
void Plan(const MapStore& store, const v1::PlanRequest& request) {
  absl::StatusOr<DecodedQuery> decoded =
      DecodePlanQuery(WireQueryOf(request), store,
                      QueryLimits{.max_expansions = kMaxExpansions,
                                  .max_cost_to_go_cells = kMaxMapCells});
  if (!decoded.ok()) return;
  PlanQuery& query = decoded->query;
  PATHD_FUZZ_CHECK(query.max_expansions >= 1 && query.max_expansions <= kMaxExpansions,
                   "budget capped by the server's");
  PATHD_FUZZ_CHECK(query.goal_tolerance_cells >= 0 &&
                       query.goal_tolerance_cells <= kMaxGoalToleranceCells,
                   "tolerance");
  const Grid& stored = *decoded->snapshot->grid;
  // The server answers these two from its cache, which refuses via points.
  const bool stateful = request.planner() == v1::PLANNER_SPM ||
                        request.planner() == v1::PLANNER_DSTAR_LITE;
  if (!CheckPlanQuery(stored, stateful, &query).ok()) return;
  PATHD_FUZZ_CHECK(query.request.goal == query.requested_goal ||
                       (stored.InBounds(query.request.goal) &&
                        Traversable(stored.cost(query.request.goal),
                                    query.request.cost.unknown_is_free)),
                   "substitute goal is traversable");
  const Planner* planner = PlannerRegistry::Default().Get(query.planner);
  PATHD_FUZZ_CHECK(planner != nullptr, "every wire planner is registered");
  std::optional<ExpansionRecorder> recorder;
  if (decoded->return_expansions) {
    recorder.emplace(kMaxRecordedExpansions);
    query.request.expansion_recorder = &*recorder;
  }
  PlanEngine engine;
  engine.planner = planner;  // the façade inflates for a robot radius itself
  const StopCondition stop(absl::InfiniteFuture(), nullptr, query.max_expansions);
  SearchScratch scratch;
  absl::StatusOr<PlanAnswer> answer = RunPlanQuery(
      query, PlanSnapshot{decoded->snapshot->grid, decoded->snapshot->version},
      engine, stop, scratch);
  if (!answer.ok()) return;
  if (recorder.has_value()) {
    PATHD_FUZZ_CHECK(recorder->cells().size() <= kMaxRecordedExpansions,
                     "recorder cap");
  }
  // A partial plan's path ends at the last reached via point.
  if (!query.via.empty() && !answer->result.found()) return;
  PlanRequest planned = query.request;
  planned.goal = answer->goal;
  CheckPlanResult(*answer->source.grid, planned, answer->result, query.max_expansions);
  v1::PlanResponse response;
  BuildPlanResponse(query, *answer, decoded->expansion_limit_source, decoded->path_encoding,
                    &response);
  PATHD_FUZZ_CHECK(UnpackPlanPath(&response).ok(), "a packed path decodes");
  PATHD_FUZZ_CHECK(response.path_size() == static_cast<int>(answer->result.path.size()),
                   "the built response carries the path");
}

// MapServiceImpl::DoUpdateMap, checked against the changes applied one cell
// at a time; then the same batch again, so the store's second update takes
// the recycled-buffer path.
void Update(MapStore& store, const v1::UpdateMapRequest& request) {
  absl::StatusOr<std::vector<MapChange>> changes = MapChangesFromProto(request.changes());
  if (!changes.ok()) return;
  absl::StatusOr<std::shared_ptr<const MapSnapshot>> found = store.Get(request.name());
  std::optional<uint64_t> expected;
  if (request.has_expected_version()) expected = request.expected_version();
  absl::StatusOr<MapUpdateResult> result = store.Update(request.name(), *changes, expected);
  if (!result.ok()) return;
  PATHD_FUZZ_CHECK(found.ok(), "an updated map existed");
  std::shared_ptr<const MapSnapshot> before = *std::move(found);
  Grid want = *before->grid;
  for (const MapChange& c : *changes) {
    PATHD_FUZZ_CHECK(c.cost <= 255 && want.InBounds(c.x_min, c.y_min) &&
                         want.InBounds(c.x_max, c.y_max),
                     "accepted change is on the map");
    for (int32_t y = c.y_min; y <= c.y_max; ++y) {
      for (int32_t x = c.x_min; x <= c.x_max; ++x) {
        want.set_cost(x, y, static_cast<uint8_t>(c.cost));
      }
    }
  }
  const MapSnapshot& after = *result->snapshot;
  PATHD_FUZZ_CHECK(after.version == before->version + 1, "version + 1");
  PATHD_FUZZ_CHECK(after.grid->cells() == want.cells(), "update applied");
  int64_t differing = 0;
  for (size_t i = 0; i < want.size(); ++i) {
    differing += want.cells()[i] != before->grid->cells()[i];
  }
  PATHD_FUZZ_CHECK(result->cells_changed == differing, "cells_changed");
  if (after.changes_known) {
    PATHD_FUZZ_CHECK(static_cast<int64_t>(after.changed_cells.size()) == differing,
                     "changed_cells");
  }
  // Unreferenced, the old version's grid becomes the spare buffer the next
  // update recycles.
  before.reset();
  result = store.Update(request.name(), *changes, std::nullopt);
  PATHD_FUZZ_CHECK(result.ok(), "the same batch applies again");
  PATHD_FUZZ_CHECK(result->snapshot->grid->cells() == want.cells(), "idempotent");
  PATHD_FUZZ_CHECK(result->cells_changed == 0, "nothing changed the second time");
}

// MapServiceImpl::DoCreateMap and BuildGrid.
void Create(MapStore& store, const v1::CreateMapRequest& request) {
  if (!MapStore::ValidateName(request.name()).ok()) return;
  const auto apply_pose = [&](Grid& grid) {
    absl::StatusOr<double> resolution = ResolutionFromProto(request.resolution());
    absl::StatusOr<GridOrigin> origin = OriginFromProto(request.origin());
    if (!resolution.ok() || !origin.ok()) return false;
    grid.set_resolution(*resolution);
    grid.set_origin(*origin);
    return true;
  };
  absl::StatusOr<Grid> grid;
  switch (request.source_case()) {
    case v1::CreateMapRequest::kRaw:
      grid = GridFromRawCells(request.raw(), store);
      if (grid.ok() && !apply_pose(*grid)) return;
      break;
    case v1::CreateMapRequest::kMovingaiText:
      grid = ParseMovingAiMap(request.movingai_text(), "movingai_text", store.max_cells());
      if (grid.ok() && !apply_pose(*grid)) return;
      break;
    case v1::CreateMapRequest::kRosMap: {
      absl::StatusOr<RosMapMetadata> metadata =
          ParseRosMapYaml(request.ros_map().yaml(), "ros_map.yaml");
      if (!metadata.ok()) return;
      grid = ParseRosMap(*metadata, request.ros_map().image(), "ros_map.image",
                         store.max_cells());
      break;
    }
    case v1::CreateMapRequest::kMapDirFile: {
      const MapDir& dir = MapDir::Get();
      const std::string& file = request.map_dir_file();
      grid = LoadMapDirFile(dir.path(), file, store.max_cells());
      if (!grid.ok()) return;
      absl::StatusOr<fs::path> resolved = ResolveMapDirFile(dir.path(), file);
      PATHD_FUZZ_CHECK(resolved.ok(), "a loaded file resolves");
      const fs::path inside = fs::canonical(dir.path());
      const fs::path relative = resolved->lexically_relative(inside);
      PATHD_FUZZ_CHECK(!relative.empty() && *relative.begin() != "..",
                       "map_dir file inside the directory");
      PATHD_FUZZ_CHECK(resolved->filename() != "escape.yaml",
                       "a YAML's image inside the directory");
      if (fs::path(file).extension() == ".map" && !apply_pose(*grid)) return;
      break;
    }
    case v1::CreateMapRequest::SOURCE_NOT_SET:
      return;
  }
  if (!grid.ok()) return;
  PATHD_FUZZ_CHECK(static_cast<int64_t>(grid->size()) <= store.max_cells(),
                   "--max_map_cells applies before the store");
  const int32_t width = grid->width();
  const int32_t height = grid->height();
  absl::StatusOr<std::shared_ptr<const MapSnapshot>> snapshot =
      store.Create(request.name(), *std::move(grid), request.replace());
  if (!snapshot.ok()) return;
  v1::MapInfo info;
  FillMapInfo(**snapshot, &info);
  PATHD_FUZZ_CHECK(info.width() == width && info.height() == height, "map info");
  PATHD_FUZZ_CHECK(info.free_cells() + info.blocked_cells() <=
                       int64_t{width} * int64_t{height},
                   "cell counts");
}

}  // namespace
}  // namespace pathd::server

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace pathd::server;  // NOLINT: file-local entry point
  if (size == 0) return 0;
  // Invalid UTF-8 in a string field fails the parse with a log line; the
  // rejection is what counts, the line would only slow the fuzzer down.
  const google::protobuf::LogSilencer quiet;
  const void* body = data + 1;
  const int body_size = static_cast<int>(size - 1);
  std::unique_ptr<MapStore> store = MakeStore();
  switch (data[0] % 3) {
    case 0: {
      pathd::v1::PlanRequest request;
      if (request.ParseFromArray(body, body_size)) Plan(*store, request);
      break;
    }
    case 1: {
      pathd::v1::UpdateMapRequest request;
      if (request.ParseFromArray(body, body_size)) Update(*store, request);
      break;
    }
    case 2: {
      pathd::v1::CreateMapRequest request;
      if (request.ParseFromArray(body, body_size)) Create(*store, request);
      break;
    }
  }
  return 0;
}
