// WatchMap: the rectangle cover and the bounded event queue on their own, then
// streams from a real PathdServer on 127.0.0.1:0: a watcher mirrors a map
// exactly while two clients update it, resyncs, replace, delete, a slow
// reader's backlog, shutdown and bad requests. Waits are hang guards only.
#include "server/rpc/watch_map.h"

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "absl/synchronization/mutex.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"

namespace pathd::server {
namespace {

using ::testing::ElementsAre;

// ---- CoverCells ----

std::vector<Cell> RowMajor(std::set<std::pair<int, int>> yx) {
  std::vector<Cell> cells;
  for (const auto& [y, x] : yx) cells.push_back(Cell{x, y});
  return cells;
}

TEST(CoverCellsTest, MergesRunsWithTheSameColumnsInConsecutiveRows) {
  EXPECT_TRUE(CoverCells({}).empty());
  EXPECT_THAT(CoverCells(RowMajor({{2, 3}})),
              ElementsAre(CellRectangle{3, 2, 3, 2}));
  // A 3x2 block is one rectangle.
  EXPECT_THAT(
      CoverCells(RowMajor({{1, 4}, {1, 5}, {1, 6}, {2, 4}, {2, 5}, {2, 6}})),
      ElementsAre(CellRectangle{4, 1, 6, 2}));
  // An L: the longer bottom run does not merge with the stem.
  EXPECT_THAT(
      CoverCells(RowMajor({{0, 0}, {1, 0}, {2, 0}, {2, 1}, {2, 2}})),
      ElementsAre(CellRectangle{0, 0, 0, 1}, CellRectangle{0, 2, 2, 2}));
  // Same columns but a row apart: two rectangles.
  EXPECT_THAT(
      CoverCells(RowMajor({{0, 5}, {2, 5}})),
      ElementsAre(CellRectangle{5, 0, 5, 0}, CellRectangle{5, 2, 5, 2}));
  // Two columns side by side over two rows, with a gap between them.
  EXPECT_THAT(
      CoverCells(RowMajor({{0, 0}, {0, 2}, {1, 0}, {1, 2}})),
      ElementsAre(CellRectangle{0, 0, 0, 1}, CellRectangle{2, 0, 2, 1}));
}

TEST(CoverCellsTest, RandomSetsAreCoveredExactlyByDisjointSortedRectangles) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 20),
              h = 1 + static_cast<int>(rng() % 20);
    const double density = (rng() % 100) / 100.0;
    std::set<std::pair<int, int>> yx;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (std::uniform_real_distribution<double>(0, 1)(rng) < density)
          yx.insert({y, x});
      }
    }
    const std::vector<CellRectangle> rects = CoverCells(RowMajor(yx));
    std::multiset<std::pair<int, int>> covered;
    for (size_t i = 0; i < rects.size(); ++i) {
      const CellRectangle& r = rects[i];
      ASSERT_LE(r.x_min, r.x_max);
      ASSERT_LE(r.y_min, r.y_max);
      if (i > 0) {
        const CellRectangle& p = rects[i - 1];
        EXPECT_TRUE(p.y_min < r.y_min ||
                    (p.y_min == r.y_min && p.x_min < r.x_min));
      }
      for (int y = r.y_min; y <= r.y_max; ++y) {
        for (int x = r.x_min; x <= r.x_max; ++x) covered.insert({y, x});
      }
    }
    // Equal as multisets: every cell covered, once, and nothing else.
    const std::multiset<std::pair<int, int>> expected(yx.begin(), yx.end());
    EXPECT_EQ(covered, expected) << "trial " << trial;
  }
}

// ---- MapEventQueue ----

std::shared_ptr<const MapSnapshot> Version(uint64_t map_id, uint64_t version,
                                           int width, int height, uint8_t fill,
                                           std::vector<Cell> changed = {},
                                           bool known = true) {
  auto snapshot = std::make_shared<MapSnapshot>();
  snapshot->name = "m";
  snapshot->map_id = map_id;
  snapshot->version = version;
  Grid grid = *Grid::Create(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) grid.set_cost(x, y, fill);
  }
  snapshot->grid = std::make_shared<const Grid>(std::move(grid));
  snapshot->changed_cells = std::move(changed);
  snapshot->changes_known = known;
  return snapshot;
}

void OfferVersion(MapEventQueue& queue, std::shared_ptr<const MapSnapshot> s) {
  queue.Offer(s, MakeUpdatedEvent(*s));
}

