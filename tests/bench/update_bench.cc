// update_bench: MapStore::Update latency on a large map (4096 x 4096 by
// default), idle and while planner threads run A* and Dijkstra on fresh
// snapshots, for batches of 100 scattered cells, a 10 x 10 rectangle, 100k
// scattered cells and the whole map; and, measured in the same run, the
// whole-grid copy every update used to make (the "copy/update" ratio). With
// --grpc the small batches also go through a real in-process pathd's
// UpdateMap, to show the transport's share. Figures, not assertions.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/client_context.h>
#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "core/search/registry.h"
#include "core/map/grid.h"
#include "core/search/planner.h"
#include "core/search/search_scratch.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "server/map_store.h"
#include "server/server.h"

ABSL_FLAG(int, size, 4096, "map width and height, cells");
ABSL_FLAG(int, planners, 8, "planner threads in the loaded phases");
ABSL_FLAG(int, updates, 300, "timed updates per small batch kind and phase");
ABSL_FLAG(int, big_updates, 30,
          "timed updates per large batch kind (100k cells, whole map) and phase, "
          "and timed baseline copies");
ABSL_FLAG(int, interval_us, 2000,
          "pause between updates (a costmap publishes every 50-200 ms; the "
          "pause lets the planners take snapshots in between)");
ABSL_FLAG(int, plan_distance, 300,
          "planner goals lie up to this many cells from the start in x and y");
ABSL_FLAG(int, warmup, 50,
          "untimed updates before each timed series: the map's buffer pool grows "
          "to what the planners hold at once (those updates copy the whole grid)");
ABSL_FLAG(bool, grpc, true, "also time the small batches through UpdateMap");
ABSL_FLAG(uint32_t, seed, 1, "random seed");

namespace {

using pathd::Cell;
using pathd::Grid;
using pathd::server::MapChange;
using pathd::server::MapStore;

constexpr char kMap[] = "bench";

// A size x size map with 20% lethal cells, the rest free.
Grid RandomMap(int32_t size, std::mt19937& rng) {
  Grid grid = *Grid::Create(size, size, pathd::kFreeCost);
  std::bernoulli_distribution blocked(0.2);
  for (uint8_t& c : grid.mutable_cells()) {
    if (blocked(rng)) c = pathd::kLethalCost;
  }
  return grid;
}

// Threads that each loop: take the current snapshot, plan between two random
// traversable cells on it (even threads A*, odd Dijkstra), drop it.
class Planners {
 public:
  Planners(const MapStore& store, int count, int32_t distance, uint32_t seed) {
    for (int t = 0; t < count; ++t) done_.push_back(std::make_unique<std::atomic<int>>(0));
    for (int t = 0; t < count; ++t) {
      threads_.emplace_back([this, &store, t, distance, seed] {
        Loop(store, t % 2 == 0 ? "astar" : "dijkstra", distance, seed + t, *done_[t]);
      });
    }
  }
  ~Planners() {
    stop_.store(true);
    for (std::thread& t : threads_) t.join();
  }
  int64_t plans() const { return plans_.load(); }

  // Returns once each thread has finished `count` plans (its search scratch,
  // 24 bytes per cell, is then allocated and touched).
  void AwaitWarm(int count) const {
    for (const auto& done : done_) {
      while (done->load() < count) absl::SleepFor(absl::Milliseconds(10));
    }
  }

 private:
  void Loop(const MapStore& store, const char* name, int32_t distance, uint32_t seed,
            std::atomic<int>& done) {
    const pathd::Planner* planner = pathd::PlannerRegistry::Default().Get(name);
    pathd::SearchScratch scratch;
    std::mt19937 rng(seed);
    while (!stop_.load()) {
      const auto snapshot = *store.Get(kMap);
      const Grid& grid = *snapshot->grid;
      auto free_cell_near = [&](Cell centre, int32_t radius) {
        std::uniform_int_distribution<int32_t> dx(-radius, radius);
        for (;;) {
          const Cell c{std::clamp(centre.x + dx(rng), 0, grid.width() - 1),
                       std::clamp(centre.y + dx(rng), 0, grid.height() - 1)};
          if (grid.cost(c) <= pathd::kMaxTraversableCost) return c;
        }
      };
      const Cell start = free_cell_near(Cell{grid.width() / 2, grid.height() / 2},
                                        grid.width() / 2);
      const Cell goal = free_cell_near(start, distance);
      // The stop condition ends a long search when the bench is done.
      const pathd::StopCondition stop(absl::InfiniteFuture(), &stop_, 0);
      (void)planner->Plan(grid, pathd::PlanRequest::Between(start, goal), stop, scratch);
      ++plans_;
      ++done;
    }
  }

