// Huge maps through the real pathd (issue 19): a 16384 x 16384 map (268 M
// cells) is streamed in (UploadMap), updated, planned on with A*, streamed
// back (DownloadMap, compared by checksum with the client's copy) and
// deleted, while the daemon's memory is read from /proc/PID/status: its
// peak (VmHWM) stays under a stated bound and its RSS falls back after the
// delete. And a streamed map is as durable as a created one: acknowledged,
// it survives a restart on --data_dir.
//
// The bounds are stated in map sizes, not measured figures, so they hold on
// any machine: the peak may hold the streamed grid, the copy an update makes
// (the store keeps the old version's buffer as a spare), A*'s scratch pages
// for the region it searched and the daemon's baseline, with half a map to
// spare; a leak of one more grid, or scratch of 24 bytes per map cell,
// cannot meet it. Waits are hang guards, never timed assertions.
//
// Under AddressSanitizer (make test-asan) the map is 4096 x 4096 and the
// RSS bounds are not checked: ASan's shadow memory and quarantine change
// what RSS means, and a 268 MB map under ASan costs minutes, not seconds.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "client/client.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/e2e/process.h"
#include "tests/testing/pathd_process.h"
#include "tests/testing/requests.h"

namespace pathd {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kCheckRss = false;
constexpr int32_t kSide = 4096;
#else
constexpr bool kCheckRss = true;
constexpr int32_t kSide = 16384;
#endif
constexpr int64_t kMapBytes = int64_t{kSide} * kSide;
constexpr uint8_t kLethal = 254;
// Walls run down every kWallPeriod columns at x = k * kWallPeriod + kWallX,
// open only in rows kGapY0..kGapY1 of every kGapPeriod rows.
constexpr int32_t kWallPeriod = 1024;
constexpr int32_t kWallX = 512;
constexpr int32_t kGapPeriod = 2048;
constexpr int32_t kGapY0 = 1000;
constexpr int32_t kGapY1 = 1047;
// The update closes the upper half of the first gap.
constexpr int32_t kClosedY1 = 1023;

// A field of /proc/PID/status ("VmRSS", "VmHWM") in bytes; 0 when unreadable.
int64_t StatusBytes(pid_t pid, std::string_view field) {
  std::istringstream status(
      e2e::ReadFile(absl::StrCat("/proc/", pid, "/status")));
  const std::string prefix = std::string(field) + ":";
  for (std::string line; std::getline(status, line);) {
    absl::string_view rest = line;
    if (!absl::ConsumePrefix(&rest, prefix)) continue;
    rest = absl::StripAsciiWhitespace(rest);
    absl::ConsumeSuffix(&rest, " kB");
    int64_t kb = 0;
    if (absl::SimpleAtoi(rest, &kb)) return kb * 1024;
  }
  return 0;
}

std::string MiB(int64_t bytes) {
  return absl::StrCat(bytes / (1024 * 1024), " MiB");
}

uint64_t Fnv1a(std::string_view bytes) {
  uint64_t hash = 14695981039346656037ull;
  for (const char c : bytes) {
    hash ^= static_cast<uint8_t>(c);
    hash *= 1099511628211ull;
  }
  return hash;
}

std::string MakeCells() {
  std::string cells(static_cast<size_t>(kMapBytes), '\0');
  for (int32_t y = 0; y < kSide; ++y) {
    const int32_t in_period = y % kGapPeriod;
    if (in_period >= kGapY0 && in_period <= kGapY1) continue;
    for (int32_t x = kWallX; x < kSide; x += kWallPeriod) {
      cells[static_cast<size_t>(y) * kSide + x] = static_cast<char>(kLethal);
    }
  }
  return cells;
}

class HugeMapTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char dir_template[] = "/tmp/pathd_huge_XXXXXX";
    ASSERT_NE(mkdtemp(dir_template), nullptr);
    dir_ = dir_template;
  }
  void TearDown() override {
    daemon_.reset();
    fs::remove_all(dir_);
  }

  void Start(std::vector<std::string> flags) {
    daemon_.reset();
    testing::PathdProcessOptions options;
    options.binary = PATHD_BIN;
    options.flags = {"--threads=2", "--log_level=warn"};
    options.flags.insert(options.flags.end(), flags.begin(), flags.end());
    options.log_file = dir_ / "pathd.log";
    daemon_ = std::make_unique<testing::PathdProcess>(std::move(options));
    ASSERT_TRUE(daemon_->listening()) << daemon_->status();
    // A generous per-call timeout: the transfers add their own per-byte
    // allowance; this only keeps a broken daemon from hanging the test.
    client_ = std::make_unique<client::PathdClient>(daemon_->address(),
                                                    absl::Seconds(60));
  }

  int64_t Rss() const { return StatusBytes(daemon_->pid(), "VmRSS"); }
  int64_t Peak() const { return StatusBytes(daemon_->pid(), "VmHWM"); }

  fs::path dir_;
  std::unique_ptr<testing::PathdProcess> daemon_;
  std::unique_ptr<client::PathdClient> client_;
};