TEST(MapEventQueueTest, InOrderVersionsBecomeUpdatedEventsWithTheirCosts) {
  MapEventQueue queue(8, *Version(1, 1, 4, 3, 0));
  OfferVersion(queue, Version(1, 2, 4, 3, 9, {{1, 0}, {2, 0}, {1, 1}, {2, 1}}));
  OfferVersion(queue, Version(1, 3, 4, 3, 9, {}));
  ASSERT_EQ(queue.size(), 2u);
  const auto first = queue.Pop();
  EXPECT_EQ(first->kind(), v1::MAP_EVENT_KIND_UPDATED);
  EXPECT_EQ(first->version(), 2u);
  ASSERT_EQ(first->changes_size(), 1);
  EXPECT_EQ(first->changes(0).rect().x_min(), 1);
  EXPECT_EQ(first->changes(0).rect().y_max(), 1);
  EXPECT_EQ(first->changes(0).costs(), std::string(4, '\x09'));
  const auto second = queue.Pop();
  EXPECT_EQ(second->version(), 3u);
  EXPECT_EQ(second->changes_size(), 0);
  EXPECT_EQ(queue.backlog_drops(), 0);
}

TEST(MapEventQueueTest, GapsUntrackedChangesAndNewMapsSendTheWholeMap) {
  MapEventQueue queue(8, *Version(1, 1, 4, 3, 0));
  // Version 2 never offered: 3's changes cannot apply to the client's copy.
  OfferVersion(queue, Version(1, 3, 4, 3, 5, {{0, 0}}));
  // An older version arriving late is already covered.
  OfferVersion(queue, Version(1, 2, 4, 3, 5, {{0, 0}}));
  OfferVersion(queue, Version(1, 4, 4, 3, 6, {}, /*known=*/false));
  OfferVersion(queue, Version(2, 5, 2, 2, 7));
  queue.PushDeleted();
  ASSERT_EQ(queue.size(), 4u);
  const auto resync = queue.Pop();
  EXPECT_EQ(resync->kind(), v1::MAP_EVENT_KIND_RESYNC);
  EXPECT_EQ(resync->version(), 3u);
  EXPECT_EQ(resync->cells(), std::string(12, '\x05'));
  EXPECT_EQ(resync->info().width(), 4);
  EXPECT_EQ(queue.Pop()->kind(), v1::MAP_EVENT_KIND_RESYNC);
  const auto replaced = queue.Pop();
  EXPECT_EQ(replaced->kind(), v1::MAP_EVENT_KIND_REPLACED);
  EXPECT_EQ(replaced->info().width(), 2);
  EXPECT_EQ(replaced->cells(), std::string(4, '\x07'));
  const auto deleted = queue.Pop();
  EXPECT_EQ(deleted->kind(), v1::MAP_EVENT_KIND_DELETED);
  EXPECT_EQ(deleted->version(), 5u);
}

TEST(MapEventQueueTest, BacklogOverTheBoundBecomesOneResyncOfTheNewest) {
  MapEventQueue queue(3, *Version(1, 1, 4, 3, 0));
  for (uint64_t v = 2; v <= 10; ++v) {
    OfferVersion(queue, Version(1, v, 4, 3, static_cast<uint8_t>(v), {{0, 0}}));
    EXPECT_LE(queue.size(), 3u);
  }
  // 2, 3, 4 queued; 5 dropped them for a RESYNC of 5; 6, 7 follow; 8 drops
  // again; 9, 10 follow.
  EXPECT_EQ(queue.backlog_drops(), 2);
  const auto resync = queue.Pop();
  EXPECT_EQ(resync->kind(), v1::MAP_EVENT_KIND_RESYNC);
  EXPECT_EQ(resync->version(), 8u);
  EXPECT_EQ(resync->cells(), std::string(12, '\x08'));
  EXPECT_EQ(queue.Pop()->version(), 9u);
  EXPECT_EQ(queue.Pop()->version(), 10u);
  EXPECT_TRUE(queue.empty());
}