  std::atomic<bool> stop_{false};
  std::atomic<int64_t> plans_{0};
  std::vector<std::unique_ptr<std::atomic<int>>> done_;
  std::vector<std::thread> threads_;
};

struct Summary {
  double median_us = 0;
  double p99_us = 0;
  double max_us = 0;
};

Summary Summarise(std::vector<double> us) {
  std::sort(us.begin(), us.end());
  Summary s;
  s.median_us = us[us.size() / 2];
  s.p99_us = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  s.max_us = us.back();
  return s;
}

// One kind of update batch.
struct BatchKind {
  const char* label;
  bool big;
  std::function<std::vector<MapChange>(int32_t size, int iteration, std::mt19937& rng)> make;
};

std::vector<MapChange> ScatteredCells(int32_t size, int count, std::mt19937& rng) {
  std::uniform_int_distribution<int32_t> coord(0, size - 1);
  std::uniform_int_distribution<uint32_t> cost(0, pathd::kLethalCost);
  std::vector<MapChange> batch;
  batch.reserve(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    batch.push_back(MapChange::ForCell(coord(rng), coord(rng), cost(rng)));
  }
  return batch;
}

const std::vector<BatchKind>& Kinds() {
  static const auto* kinds = new std::vector<BatchKind>{
      {"100 cells", false,
       [](int32_t size, int, std::mt19937& rng) { return ScatteredCells(size, 100, rng); }},
      {"10x10 rect", false,
       [](int32_t size, int i, std::mt19937& rng) {
         std::uniform_int_distribution<int32_t> corner(0, size - 10);
         const int32_t x = corner(rng), y = corner(rng);
         return std::vector<MapChange>{
             MapChange::ForRect(x, y, x + 9, y + 9, (i & 1) == 0 ? 100 : 0)};
       }},
      {"100k cells", true,
       [](int32_t size, int, std::mt19937& rng) { return ScatteredCells(size, 100000, rng); }},
      // Alternating 1 and 2 changes every cell every time: the worst case.
      {"whole map", true,
       [](int32_t size, int i, std::mt19937&) {
         return std::vector<MapChange>{
             MapChange::ForRect(0, 0, size - 1, size - 1, 1 + static_cast<uint32_t>(i & 1))};
       }},
  };
  return *kinds;
}

void PrintHeader() {
  std::printf("%-7s %-22s %5s %10s %10s %10s %9s  %-14s %s\n", "phase", "update", "n",
              "median_us", "p99_us", "max_us", "copy/upd", "buffers r/c/n",
              "replayed: p99/max_us");
}

// Latencies of one batch kind: all, and those of the updates that got their
// buffer by replaying (the others copied or allocated a whole grid).
struct Timings {
  std::vector<double> all_us;
  std::vector<double> replayed_us;
  MapStore::BufferStats buffers;
};

void PrintRow(const char* phase, const std::string& label, const Timings& t,
              double copy_median_us) {
  const Summary s = Summarise(t.all_us);
  const std::string ratio =
      copy_median_us > 0 ? absl::StrFormat("%.1f", copy_median_us / s.median_us) : "-";
  const std::string buffers =
      t.buffers.replayed + t.buffers.copied + t.buffers.allocated == 0
          ? "-"
          : absl::StrFormat("%d/%d/%d", t.buffers.replayed, t.buffers.copied,
                            t.buffers.allocated);
  std::string replayed = "-";
  if (!t.replayed_us.empty()) {
    const Summary r = Summarise(t.replayed_us);
    replayed = absl::StrFormat("%.1f/%.1f", r.p99_us, r.max_us);
  }
  std::printf("%-7s %-22s %5zu %10.1f %10.1f %10.1f %9s  %-14s %s\n", phase, label.c_str(),
              t.all_us.size(), s.median_us, s.p99_us, s.max_us, ratio.c_str(),
              buffers.c_str(), replayed.c_str());
}

// Times `apply` over `count` batches of `kind` (after --warmup untimed
// ones), pausing --interval_us between them; `store` is the store they land
// in.
Timings TimeUpdates(const BatchKind& kind, int count, int32_t size, std::mt19937& rng,
                    const MapStore& store,
                    const std::function<absl::Status(const std::vector<MapChange>&)>& apply) {
  const absl::Duration interval = absl::Microseconds(absl::GetFlag(FLAGS_interval_us));
  Timings t;
  for (int i = -std::max(1, absl::GetFlag(FLAGS_warmup)); i < count; ++i) {
    const std::vector<MapChange> batch = kind.make(size, i, rng);
    absl::SleepFor(interval);
    const MapStore::BufferStats before = store.buffer_stats();
    const absl::Time start = absl::Now();
    const absl::Status status = apply(batch);
    const absl::Duration took = absl::Now() - start;
    if (!status.ok()) {
      std::fprintf(stderr, "update failed: %s\n", std::string(status.message()).c_str());
      std::exit(1);
    }
    if (i < 0) continue;
    const MapStore::BufferStats after = store.buffer_stats();
    const double us = absl::ToDoubleMicroseconds(took);
    t.all_us.push_back(us);
    if (after.replayed > before.replayed) t.replayed_us.push_back(us);
    t.buffers.replayed += after.replayed - before.replayed;
    t.buffers.copied += after.copied - before.copied;
    t.buffers.allocated += after.allocated - before.allocated;
  }
  return t;
}

// The copy an update made before buffers were recycled: a new grid equal to
// the current one.
std::vector<double> TimeFullCopies(const MapStore& store, int count) {
  const absl::Duration interval = absl::Microseconds(absl::GetFlag(FLAGS_interval_us));
  std::vector<double> us;
  for (int i = 0; i < count; ++i) {
    const auto snapshot = *store.Get(kMap);
    absl::SleepFor(interval);
    const absl::Time start = absl::Now();
    auto copy = std::make_shared<Grid>(*snapshot->grid);
    const absl::Duration took = absl::Now() - start;
    if (copy->size() != snapshot->grid->size()) std::exit(1);
    copy.reset();
    us.push_back(absl::ToDoubleMicroseconds(took));
  }
  return us;
}

// Every batch kind against the store, then the baseline copy.
void RunStorePhase(const char* phase, MapStore& store, int32_t size, std::mt19937& rng) {
  Timings copy;
  copy.all_us = TimeFullCopies(store, absl::GetFlag(FLAGS_big_updates));
  const double copy_median_us = Summarise(copy.all_us).median_us;
  for (const BatchKind& kind : Kinds()) {
    const Timings t = TimeUpdates(
        kind, kind.big ? absl::GetFlag(FLAGS_big_updates) : absl::GetFlag(FLAGS_updates), size,
        rng, store, [&](const std::vector<MapChange>& batch) {
          return store.Update(kMap, batch, std::nullopt).status();
        });
    PrintRow(phase, kind.label, t, copy_median_us);
  }
  PrintRow(phase, "full copy (old update)", copy, copy_median_us);
}

pathd::v1::UpdateMapRequest ToRequest(const std::vector<MapChange>& batch) {
  pathd::v1::UpdateMapRequest request;
  request.set_name(kMap);
  for (const MapChange& c : batch) {
    pathd::v1::CellChange* change = request.add_changes();
    change->set_cost(c.cost);
    if (c.is_rect) {
      change->mutable_rect()->set_x_min(c.x_min);
      change->mutable_rect()->set_y_min(c.y_min);
      change->mutable_rect()->set_x_max(c.x_max);
      change->mutable_rect()->set_y_max(c.y_max);
    } else {
      change->mutable_cell()->set_x(c.x_min);
      change->mutable_cell()->set_y(c.y_min);
    }
  }
  return request;
}

// The small batch kinds through UpdateMap on a running server (its store
// listeners included), idle and with planners on the server's store.
int RunGrpc(const Grid& map, int planner_count, int32_t distance, std::mt19937& rng) {
  pathd::server::ServerOptions options;
  options.address = "127.0.0.1:0";
  options.threads = 2;
  options.max_map_cells = static_cast<int64_t>(map.size());
  pathd::server::PathdServer server(options);
  if (absl::Status s = server.Start(); !s.ok()) {
    std::fprintf(stderr, "server: %s\n", std::string(s.message()).c_str());
    return 1;
  }
  if (auto created = server.store().Create(kMap, map, false); !created.ok()) {
    std::fprintf(stderr, "create: %s\n", std::string(created.status().message()).c_str());
    return 1;
  }
  auto stub = pathd::v1::MapService::NewStub(
      grpc::CreateChannel(server.listen_address(), grpc::InsecureChannelCredentials()));
  auto apply = [&](const std::vector<MapChange>& batch) {
    const pathd::v1::UpdateMapRequest request = ToRequest(batch);
    pathd::v1::UpdateMapResponse response;
    grpc::ClientContext context;
    const grpc::Status status = stub->UpdateMap(&context, request, &response);
    return status.ok() ? absl::OkStatus() : absl::InternalError(status.error_message());
  };
  const int32_t size = map.width();
  for (const char* phase : {"idle", "loaded"}) {
    std::unique_ptr<Planners> planners;
    if (std::string(phase) == "loaded") {
      planners = std::make_unique<Planners>(server.store(), planner_count, distance,
                                            absl::GetFlag(FLAGS_seed));
      planners->AwaitWarm(2);
    }
    for (const BatchKind& kind : Kinds()) {
      if (kind.big) continue;
      const Timings t =
          TimeUpdates(kind, absl::GetFlag(FLAGS_updates), size, rng, server.store(), apply);
      PrintRow(phase, std::string("gRPC ") + kind.label, t, 0);
    }
  }
  server.Shutdown();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "update_bench [--size 4096] [--planners 8] [--updates 300] [--grpc=false]\n"
      "Prints map update latency with and without planners running.");
  absl::ParseCommandLine(argc, argv);
  const int32_t size = absl::GetFlag(FLAGS_size);
  const int planner_count = absl::GetFlag(FLAGS_planners);
  const int32_t distance = absl::GetFlag(FLAGS_plan_distance);
  std::mt19937 rng(absl::GetFlag(FLAGS_seed));