// Checks that `path` is a chain of 8-neighbour moves over cells of `cells`
// that are not lethal, from start to goal.
void ExpectValidPath(const v1::PlanResponse& plan, const std::string& cells,
                     int32_t sx, int32_t sy, int32_t gx, int32_t gy) {
  ASSERT_TRUE(plan.found()) << plan.ShortDebugString().substr(0, 300);
  ASSERT_GE(plan.path_size(), 2);
  EXPECT_EQ(plan.path(0).x(), sx);
  EXPECT_EQ(plan.path(0).y(), sy);
  EXPECT_EQ(plan.path(plan.path_size() - 1).x(), gx);
  EXPECT_EQ(plan.path(plan.path_size() - 1).y(), gy);
  for (int i = 0; i < plan.path_size(); ++i) {
    const v1::Cell& c = plan.path(i);
    ASSERT_TRUE(c.x() >= 0 && c.y() >= 0 && c.x() < kSide && c.y() < kSide);
    ASSERT_NE(
        static_cast<uint8_t>(cells[static_cast<size_t>(c.y()) * kSide + c.x()]),
        kLethal)
        << "path cell " << i << " (" << c.x() << ", " << c.y() << ") is lethal";
    if (i > 0) {
      const v1::Cell& p = plan.path(i - 1);
      ASSERT_LE(std::abs(c.x() - p.x()), 1);
      ASSERT_LE(std::abs(c.y() - p.y()), 1);
    }
  }
}

TEST_F(HugeMapTest, CreatedUpdatedPlannedDownloadedAndDeletedInBoundedMemory) {
  // Default flags: the defaults must serve a 16384 x 16384 map.
  ASSERT_NO_FATAL_FAILURE(Start({}));
  const int64_t baseline = Rss();
  ASSERT_GT(baseline, 0);
  // The peak may hold two grids (the streamed one and an update's copy)
  // and half a map for the rest: A*'s scratch for the part of the map it
  // searched (25 MiB measured), bands, the open list, gRPC's buffers. A
  // third grid (a leak, or a copy per band) cannot fit, nor can A*'s old
  // 24 bytes of scratch per map cell.
  const int64_t peak_bound = baseline + 2 * kMapBytes + kMapBytes / 2;
  std::cout << "side " << kSide << ", map " << MiB(kMapBytes)
            << ", baseline RSS " << MiB(baseline) << ", peak bound "
            << MiB(peak_bound) << std::endl;

  std::string cells = MakeCells();
  v1::UploadMapHeader header;
  header.set_name("huge");
  header.set_width(kSide);
  header.set_height(kSide);
  header.set_resolution(0.05);
  absl::Time start = absl::Now();
  absl::StatusOr<v1::CreateMapResponse> created =
      client_->UploadMap(header, cells);
  ASSERT_TRUE(created.ok()) << created.status();
  std::cout << "UploadMap: " << absl::ToDoubleSeconds(absl::Now() - start)
            << " s, RSS " << MiB(Rss()) << std::endl;
  EXPECT_EQ(created->info().width(), kSide);
  EXPECT_EQ(created->info().height(), kSide);
  EXPECT_EQ(created->info().version(), 1u);
  int64_t walls = 0;
  for (const char c : cells) walls += static_cast<uint8_t>(c) == kLethal;
  EXPECT_EQ(created->info().blocked_cells(), walls);

  // One message cannot carry it: GetMap with cells says so and names the
  // stream.
  v1::GetMapRequest get;
  get.set_name("huge");
  get.set_include_cells(true);
  absl::StatusOr<v1::GetMapResponse> unary = client_->GetMap(get);
  if (kCheckRss) {
    ASSERT_FALSE(unary.ok());
    EXPECT_THAT(unary.status().message(), HasSubstr("DownloadMap"));
  }

  // Close the upper half of the first gap in the first wall.
  v1::UpdateMapRequest update;
  update.set_name("huge");
  v1::CellChange* change = update.add_changes();
  change->mutable_rect()->set_x_min(kWallX);
  change->mutable_rect()->set_x_max(kWallX);
  change->mutable_rect()->set_y_min(kGapY0);
  change->mutable_rect()->set_y_max(kClosedY1);
  change->set_cost(kLethal);
  absl::StatusOr<v1::UpdateMapResponse> updated = client_->UpdateMap(update);
  ASSERT_TRUE(updated.ok()) << updated.status();
  EXPECT_EQ(updated->version(), 2u);
  EXPECT_EQ(updated->cells_changed(), kClosedY1 - kGapY0 + 1);
  for (int32_t y = kGapY0; y <= kClosedY1; ++y) {
    cells[static_cast<size_t>(y) * kSide + kWallX] = static_cast<char>(kLethal);
  }

  // A* through the remaining gap: its scratch holds records only for the
  // pages it writes, not 24 bytes for each of the 268 M cells.
  start = absl::Now();
  v1::PlanRequest request = testing::PlanBetween("huge", 10, 10, 900, 300);
  absl::StatusOr<v1::PlanResponse> plan = client_->Plan(request);
  ASSERT_TRUE(plan.ok()) << plan.status();
  std::cout << "Plan (astar): " << absl::ToDoubleSeconds(absl::Now() - start)
            << " s, " << plan->path_size() << " cells, RSS " << MiB(Rss())
            << std::endl;
  EXPECT_EQ(plan->map_version(), 2u);
  ExpectValidPath(*plan, cells, 10, 10, 900, 300);
  bool through_open_half = false;
  for (const v1::Cell& c : plan->path()) {
    if (c.x() == kWallX)
      through_open_half = c.y() > kClosedY1 && c.y() <= kGapY1;
  }
  EXPECT_TRUE(through_open_half)
      << "the path must cross the wall below the closed rows";

  start = absl::Now();
  absl::StatusOr<v1::GetMapResponse> downloaded = client_->DownloadMap("huge");
  ASSERT_TRUE(downloaded.ok()) << downloaded.status();
  std::cout << "DownloadMap: " << absl::ToDoubleSeconds(absl::Now() - start)
            << " s, RSS " << MiB(Rss()) << std::endl;
  EXPECT_EQ(downloaded->info().version(), 2u);
  ASSERT_EQ(downloaded->cells().size(), cells.size());
  EXPECT_EQ(Fnv1a(downloaded->cells()), Fnv1a(cells));
  downloaded->clear_cells();

  const int64_t peak = Peak();
  std::cout << "peak (VmHWM) " << MiB(peak) << std::endl;
  if (kCheckRss) {
    EXPECT_LE(peak, peak_bound)
        << "VmHWM " << MiB(peak) << " over the bound " << MiB(peak_bound);
  }

  ASSERT_TRUE(client_->DeleteMap("huge").ok());
  // Every grid buffer is one allocation far above glibc's mmap threshold,
  // so it goes back to the kernel when its last snapshot does. Polled: the
  // last references (a stream's snapshot) go when their calls have ended.
  const int64_t after_bound = baseline + kMapBytes / 4;
  int64_t after = Rss();
  for (const absl::Time guard = absl::Now() + absl::Seconds(60);
       kCheckRss && after > after_bound && absl::Now() < guard; after = Rss()) {
    absl::SleepFor(absl::Milliseconds(100));
  }
  std::cout << "RSS after DeleteMap " << MiB(after) << std::endl;
  if (kCheckRss) {
    EXPECT_LE(after, after_bound)
        << "RSS " << MiB(after) << " after the delete, over "
        << MiB(after_bound);
  }
  EXPECT_EQ(daemon_->Stop(), 0);
}