// --watch_backlog_bytes (issue 15): the bytes of queued events are bounded
// by the flag when set, not only by the map's size.
TEST(MapEventQueueTest, BacklogBytesBoundSetByTheFlag) {
  std::vector<Cell> row;
  for (int x = 0; x < 100; ++x) row.push_back(Cell{x, 0});
  MapEventQueue bounded(1000, *Version(1, 1, 100, 100, 0), /*max_bytes=*/1000);
  MapEventQueue by_map_size(1000, *Version(1, 1, 100, 100, 0));
  for (uint64_t v = 2; v <= 21; ++v) {
    const auto version = Version(1, v, 100, 100, static_cast<uint8_t>(v), row);
    OfferVersion(bounded, version);
    OfferVersion(by_map_size, version);
  }
  // 20 one-row events (~130 bytes each) fit in the map-sized default bound
  // (64 KiB at least) but not in 1000 bytes.
  EXPECT_EQ(by_map_size.backlog_drops(), 0);
  EXPECT_EQ(by_map_size.size(), 20u);
  EXPECT_GE(bounded.backlog_drops(), 1);
  EXPECT_LT(bounded.size(), 10u);
  EXPECT_EQ(bounded.Pop()->kind(), v1::MAP_EVENT_KIND_RESYNC);
}

// ---- WatchMap over gRPC ----

// The map as a client mirrors it from events alone.
struct Mirror {
  int width = 0;
  int height = 0;
  uint64_t version = 0;
  std::string cells;
  bool deleted = false;

  // Applies `event`; false (with a test failure) when it cannot apply.
  bool Apply(const v1::MapEvent& event) {
    // Versions only grow; DELETED repeats the last one delivered.
    if (event.kind() == v1::MAP_EVENT_KIND_DELETED) {
      EXPECT_EQ(event.version(), version);
    } else {
      EXPECT_GT(event.version(), version);
    }
    switch (event.kind()) {
      case v1::MAP_EVENT_KIND_RESYNC:
      case v1::MAP_EVENT_KIND_REPLACED:
        width = event.info().width();
        height = event.info().height();
        cells = event.cells();
        EXPECT_EQ(cells.size(), static_cast<size_t>(width) * height);
        break;
      case v1::MAP_EVENT_KIND_UPDATED:
        // Changes apply only to the version right before.
        EXPECT_EQ(event.version(), version + 1);
        if (event.version() != version + 1) return false;
        for (const v1::ChangedRect& change : event.changes()) {
          const v1::CellRect& r = change.rect();
          size_t i = 0;
          EXPECT_EQ(change.costs().size(),
                    static_cast<size_t>(r.x_max() - r.x_min() + 1) *
                        (r.y_max() - r.y_min() + 1));
          for (int y = r.y_min(); y <= r.y_max(); ++y) {
            for (int x = r.x_min(); x <= r.x_max(); ++x) {
              cells[static_cast<size_t>(y) * width + x] = change.costs()[i++];
            }
          }
        }
        break;
      case v1::MAP_EVENT_KIND_DELETED:
        deleted = true;
        break;
      default:
        ADD_FAILURE() << "unexpected kind " << event.kind();
        return false;
    }
    version = event.version();
    return true;
  }
};

class Watch {
 public:
  Watch(v1::MapService::Stub& stub, const std::string& name,
        uint64_t from_version) {
    context_.set_deadline(std::chrono::system_clock::now() +
                          std::chrono::seconds(120));
    v1::WatchMapRequest request;
    request.set_name(name);
    request.set_from_version(from_version);
    reader_ = stub.WatchMap(&context_, request);
  }

  std::optional<v1::MapEvent> Next() {
    v1::MapEvent event;
    if (!reader_->Read(&event)) return std::nullopt;
    return event;
  }

  grpc::Status Finish() { return reader_->Finish(); }
  void Cancel() { context_.TryCancel(); }

 private:
  grpc::ClientContext context_;
  std::unique_ptr<grpc::ClientReader<v1::MapEvent>> reader_;
};

class WatchMapTest : public ::testing::Test {
 protected:
  void StartServer(ServerOptions options = {}) {
    options.threads = 2;
    server_ = std::make_unique<testing::InProcessServer>(options);
    // Every version of every map, to check each event against the two
    // versions it lies between.
    server_->KeepMapVersions();
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(-1);
    ASSERT_TRUE(server_->Start(args).ok());
    maps_ = &server_->maps();
  }

  void TearDown() override {
    if (server_ != nullptr) server_->Shutdown();
  }