  const Grid map = RandomMap(size, rng);
  MapStore store(static_cast<int64_t>(map.size()));
  if (auto created = store.Create(kMap, map, false); !created.ok()) {
    std::fprintf(stderr, "create: %s\n", std::string(created.status().message()).c_str());
    return 1;
  }
  std::printf("%d x %d map, %d planner threads (A*/Dijkstra, goals within %d cells), "
              "%d us between updates; copy/upd = median full copy / median update "
              "in the same phase\n",
              size, size, planner_count, distance, absl::GetFlag(FLAGS_interval_us));
  PrintHeader();
  RunStorePhase("idle", store, size, rng);
  int64_t plans = 0;
  absl::Duration loaded_time;
  {
    Planners planners(store, planner_count, distance, absl::GetFlag(FLAGS_seed));
    planners.AwaitWarm(2);
    const int64_t plans_before = planners.plans();
    const absl::Time start = absl::Now();
    RunStorePhase("loaded", store, size, rng);
    loaded_time = absl::Now() - start;
    plans = planners.plans() - plans_before;
  }
  std::printf("loaded phase: %lld plans finished in %.1f s\n", static_cast<long long>(plans),
              absl::ToDoubleSeconds(loaded_time));
  if (absl::GetFlag(FLAGS_grpc)) {
    std::printf("through UpdateMap on an in-process pathd (its listeners included):\n");
    return RunGrpc(map, planner_count, distance, rng);
  }
  return 0;
}