// A streamed map is acknowledged only once it is durable, like CreateMap:
// it is there after a restart on the same --data_dir, cell for cell; an
// upload that ended early left nothing behind.
TEST_F(HugeMapTest, StreamedMapSurvivesRestart) {
  const std::string data_dir = (dir_ / "data").string();
  ASSERT_NO_FATAL_FAILURE(Start({"--data_dir=" + data_dir}));
  constexpr int32_t kW = 700, kH = 300;
  std::string cells(size_t{kW} * kH, '\0');
  for (size_t i = 0; i < cells.size(); i += 7)
    cells[i] = static_cast<char>(i % 256);
  v1::UploadMapHeader header;
  header.set_name("streamed");
  header.set_width(kW);
  header.set_height(kH);
  header.set_resolution(0.1);
  header.mutable_origin()->set_x(-2.5);
  // Bands of 4 rows: 75 messages.
  absl::StatusOr<v1::CreateMapResponse> created =
      client_->UploadMap(header, cells, 4 * kW);
  ASSERT_TRUE(created.ok()) << created.status();
  // Too few cells: the server refuses it at the end and creates nothing.
  header.set_name("short");
  absl::StatusOr<v1::CreateMapResponse> short_upload = client_->UploadMap(
      header, std::string_view(cells).substr(0, cells.size() - kW), 4 * kW);
  ASSERT_FALSE(short_upload.ok());
  EXPECT_THAT(
      short_upload.status().message(),
      HasSubstr(
          "ended after 299 of header.height 300 rows; nothing was created"));

  // SIGKILL: nothing gets flushed at exit.
  daemon_->Kill();
  ASSERT_NO_FATAL_FAILURE(Start({"--data_dir=" + data_dir}));
  absl::StatusOr<v1::GetMapResponse> back = client_->DownloadMap("streamed");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->info().width(), kW);
  EXPECT_EQ(back->info().resolution(), 0.1);
  EXPECT_EQ(back->info().origin().x(), -2.5);
  EXPECT_EQ(back->cells(), cells);
  v1::GetMapRequest get;
  get.set_name("short");
  EXPECT_EQ(client_->GetMap(get).status().code(), absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace pathd