  void AddMap(const std::string& name, int width, int height, uint32_t seed) {
    Grid grid = *Grid::Create(width, height);
    std::mt19937 rng(seed);
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x)
        grid.set_cost(x, y, static_cast<uint8_t>(rng() % 4));
    }
    auto created = server_->store().Create(name, std::move(grid), false);
    ASSERT_TRUE(created.ok()) << created.status();
    server_->KeepMapVersion(name, *created);
  }

  // A Watch's call reaches the server asynchronously; a test that changes
  // the map right after opening one waits until the server has registered it
  // (else it would start from the changed version). The bound is a hang guard.
  void AwaitWatchers(int64_t count) {
    for (int i = 0; i < 3000 && server_->map_watchers().count() < count; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_EQ(server_->map_watchers().count(), count);
  }

  std::shared_ptr<const Grid> StoredVersion(const std::string& name,
                                            uint64_t version) {
    return server_->MapVersion(name, version);
  }

  grpc::Status Update(const v1::UpdateMapRequest& request,
                      v1::UpdateMapResponse* out) {
    grpc::ClientContext context;
    return maps_->UpdateMap(&context, request, out);
  }

  uint64_t UpdateRect(const std::string& name, int x0, int y0, int x1, int y1,
                      uint32_t cost) {
    v1::UpdateMapRequest request;
    request.set_name(name);
    v1::CellChange* change = request.add_changes();
    change->mutable_rect()->set_x_min(x0);
    change->mutable_rect()->set_y_min(y0);
    change->mutable_rect()->set_x_max(x1);
    change->mutable_rect()->set_y_max(y1);
    change->set_cost(cost);
    v1::UpdateMapResponse response;
    const grpc::Status status = Update(request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response.version();
  }

  v1::GetMapResponse Get(const std::string& name) {
    v1::GetMapRequest request;
    request.set_name(name);
    request.set_include_cells(true);
    v1::GetMapResponse response;
    grpc::ClientContext context;
    const grpc::Status status = maps_->GetMap(&context, request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response;
  }

  // Checks an UPDATED event's rectangles cover exactly the cells that differ
  // between the two stored versions and carry the new costs.
  void ExpectExactChanges(const std::string& name, const v1::MapEvent& event) {
    auto before = StoredVersion(name, event.version() - 1);
    auto after = StoredVersion(name, event.version());
    ASSERT_NE(before, nullptr);
    ASSERT_NE(after, nullptr);
    std::set<std::pair<int, int>> covered;
    for (const v1::ChangedRect& change : event.changes()) {
      const v1::CellRect& r = change.rect();
      size_t i = 0;
      for (int y = r.y_min(); y <= r.y_max(); ++y) {
        for (int x = r.x_min(); x <= r.x_max(); ++x) {
          EXPECT_TRUE(covered.insert({x, y}).second) << "covered twice";
          EXPECT_EQ(static_cast<uint8_t>(change.costs()[i++]),
                    after->cost(x, y));
        }
      }
    }
    for (int y = 0; y < after->height(); ++y) {
      for (int x = 0; x < after->width(); ++x) {
        EXPECT_EQ(covered.count({x, y}) == 1,
                  before->cost(x, y) != after->cost(x, y))
            << "cell (" << x << "," << y << ") of version " << event.version();
      }
    }
  }

  std::unique_ptr<testing::InProcessServer> server_;
  v1::MapService::Stub* maps_ = nullptr;
};

TEST_F(WatchMapTest, MirrorsEveryVersionWhileTwoClientsUpdate) {
  ServerOptions options;
  // Room for every event, so none may be dropped and each version must
  // arrive as its own UPDATED event.
  options.watch_queue_events = 100000;
  StartServer(options);
  constexpr int kWidth = 64, kHeight = 48, kUpdatesPerWriter = 150;
  AddMap("yard", kWidth, kHeight, 1);
  Watch watch(*maps_, "yard", 0);

  std::vector<std::thread> writers;
  for (int w = 0; w < 2; ++w) {
    writers.emplace_back([this, w] {
      std::mt19937 rng(100 + w);
      for (int i = 0; i < kUpdatesPerWriter; ++i) {
        v1::UpdateMapRequest request;
        request.set_name("yard");
        const int changes = 1 + static_cast<int>(rng() % 4);
        for (int c = 0; c < changes; ++c) {
          v1::CellChange* change = request.add_changes();
          const int x0 = static_cast<int>(rng() % kWidth),
                    y0 = static_cast<int>(rng() % kHeight);
          if (rng() % 2 == 0) {
            change->mutable_cell()->set_x(x0);
            change->mutable_cell()->set_y(y0);
          } else {
            change->mutable_rect()->set_x_min(x0);
            change->mutable_rect()->set_y_min(y0);
            change->mutable_rect()->set_x_max(
                std::min(kWidth - 1, x0 + static_cast<int>(rng() % 6)));
            change->mutable_rect()->set_y_max(
                std::min(kHeight - 1, y0 + static_cast<int>(rng() % 6)));
          }
          change->set_cost(static_cast<uint32_t>(rng() % 256));
        }
        v1::UpdateMapResponse response;
        const grpc::Status status = Update(request, &response);
        EXPECT_TRUE(status.ok()) << status.error_message();
      }
    });
  }
  for (std::thread& t : writers) t.join();
  constexpr uint64_t kFinal = 1 + 2 * kUpdatesPerWriter;

  Mirror mirror;
  std::vector<uint64_t> seen;
  while (mirror.version < kFinal) {
    std::optional<v1::MapEvent> event = watch.Next();
    ASSERT_TRUE(event.has_value())
        << "stream ended at version " << mirror.version;
    if (seen.empty()) {
      EXPECT_EQ(event->kind(), v1::MAP_EVENT_KIND_RESYNC);
    } else {
      ASSERT_EQ(event->kind(), v1::MAP_EVENT_KIND_UPDATED);
      ExpectExactChanges("yard", *event);
    }
    ASSERT_TRUE(mirror.Apply(*event));
    seen.push_back(event->version());
  }
  // The first event is the version current when the watch started; after it
  // every version exactly once, in order.
  for (size_t i = 1; i < seen.size(); ++i) EXPECT_EQ(seen[i], seen[i - 1] + 1);
  EXPECT_EQ(seen.back(), kFinal);
  const v1::GetMapResponse stored = Get("yard");
  EXPECT_EQ(stored.info().version(), kFinal);
  EXPECT_EQ(mirror.cells, stored.cells());
  EXPECT_EQ(server_->map_watchers().backlog_drops(), 0);
  watch.Cancel();
  EXPECT_EQ(watch.Finish().error_code(), grpc::StatusCode::CANCELLED);
}

TEST_F(WatchMapTest, FromVersionDecidesWhetherTheStreamStartsWithAResync) {
  StartServer();
  // Large enough that the store tracks a 9-cell change (it lists up to 1/8
  // of a map's cells).
  AddMap("lot", 20, 10, 2);
  UpdateRect("lot", 0, 0, 1, 1, 254);
  UpdateRect("lot", 2, 2, 2, 2, 254);  // version 3

  // An older copy cannot be patched: the whole current map comes first.
  Watch old_copy(*maps_, "lot", 2);
  std::optional<v1::MapEvent> first = old_copy.Next();
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->kind(), v1::MAP_EVENT_KIND_RESYNC);
  EXPECT_EQ(first->version(), 3u);
  EXPECT_EQ(first->info().name(), "lot");
  EXPECT_EQ(first->cells(), Get("lot").cells());

  // A current copy gets only what changes next.
  Watch current(*maps_, "lot", 3);
  ASSERT_NO_FATAL_FAILURE(AwaitWatchers(2));
  UpdateRect("lot", 5, 1, 7, 3, 200);
  for (Watch* watch : {&old_copy, &current}) {
    SCOPED_TRACE(watch == &current ? "from the current version"
                                   : "from an old one");
    std::optional<v1::MapEvent> next = watch->Next();
    ASSERT_TRUE(next.has_value());
    EXPECT_EQ(next->kind(), v1::MAP_EVENT_KIND_UPDATED);
    EXPECT_EQ(next->version(), 4u);
    ASSERT_EQ(next->changes_size(), 1);
    EXPECT_EQ(next->changes(0).rect().x_min(), 5);
    EXPECT_EQ(next->changes(0).rect().y_max(), 3);
    EXPECT_EQ(next->changes(0).costs(), std::string(9, '\xc8'));
  }
}

TEST_F(WatchMapTest, ReplaceSendsTheNewMapAndDeleteEndsTheStream) {
  StartServer();
  AddMap("hall", 8, 8, 3);
  Watch watch(*maps_, "hall", 1);
  ASSERT_NO_FATAL_FAILURE(AwaitWatchers(1));
  Grid bigger = *Grid::Create(12, 5);
  bigger.set_cost(11, 4, 254);
  ASSERT_TRUE(server_->store().Create("hall", std::move(bigger), true).ok());
  std::optional<v1::MapEvent> replaced = watch.Next();
  ASSERT_TRUE(replaced.has_value());
  EXPECT_EQ(replaced->kind(), v1::MAP_EVENT_KIND_REPLACED);
  EXPECT_EQ(replaced->version(), 2u);
  EXPECT_EQ(replaced->info().width(), 12);
  EXPECT_EQ(replaced->cells().size(), 60u);
  EXPECT_EQ(static_cast<uint8_t>(replaced->cells()[59]), 254);

  grpc::ClientContext context;
  v1::DeleteMapRequest request;
  request.set_name("hall");
  v1::DeleteMapResponse response;
  ASSERT_TRUE(maps_->DeleteMap(&context, request, &response).ok());
  std::optional<v1::MapEvent> deleted = watch.Next();
  ASSERT_TRUE(deleted.has_value());
  EXPECT_EQ(deleted->kind(), v1::MAP_EVENT_KIND_DELETED);
  EXPECT_EQ(deleted->version(), 2u);
  EXPECT_FALSE(watch.Next().has_value());
  EXPECT_TRUE(watch.Finish().ok());
  // gRPC runs the reactor's OnDone (which unregisters) just after the status
  // goes out; the bound is a hang guard.
  for (int i = 0; i < 1000 && server_->map_watchers().count() > 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(server_->map_watchers().count(), 0);
}

TEST_F(WatchMapTest, SlowReaderGetsAResyncInsteadOfAnUnboundedBacklog) {
  ServerOptions options;
  options.watch_queue_events = 4;
  StartServer(options);
  constexpr int kSide = 512;
  AddMap("field", kSide, kSide, 4);
  Watch watch(*maps_, "field", 1);
  // Nothing is read until the server has dropped a backlog. Each update
  // changes a 128 x 256 block (32 KiB of event), so transport buffers fill
  // and events queue up; the bound on updates is a hang guard.
  int updates = 0;
  while (server_->map_watchers().backlog_drops() == 0 && updates < 5000) {
    UpdateRect("field", 0, 0, 127, 255, updates % 2 == 0 ? 254 : 0);
    ++updates;
  }
  ASSERT_GT(server_->map_watchers().backlog_drops(), 0)
      << "no backlog dropped after " << updates << " updates";
  UpdateRect("field", 300, 300, 300, 300, 77);
  const uint64_t final_version = 1 + static_cast<uint64_t>(updates) + 1;

  Mirror mirror;
  mirror.version = 1;
  mirror.width = mirror.height = kSide;
  const std::vector<uint8_t>& first = StoredVersion("field", 1)->cells();
  mirror.cells.assign(first.begin(), first.end());
  int events = 0;
  bool resynced = false;
  while (mirror.version < final_version) {
    std::optional<v1::MapEvent> event = watch.Next();
    ASSERT_TRUE(event.has_value())
        << "stream ended at version " << mirror.version;
    resynced |= event->kind() == v1::MAP_EVENT_KIND_RESYNC;
    ASSERT_TRUE(mirror.Apply(*event));
    ++events;
  }
  EXPECT_TRUE(resynced);
  EXPECT_LT(events, updates + 1);
  EXPECT_EQ(mirror.cells, Get("field").cells());
}

TEST_F(WatchMapTest, ShutdownEndsOpenStreamsWithUnavailable) {
  StartServer();
  AddMap("dock", 4, 4, 5);
  Watch watch(*maps_, "dock", 1);
  UpdateRect("dock", 0, 0, 0, 0, 254);
  ASSERT_TRUE(watch.Next().has_value());  // the stream is open server-side
  server_->Shutdown();
  EXPECT_FALSE(watch.Next().has_value());
  EXPECT_EQ(watch.Finish().error_code(), grpc::StatusCode::UNAVAILABLE);
}

TEST_F(WatchMapTest, UnknownMapAndBadNameAreRefused) {
  StartServer();
  Watch unknown(*maps_, "nowhere", 0);
  EXPECT_FALSE(unknown.Next().has_value());
  const grpc::Status not_found = unknown.Finish();
  EXPECT_EQ(not_found.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(not_found.error_message(), ::testing::HasSubstr("nowhere"));
  Watch bad(*maps_, "../etc", 0);
  EXPECT_FALSE(bad.Next().has_value());
  EXPECT_EQ(bad.Finish().error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

}  // namespace
}  // namespace pathd::server
