// End-to-end test: starts the real pathd binary on a free loopback port and
// drives it with the real pathctl binary, checking exit codes, stderr and the
// --json output exactly as a user or script would see them. Each test gets
// its own daemon, stopped with SIGTERM in TearDown (which also checks the
// graceful exit status), so a failing test never leaves a daemon behind.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "proto/planner_names.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "google/protobuf/struct.pb.h"
#include "google/protobuf/util/json_util.h"
#include "gtest/gtest.h"
#include "client/pathctl/pathctl.h"
#include "client/pathctl/png_io.h"
#include "client/pathctl/render.h"
#include "pathd/v1/map_service.pb.h"
#include "pathd/v1/planner_service.pb.h"
#include "tests/e2e/process.h"
#include "tests/testing/temp_dir.h"
#include "tests/testing/test_certs.h"

namespace pathd {
namespace {

namespace fs = std::filesystem;
using e2e::ReadFile;
using e2e::WriteFile;
using Clock = std::chrono::steady_clock;

// Hang guards, not timing assertions: generous enough for a loaded CI
// machine, there only so a broken binary fails the test instead of hanging it.
constexpr auto kCommandBound = std::chrono::seconds(120);

using e2e::kListeningPrefix;
const double kSqrt2 = std::sqrt(2.0);

// A 10x10 open room in Moving AI format.
std::string OpenRoomMap(int width = 10, int height = 10) {
  std::string text = absl::StrCat("type octile\nheight ", height, "\nwidth ",
                                  width, "\nmap\n");
  for (int y = 0; y < height; ++y) text += std::string(width, '.') + "\n";
  return text;
}



struct ProcessResult {
  int exit_code = -1;  // -1: killed by a signal
  std::string out;
  std::string err;
};

std::ostream& operator<<(std::ostream& os, const ProcessResult& r) {
  return os << "exit " << r.exit_code << "\n--- stdout ---\n"
            << r.out << "--- stderr ---\n"
            << r.err;
}

using e2e::MakePipe;
using e2e::Spawn;
using e2e::WaitForExit;

// A pathctl process (or another `binary`, e.g. pathd) whose stdout and stderr
// are collected as they arrive, so a test can act while it runs (a navigate
// session waiting for a push) and wait for what it prints.
class PathctlProcess {
 public:
  explicit PathctlProcess(const std::vector<std::string>& args,
                          const std::vector<std::string>& extra_env = {},
                          const std::string& binary = PATHCTL_BIN) {
    int out_pipe[2], err_pipe[2];
    MakePipe(out_pipe);
    MakePipe(err_pipe);
    std::vector<std::string> argv = {binary};
    argv.insert(argv.end(), args.begin(), args.end());
    pid_ = Spawn(argv, extra_env, out_pipe[1], err_pipe[1], true);
    close(out_pipe[1]);
    close(err_pipe[1]);
    fds_[0] = {out_pipe[0], POLLIN, 0};
    fds_[1] = {err_pipe[0], POLLIN, 0};
    if (pid_ < 0) {
      ADD_FAILURE() << "fork failed: " << strerror(errno);
      CloseAll();
    }
  }

  PathctlProcess(const PathctlProcess&) = delete;
  PathctlProcess& operator=(const PathctlProcess&) = delete;

  ~PathctlProcess() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      WaitForExit(pid_);
    }
    CloseAll();
  }

  // Reads until stdout holds a whole line containing `text` (true) or the
  // process closed its output or ran past kCommandBound (false).
  bool WaitForLine(const std::string& text) {
    const Clock::time_point bound = Clock::now() + kCommandBound;
    while (true) {
      const size_t at = result_.out.find(text);
      if (at != std::string::npos &&
          result_.out.find('\n', at) != std::string::npos) {
        return true;
      }
      if (open_count_ == 0 || Clock::now() > bound) return false;
      Pump();
    }
  }

  // Reads everything and waits for the exit.
  ProcessResult Finish() {
    const Clock::time_point bound = Clock::now() + kCommandBound;
    while (open_count_ > 0) {
      if (Clock::now() > bound) {
        ADD_FAILURE() << "pathctl did not finish; killing it";
        kill(pid_, SIGKILL);
        break;
      }
      Pump();
    }
    CloseAll();
    if (pid_ > 0) {
      result_.exit_code = WaitForExit(pid_);
      pid_ = -1;
    }
    return result_;
  }

  const std::string& out() const { return result_.out; }
  const std::string& err() const { return result_.err; }

  // WaitForLine for stderr (where pathd logs).
  bool WaitForStderrLine(const std::string& text) {
    const Clock::time_point bound = Clock::now() + kCommandBound;
    while (true) {
      const size_t at = result_.err.find(text);
      if (at != std::string::npos &&
          result_.err.find('\n', at) != std::string::npos) {
        return true;
      }
      if (open_count_ == 0 || Clock::now() > bound) return false;
      Pump();
    }
  }

  // Sends `signal_number` to the process (while it runs).
  void Signal(int signal_number) {
    if (pid_ > 0) kill(pid_, signal_number);
  }

 private:
  // Both pipes are read together so neither can fill up and block pathctl.
  void Pump() {
    if (poll(fds_, 2, 1000) < 0 && errno != EINTR) {
      CloseAll();
      return;
    }
    std::string* sinks[2] = {&result_.out, &result_.err};
    for (int i = 0; i < 2; ++i) {
      if (fds_[i].fd < 0 || fds_[i].revents == 0) continue;
      char buffer[4096];
      const ssize_t n = read(fds_[i].fd, buffer, sizeof(buffer));
      if (n > 0) {
        sinks[i]->append(buffer, static_cast<size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        close(fds_[i].fd);
        fds_[i].fd = -1;
        --open_count_;
      }
    }
  }

  void CloseAll() {
    for (pollfd& p : fds_) {
      if (p.fd >= 0) close(p.fd);
      p.fd = -1;
    }
    open_count_ = 0;
  }

  pid_t pid_ = -1;
  pollfd fds_[2] = {{-1, POLLIN, 0}, {-1, POLLIN, 0}};
  int open_count_ = 2;
  ProcessResult result_;
};

// Runs pathctl with `args` and returns its exit code and output.
ProcessResult RunPathctl(const std::vector<std::string>& args,
                         const std::vector<std::string>& extra_env = {}) {
  return PathctlProcess(args, extra_env).Finish();
}

template <typename Message>
Message ParseJson(const std::string& json) {
  Message message;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = true;
  auto status =
      google::protobuf::util::JsonStringToMessage(json, &message, options);
  EXPECT_TRUE(status.ok()) << status.ToString() << "\n" << json;
  return message;
}

std::vector<std::pair<int, int>> PathCells(const v1::PlanResponse& response) {
  std::vector<std::pair<int, int>> cells;
  for (const v1::Cell& c : response.path()) cells.emplace_back(c.x(), c.y());
  return cells;
}

// The status code whose name is `name`, e.g. "NOT_FOUND"; kUnknown if none.
absl::StatusCode StatusCodeNamed(const std::string& name) {
  for (int c = 0; c <= static_cast<int>(absl::StatusCode::kUnauthenticated); ++c) {
    const auto code = static_cast<absl::StatusCode>(c);
    if (absl::StatusCodeToString(code) == name) return code;
  }
  return absl::StatusCode::kUnknown;
}

class E2eTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_FALSE(temp_dir_.empty()) << scratch_.error();
    // map_dir stays empty: the daemon preloads whatever it finds there, and
    // the tests want to create every map themselves.
    map_dir_ = temp_dir_ / "map_dir";
    fs::create_directory(map_dir_);
    ASSERT_NO_FATAL_FAILURE(StartDaemon());
  }

  void TearDown() override {
    if (daemon_ != nullptr) {
      const int exit_code = StopDaemon();
      EXPECT_EQ(exit_code, 0) << "pathd did not exit cleanly on SIGTERM";
    }
  }

  // Starts pathd on a free port with this test's map_dir and `extra_flags`;
  // its log goes to the test's stderr.
  void StartDaemon(const std::vector<std::string>& extra_flags = {}) {
    std::vector<std::string> flags = {absl::StrCat("--map_dir=", map_dir_.string())};
    flags.insert(flags.end(), extra_flags.begin(), extra_flags.end());
    daemon_ = std::make_unique<e2e::PathdProcess>(
        e2e::PathdProcessOptions{.binary = PATHD_BIN, .flags = flags});
    ASSERT_TRUE(daemon_->listening()) << daemon_->status();
    address_ = daemon_->address();
  }

  // Sends SIGTERM and returns the daemon's exit code (-1: killed by a signal).
  int StopDaemon() {
    const int exit_code = daemon_->Stop();
    EXPECT_EQ(daemon_->StdoutAfterListening(), "")
        << "pathd must print only the listening line on stdout";
    daemon_.reset();
    return exit_code;
  }

  // A pathd of the test's own besides the fixture's, with `flags` and its
  // log in the temp folder; fails the test unless it listens.
  std::unique_ptr<e2e::PathdProcess> StartOwnPathd(const std::vector<std::string>& flags) {
    auto pathd = std::make_unique<e2e::PathdProcess>(e2e::PathdProcessOptions{
        .binary = PATHD_BIN, .flags = flags, .log_file = temp_dir_ / "own_pathd.log"});
    EXPECT_TRUE(pathd->listening()) << pathd->status();
    return pathd;
  }

  // SIGTERM to `pathd`: its exit code, later stdout and log (as err).
  static ProcessResult StopOwnPathd(e2e::PathdProcess& pathd) {
    ProcessResult result;
    result.exit_code = pathd.Stop();
    result.out = pathd.StdoutAfterListening();
    result.err = pathd.Log();
    return result;
  }

  // Runs pathctl against this test's daemon.
  ProcessResult Ctl(std::vector<std::string> args) {
    args.insert(args.begin(), absl::StrCat("--server=", address_));
    return RunPathctl(args);
  }

  // Starts pathctl against this test's daemon without waiting for it.
  std::unique_ptr<PathctlProcess> StartCtl(std::vector<std::string> args) {
    args.insert(args.begin(), absl::StrCat("--server=", address_));
    return std::make_unique<PathctlProcess>(args);
  }

  // Writes a map file into the temp folder and returns its path.
  std::string MapFile(const std::string& name, const std::string& contents) {
    const fs::path path = temp_dir_ / name;
    WriteFile(path, contents);
    return path.string();
  }

  // Creates `name` from Moving AI text; fails the test unless it worked.
  void CreateMap(const std::string& name, const std::string& text,
                 std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"maps", "create", name, "--from",
                                     MapFile(name + ".map", text)};
    args.insert(args.end(), extra.begin(), extra.end());
    const ProcessResult r = Ctl(args);
    ASSERT_EQ(r.exit_code, 0) << r;
  }

  // Runs `plan ... --json` and parses the response; `expected_exit` is 0 for
  // a found path and 3 for none.
  v1::PlanResponse PlanJson(std::vector<std::string> args,
                            int expected_exit = 0) {
    args.insert(args.begin(), "plan");
    args.push_back("--json");
    const ProcessResult r = Ctl(args);
    EXPECT_EQ(r.exit_code, expected_exit) << r;
    return ParseJson<v1::PlanResponse>(r.out);
  }

  // Expects pathctl to fail with the exit code of `code` (1, or 5-8 for the
  // codes scripts tell apart) and "error: <code>: ..." on stderr containing
  // every one of `words`.
  void ExpectRpcError(const std::vector<std::string>& args,
                      const std::string& code,
                      const std::vector<std::string>& words = {}) {
    const ProcessResult r = Ctl(args);
    EXPECT_EQ(r.exit_code, pathctl::ExitCodeForStatus(StatusCodeNamed(code))) << r;
    EXPECT_TRUE(absl::StartsWith(r.err, absl::StrCat("error: ", code, ": ")))
        << r;
    for (const std::string& word : words) {
      EXPECT_TRUE(absl::StrContains(r.err, word))
          << "missing '" << word << "'\n"
          << r;
    }
  }

  // Removed with the fixture, after TearDown has stopped the daemon.
  testing::TempDir scratch_{"pathd_e2e"};
  fs::path temp_dir_ = scratch_.path();
  fs::path map_dir_;
  std::unique_ptr<e2e::PathdProcess> daemon_;
  std::string address_;
};

TEST_F(E2eTest, HealthReportsServing) {
  const ProcessResult r = Ctl({"health"});
  EXPECT_EQ(r.exit_code, 0) << r;
  EXPECT_EQ(r.out, "SERVING\n");
}

TEST_F(E2eTest, ServerAddressFromEnvironment) {
  const ProcessResult r =
      RunPathctl({"health"}, {absl::StrCat("PATHD_SERVER=", address_)});
  EXPECT_EQ(r.exit_code, 0) << r;
  EXPECT_EQ(r.out, "SERVING\n");
}

TEST_F(E2eTest, CreateListGetDelete) {
  const ProcessResult created =
      Ctl({"maps", "create", "room", "--from",
           MapFile("room.map", OpenRoomMap()), "--json"});
  ASSERT_EQ(created.exit_code, 0) << created;
  const auto create = ParseJson<v1::CreateMapResponse>(created.out);
  EXPECT_EQ(create.info().name(), "room");
  EXPECT_EQ(create.info().width(), 10);
  EXPECT_EQ(create.info().height(), 10);
  EXPECT_EQ(create.info().version(), 1u);
  EXPECT_EQ(create.info().free_cells(), 100);
  EXPECT_EQ(create.info().blocked_cells(), 0);

  const ProcessResult list = Ctl({"maps", "list"});
  ASSERT_EQ(list.exit_code, 0) << list;
  EXPECT_TRUE(absl::StrContains(list.out, "room")) << list;
  EXPECT_TRUE(absl::StrContains(list.out, "10x10")) << list;

  const ProcessResult list_json = Ctl({"maps", "list", "--json"});
  ASSERT_EQ(list_json.exit_code, 0) << list_json;
  const auto maps = ParseJson<v1::ListMapsResponse>(list_json.out);
  ASSERT_EQ(maps.maps_size(), 1) << list_json;
  EXPECT_EQ(maps.maps(0).name(), "room");

  const ProcessResult get = Ctl({"maps", "get", "room"});
  ASSERT_EQ(get.exit_code, 0) << get;
  EXPECT_TRUE(absl::StrContains(get.out, "10 x 10 cells")) << get;
  EXPECT_TRUE(absl::StrContains(get.out, "version:     1")) << get;

  ASSERT_EQ(Ctl({"maps", "set", "room", "3", "2", "lethal"}).exit_code, 0);
  ASSERT_EQ(Ctl({"maps", "set", "room", "4", "2", "100"}).exit_code, 0);
  ASSERT_EQ(Ctl({"maps", "set", "room", "5", "2", "unknown"}).exit_code, 0);
  const ProcessResult cells = Ctl({"maps", "get", "room", "--cells"});
  ASSERT_EQ(cells.exit_code, 0) << cells;
  // Row 2 holds lethal, cost 100 (digit 4: 85..112) and unknown.
  EXPECT_TRUE(
      absl::StrContains(cells.out, "\n..........\n..........\n...#4?....\n"))
      << cells;

  const ProcessResult deleted = Ctl({"maps", "delete", "room"});
  ASSERT_EQ(deleted.exit_code, 0) << deleted;
  EXPECT_TRUE(absl::StrContains(deleted.out, "version 4")) << deleted;
  ExpectRpcError({"maps", "get", "room"}, "NOT_FOUND", {"room"});
  const ProcessResult empty = Ctl({"maps", "list"});
  EXPECT_EQ(empty.exit_code, 0) << empty;
  EXPECT_EQ(empty.out, "no maps\n");
}

TEST_F(E2eTest, CreateFromRosMap) {
  // The image lives beside the YAML, which names it relatively: pathctl must
  // resolve it against the YAML's folder, not its own working directory.
  const fs::path ros_dir = temp_dir_ / "ros";
  fs::create_directory(ros_dir);
  // 4x3 P2 image: 254 white (free), 0 black (occupied), 128 grey (unknown).
  WriteFile(ros_dir / "room.pgm",
            "P2\n4 3\n255\n"
            "0 254 254 254\n"
            "254 128 254 254\n"
            "254 254 254 0\n");
  WriteFile(ros_dir / "room.yaml",
            "image: room.pgm\nresolution: 0.05\norigin: [1.0, 2.0, 0.0]\n"
            "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
  const ProcessResult created =
      Ctl({"maps", "create", "ros_room", "--from",
           (ros_dir / "room.yaml").string(), "--json"});
  ASSERT_EQ(created.exit_code, 0) << created;
  const auto info = ParseJson<v1::CreateMapResponse>(created.out).info();
  EXPECT_EQ(info.width(), 4);
  EXPECT_EQ(info.height(), 3);
  EXPECT_DOUBLE_EQ(info.resolution(), 0.05);
  EXPECT_DOUBLE_EQ(info.origin().x(), 1.0);
  EXPECT_DOUBLE_EQ(info.origin().y(), 2.0);

  // Row 0 is the image's bottom row (OccupancyGrid convention).
  const ProcessResult cells = Ctl({"maps", "get", "ros_room", "--cells"});
  ASSERT_EQ(cells.exit_code, 0) << cells;
  EXPECT_TRUE(absl::EndsWith(cells.out, "\n...#\n.?..\n#...\n")) << cells;

  // A YAML carries its own resolution.
  const ProcessResult r =
      Ctl({"maps", "create", "ros_room2", "--from",
           (ros_dir / "room.yaml").string(), "--resolution=2"});
  EXPECT_EQ(r.exit_code, 2) << r;
}

TEST_F(E2eTest, EveryPlannerFindsTheDiagonal) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  // From corner to corner of an open room the only shortest path is the
  // diagonal: 9 moves of sqrt(2), whatever the planner.
  for (const char* planner : {"astar", "dijkstra", "bfs"}) {
    SCOPED_TRACE(planner);
    const v1::PlanResponse plan = PlanJson(
        {"room", "0", "0", "9", "9", absl::StrCat("--planner=", planner)});
    EXPECT_TRUE(plan.found());
    EXPECT_EQ(plan.outcome(), v1::PLAN_OUTCOME_FOUND);
    EXPECT_EQ(plan.planner(), planner);
    EXPECT_NEAR(plan.cost(), 9 * kSqrt2, 1e-9);
    EXPECT_NEAR(plan.length(), 9 * kSqrt2, 1e-9);
    EXPECT_EQ(plan.path_size(), 10);
    EXPECT_EQ(plan.map_version(), 1u);
    EXPECT_GT(plan.expansions(), 0);
  }
  // 4-connected, the same trip is 18 straight moves.
  const v1::PlanResponse four =
      PlanJson({"room", "0", "0", "9", "9", "--planner", "astar",
                "--connectivity", "4"});
  EXPECT_NEAR(four.cost(), 18.0, 1e-9);
  EXPECT_EQ(four.path_size(), 19);

  // The human-readable form carries the same facts.
  const ProcessResult text = Ctl({"plan", "room", "0", "0", "9", "9"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "found:       yes")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "cost:        12.727922")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "map version: 1")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "path (10 cells): (0,0) (1,1)"))
      << text;
}

// A 20 x 12 room split by a wall at x = 10 with a gap in rows 8..9, so no
// planner gets there in a straight line.
std::string WalledRoomMap() {
  std::string text = "type octile\nheight 12\nwidth 20\nmap\n";
  for (int y = 0; y < 12; ++y) {
    std::string row(20, '.');
    if (y < 8 || y > 9) row[10] = '@';
    text += row + "\n";
  }
  return text;
}

TEST_F(E2eTest, EveryPlannerRunsThroughPathctl) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  for (const WirePlanner& entry : WirePlanners()) {
    const std::string planner(entry.name);
    SCOPED_TRACE(planner);
    const ProcessResult r = Ctl({"plan", "walled", "2", "2", "17", "3",
                                 absl::StrCat("--planner=", planner), "--json"});
    // The potential field may stall behind the wall (exit 3, LOCAL_MINIMUM);
    // every complete planner must find the gap.
    ASSERT_TRUE(r.exit_code == 0 || (planner == "potential_field" && r.exit_code == 3))
        << r;
    const auto plan = ParseJson<v1::PlanResponse>(r.out);
    EXPECT_EQ(plan.planner(), planner);
    if (!plan.found()) {
      EXPECT_EQ(plan.outcome(), v1::PLAN_OUTCOME_LOCAL_MINIMUM);
      continue;
    }
    ASSERT_GE(plan.path_size(), 2);
    EXPECT_EQ(plan.path(0).x(), 2);
    EXPECT_EQ(plan.path(0).y(), 2);
    EXPECT_EQ(plan.path(plan.path_size() - 1).x(), 17);
    EXPECT_EQ(plan.path(plan.path_size() - 1).y(), 3);
    // Through the gap: the wall column is only crossed in rows 8..9.
    for (const v1::Cell& c : plan.path()) {
      if (c.x() == 10) {
        EXPECT_TRUE(c.y() == 8 || c.y() == 9) << c.y();
      }
    }
    // Never shorter than the straight line, and A*'s optimum bounds every
    // optimal planner.
    EXPECT_GE(plan.length(), std::hypot(15.0, 1.0) - 1e-9);
    if (planner == "rtaa_star" || planner == "lrta_star") {
      EXPECT_GT(plan.episodes(), 0);
    }
  }
}

TEST_F(E2eTest, RobotRadiusKeepsThePathAwayFromWalls) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap(), {"--resolution=0.5"}));
  // With a 1-cell radius the two-row gap narrows to nothing: cells of rows 8
  // and 9 next to the wall ends are within 1 cell of a lethal cell.
  const v1::PlanResponse blocked =
      PlanJson({"walled", "2", "2", "17", "3", "--robot_radius_cells=1"}, 3);
  EXPECT_EQ(blocked.outcome(), v1::PLAN_OUTCOME_NO_PATH);
  EXPECT_DOUBLE_EQ(blocked.robot_radius_cells(), 1.0);
  // 0.25 m at 0.5 m per cell is half a cell: only lethal cells' centres are
  // within it, so the plan is the plain one.
  const v1::PlanResponse thin =
      PlanJson({"walled", "2", "2", "17", "3", "--robot_radius=0.25"});
  const v1::PlanResponse plain = PlanJson({"walled", "2", "2", "17", "3"});
  EXPECT_DOUBLE_EQ(thin.robot_radius_cells(), 0.5);
  EXPECT_NEAR(thin.cost(), plain.cost(), 1e-9);
  // A start inside the inflated band is refused with the reason.
  ExpectRpcError({"plan", "walled", "9", "2", "17", "3", "--robot_radius_cells=1.5"},
                 "INVALID_ARGUMENT", {"start", "robot radius"});
  ExpectRpcError({"plan", "walled", "2", "2", "17", "3", "--robot_radius_cells=-1"},
                 "INVALID_ARGUMENT", {"robot_radius_cells"});
  const ProcessResult both =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--robot_radius=1",
           "--robot_radius_cells=1"});
  EXPECT_EQ(both.exit_code, 2) << both;
}

TEST_F(E2eTest, SimplifyKeepsOnlyTheTurns) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const v1::PlanResponse plain = PlanJson({"walled", "2", "2", "17", "3"});
  const v1::PlanResponse simple =
      PlanJson({"walled", "2", "2", "17", "3", "--simplify"});
  EXPECT_FALSE(plain.any_angle());
  EXPECT_TRUE(simple.any_angle());
  EXPECT_LT(simple.path_size(), plain.path_size());
  EXPECT_LE(simple.length(), plain.length() + 1e-9);
  EXPECT_LE(simple.cost(), plain.cost() + 1e-9);
  const ProcessResult text = Ctl({"plan", "walled", "2", "2", "17", "3", "--simplify"});
  EXPECT_TRUE(absl::StrContains(text.out, "vertices, any-angle")) << text;
}

TEST_F(E2eTest, DistanceTransformWritesItsCostToGoField) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const std::string csv = (temp_dir_ / "ctg.csv").string();
  const ProcessResult r =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--planner=distance_transform",
           "--cost_to_go_file", csv});
  ASSERT_EQ(r.exit_code, 0) << r;
  std::ifstream in(csv);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    rows.push_back(absl::StrSplit(line, ','));
  }
  ASSERT_EQ(rows.size(), 12u);
  for (const auto& row : rows) ASSERT_EQ(row.size(), 20u);
  EXPECT_EQ(rows[3][17], "0.000000");  // the goal
  EXPECT_EQ(rows[0][10], "inf");       // a wall cell
  double start_cost = 0;
  ASSERT_TRUE(absl::SimpleAtod(rows[2][2], &start_cost));
  const v1::PlanResponse astar = PlanJson({"walled", "2", "2", "17", "3"});
  EXPECT_NEAR(start_cost, astar.cost(), 1e-5);
}

TEST_F(E2eTest, PotentialFieldReportsWhereItStalled) {
  // A cup open towards the start: the goal's pull holds the robot inside it.
  std::string text = "type octile\nheight 15\nwidth 15\nmap\n";
  for (int y = 0; y < 15; ++y) {
    std::string row(15, '.');
    if (y >= 4 && y <= 10) row[10] = '@';
    if (y == 4 || y == 10) {
      for (int x = 6; x <= 10; ++x) row[x] = '@';
    }
    text += row + "\n";
  }
  ASSERT_NO_FATAL_FAILURE(CreateMap("cup", text));
  const ProcessResult r =
      Ctl({"plan", "cup", "2", "7", "13", "7", "--planner=potential_field"});
  EXPECT_EQ(r.exit_code, 3) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "outcome:     LOCAL_MINIMUM")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "stalled at:")) << r;
  const v1::PlanResponse plan =
      PlanJson({"cup", "2", "7", "13", "7", "--planner=potential_field"}, 3);
  EXPECT_GT(plan.stall_point().x(), 5.0);
  EXPECT_LT(plan.stall_point().x(), 10.0);
  // Around the cup's back the field leads straight to the goal.
  const v1::PlanResponse open =
      PlanJson({"cup", "2", "1", "13", "1", "--planner=potential_field"});
  EXPECT_GT(open.trajectory_size(), 1);
}

TEST_F(E2eTest, JpsRefusesWeightedMaps) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const ProcessResult set = Ctl({"maps", "set", "room", "4", "4", "100"});
  ASSERT_EQ(set.exit_code, 0) << set;
  ExpectRpcError({"plan", "room", "0", "0", "9", "9", "--planner=jps"},
                 "FAILED_PRECONDITION", {"jps", "(4, 4)", "cost_weight 0"});
  // Ignoring cell costs the map is uniform again.
  const v1::PlanResponse flat =
      PlanJson({"room", "0", "0", "9", "9", "--planner=jps", "--cost_weight=0"});
  EXPECT_NEAR(flat.cost(), 9 * kSqrt2, 1e-9);
}

TEST_F(E2eTest, BadPlannerOptionsNameTheField) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ExpectRpcError({"plan", "room", "0", "0", "9", "9", "--planner=weighted_astar",
                  "--heuristic_weight=0.5"},
                 "INVALID_ARGUMENT", {"heuristic_weight", "0.5"});
  ExpectRpcError({"plan", "room", "0", "0", "9", "9", "--planner=rtaa_star",
                  "--lookahead=-1"},
                 "INVALID_ARGUMENT", {"lookahead"});
  ExpectRpcError({"plan", "room", "0", "0", "9", "9", "--planner=potential_field",
                  "--pf_step=-1"},
                 "INVALID_ARGUMENT", {"potential_field.step_size"});
  const ProcessResult shape = Ctl({"plan", "room", "0", "0", "9", "9",
                                   "--planner=potential_field", "--pf_attractive=cubic"});
  EXPECT_EQ(shape.exit_code, 2) << shape;
  // A whole cost-to-go field is refused for maps over 4 Mi cells.
  std::string big = "type octile\nheight 2100\nwidth 2100\nmap\n";
  const std::string row = std::string(2100, '.') + "\n";
  for (int y = 0; y < 2100; ++y) big += row;
  ASSERT_NO_FATAL_FAILURE(CreateMap("big", big));
  ExpectRpcError({"plan", "big", "0", "0", "9", "9", "--planner=distance_transform",
                  "--cost_to_go_file", (temp_dir_ / "big.csv").string()},
                 "INVALID_ARGUMENT", {"return_cost_to_go", "4194304"});
  // The server keeps serving.
  EXPECT_TRUE(PlanJson({"room", "0", "0", "9", "9"}).found());
}

TEST_F(E2eTest, BlockingAPathCellChangesThePlan) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse before = PlanJson({"room", "0", "0", "9", "9"});
  ASSERT_TRUE(before.found());
  ASSERT_GE(before.path_size(), 3);
  const v1::Cell blocked = before.path(before.path_size() / 2);

  const ProcessResult set =
      Ctl({"maps", "set", "room", absl::StrCat(blocked.x()),
           absl::StrCat(blocked.y()), "254"});
  ASSERT_EQ(set.exit_code, 0) << set;
  EXPECT_TRUE(absl::StrContains(set.out, "now at version 2")) << set;

  const v1::PlanResponse after = PlanJson({"room", "0", "0", "9", "9"});
  ASSERT_TRUE(after.found());
  EXPECT_GT(after.map_version(), before.map_version());
  EXPECT_NE(PathCells(after), PathCells(before));
  for (const v1::Cell& c : after.path()) {
    EXPECT_FALSE(c.x() == blocked.x() && c.y() == blocked.y())
        << "path still crosses the blocked cell (" << c.x() << "," << c.y()
        << ")";
  }
  // The diagonal was the unique optimum, so any detour costs more.
  EXPECT_GT(after.cost(), before.cost() + 1e-9);
}

TEST_F(E2eTest, WallingOffTheGoalExitsThree) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const ProcessResult rect =
      Ctl({"maps", "rect", "room", "0", "5", "9", "5", "lethal"});
  ASSERT_EQ(rect.exit_code, 0) << rect;
  EXPECT_TRUE(absl::StrContains(rect.out, "(10 cells changed)")) << rect;

  const v1::PlanResponse plan = PlanJson({"room", "0", "0", "9", "9"}, 3);
  EXPECT_FALSE(plan.found());
  EXPECT_EQ(plan.outcome(), v1::PLAN_OUTCOME_NO_PATH);
  EXPECT_EQ(plan.path_size(), 0);

  const ProcessResult text = Ctl({"plan", "room", "0", "0", "9", "9"});
  EXPECT_EQ(text.exit_code, 3) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "found:       no")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "outcome:     NO_PATH")) << text;
}

TEST_F(E2eTest, PlansBetweenWorldPoints) {
  ASSERT_NO_FATAL_FAILURE(
      CreateMap("room", OpenRoomMap(), {"--resolution=0.5"}));
  // With 0.5 m cells and the origin at 0, (0.3, 0.2) m lies in cell (0,0) and
  // (4.9, 0.1) m in cell (9,0).
  const v1::PlanResponse plan =
      PlanJson({"room", "0.3", "0.2", "4.9", "0.1", "--world"});
  ASSERT_TRUE(plan.found());
  EXPECT_EQ(plan.start().x(), 0);
  EXPECT_EQ(plan.start().y(), 0);
  EXPECT_EQ(plan.goal().x(), 9);
  EXPECT_EQ(plan.goal().y(), 0);
  EXPECT_NEAR(plan.length(), 9.0, 1e-9);
  ASSERT_EQ(plan.world_path_size(), plan.path_size());
  EXPECT_NEAR(plan.world_path(0).x(), 0.25, 1e-9);
  EXPECT_NEAR(plan.world_path(0).y(), 0.25, 1e-9);

  const ProcessResult text =
      Ctl({"plan", "room", "0.3", "0.2", "4.9", "0.1", "--world"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "world path (m): (0.25,0.25)"))
      << text;
}

TEST_F(E2eTest, ServerErrorsReachTheUser) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));

  ExpectRpcError({"plan", "nosuch", "0", "0", "1", "1"}, "NOT_FOUND",
                 {"nosuch"});
  ExpectRpcError({"maps", "delete", "nosuch"}, "NOT_FOUND");
  ExpectRpcError({"maps", "set", "nosuch", "0", "0", "0"}, "NOT_FOUND");

  ExpectRpcError({"plan", "room", "20", "20", "0", "0"}, "INVALID_ARGUMENT",
                 {"start"});
  ExpectRpcError({"plan", "room", "-1", "0", "0", "0"}, "INVALID_ARGUMENT",
                 {"start"});
  ASSERT_EQ(Ctl({"maps", "set", "room", "9", "9", "lethal"}).exit_code, 0);
  ExpectRpcError({"plan", "room", "0", "0", "9", "9"}, "INVALID_ARGUMENT",
                 {"goal"});
  ExpectRpcError({"maps", "set", "room", "10", "0", "0"}, "INVALID_ARGUMENT");

  // The server parses map files; its message names the problem.
  ExpectRpcError(
      {"maps", "create", "bad", "--from",
       MapFile("bad.map", "type octile\nheight 2\nwidth 3\nmap\n..x\n...\n")},
      "INVALID_ARGUMENT");
  ExpectRpcError(
      {"maps", "create", "room", "--from", MapFile("room2.map", OpenRoomMap())},
      "ALREADY_EXISTS");
  const ProcessResult replaced =
      Ctl({"maps", "create", "room", "--from",
           MapFile("room3.map", OpenRoomMap(5, 5)), "--replace", "--json"});
  ASSERT_EQ(replaced.exit_code, 0) << replaced;
  const auto info = ParseJson<v1::CreateMapResponse>(replaced.out).info();
  EXPECT_EQ(info.width(), 5);
  EXPECT_GT(info.version(), 2u) << "a replaced map's version continues";

  // Optimistic concurrency: an update based on a stale version is refused.
  const uint64_t version = info.version();
  ExpectRpcError({"maps", "set", "room", "1", "1", "lethal",
                  absl::StrCat("--expected_version=", version - 1)},
                 "ABORTED");
  const ProcessResult fresh =
      Ctl({"maps", "set", "room", "1", "1", "lethal", "--expected_version",
           absl::StrCat(version)});
  EXPECT_EQ(fresh.exit_code, 0) << fresh;
  EXPECT_TRUE(
      absl::StrContains(fresh.out, absl::StrCat("version ", version + 1)))
      << fresh;

  // A local file that does not exist never reaches the server; NOT_FOUND
  // exits 7 whether the map or the file is missing.
  const ProcessResult missing = Ctl(
      {"maps", "create", "x", "--from", (temp_dir_ / "missing.map").string()});
  EXPECT_EQ(missing.exit_code, 7) << missing;
  EXPECT_TRUE(absl::StrContains(missing.err, "missing.map")) << missing;
}

TEST_F(E2eTest, UsageErrorsExitTwo) {
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::string txt = MapFile("room.txt", OpenRoomMap());
  const std::vector<Case> cases = {
      {{}, "missing command"},
      {{"frobnicate"}, "unknown command 'frobnicate'"},
      {{"maps"}, "maps needs a subcommand"},
      {{"maps", "shred", "x"}, "unknown maps subcommand 'shred'"},
      {{"maps", "create", "room"}, "--from"},
      {{"maps", "create", "room", "--from", txt}, "unknown map file type"},
      {{"maps", "get"}, "maps get takes one NAME"},
      {{"maps", "set", "room", "0", "0"}, "maps set takes NAME X Y COST"},
      {{"maps", "set", "room", "0", "zero", "0"},
       "Y: 'zero' is not an integer"},
      {{"maps", "set", "room", "0", "0", "300"}, "COST: '300'"},
      {{"maps", "rect", "room", "0", "0", "1", "1"}, "maps rect takes"},
      {{"plan", "room", "0", "0"}, "plan takes NAME SX SY GX GY"},
      {{"plan", "room", "0", "0", "1", "x"}, "GY: 'x' is not an integer"},
      {{"plan", "room", "0", "0", "1", "1", "--planner=warp"},
       "unknown planner 'warp'; valid planners: astar, dijkstra, bfs"},
      {{"plan", "room", "0", "0", "1", "1", "--connectivity=6"},
       "--connectivity"},
      {{"--bogus", "maps", "list"}, "unknown flag --bogus"},
      {{"maps", "list", "--timeout=soon"}, "--timeout"},
      {{"maps", "list", "--server"}, "--server needs a value"},
      {{"navigate", "room", "0", "0", "1"}, "navigate takes NAME SX SY GX GY"},
      {{"navigate", "room", "0", "0", "1", "1", "--world"}, "--world"},
      {{"cost-to-go", "room", "1"}, "cost-to-go takes NAME GX GY"},
      {{"cost-to-go", "room", "1", "1", "--window=1,2,3"},
       "--window takes X,Y,W,H"},
      {{"cost-to-go", "room", "1", "1", "--window=0,0,0,4"},
       "--window width and height must be positive"},
      {{"cache-stats", "spm"}, "cache-stats takes no arguments"},
      // A flag the command does not read is named, not ignored: plan used
      // to write no picture for -o and say nothing.
      {{"plan", "room", "0", "0", "1", "1", "-o", "x.png"},
       "-o does not apply to plan; render reads it"},
      {{"maps", "list", "--planner=astar"}, "--planner does not apply to maps list"},
      {{"health", "--count=3"}, "--count does not apply to health"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(absl::StrJoin(c.args, " "));
    const ProcessResult r = Ctl(c.args);
    EXPECT_EQ(r.exit_code, 2) << r;
    EXPECT_TRUE(absl::StartsWith(r.err, "error: ")) << r;
    EXPECT_TRUE(absl::StrContains(r.err, c.says)) << r;
    EXPECT_TRUE(absl::StrContains(r.err, "usage:")) << r;
    EXPECT_EQ(r.out, "") << r;
  }
  // A command's usage error shows that command's usage, not every command's.
  const ProcessResult plan = Ctl({"plan", "room", "0", "0"});
  EXPECT_TRUE(absl::StrContains(plan.err, "usage: pathctl [flags] plan NAME SX SY GX GY"))
      << plan;
  EXPECT_TRUE(absl::StrContains(plan.err, "run 'pathctl help plan' for details")) << plan;
  EXPECT_FALSE(absl::StrContains(plan.err, "maps create")) << plan;
  EXPECT_FALSE(fs::exists("x.png"));

  const ProcessResult help = RunPathctl({"--help"});
  EXPECT_EQ(help.exit_code, 0) << help;
  EXPECT_TRUE(absl::StrContains(help.out, "exit codes:")) << help;
  EXPECT_TRUE(absl::StrContains(help.out, "3  plan ran but found no path"))
      << help;
}

// Path lines of `pathctl navigate` output ("  path (N cells): (x,y) ..."),
// without the prefix.
std::vector<std::string> NavigatePaths(const std::string& out) {
  std::vector<std::string> paths;
  for (absl::string_view line : absl::StrSplit(out, '\n')) {
    if (!absl::ConsumePrefix(&line, "  path (")) continue;
    const size_t colon = line.find("): ");
    if (colon != absl::string_view::npos) {
      paths.emplace_back(line.substr(colon + 3));
    }
  }
  return paths;
}

// The seed's D* Lite example, shipped as maps/dstar_example.map and
// examples/navigate/dstar_example.nav: the robot steps from (4,2) to (3,2),
// an obstacle appears at (2,2), the robot drives the repaired path.
TEST_F(E2eTest, NavigateReplaysTheDstarLiteDemo) {
  const std::string source_dir = PATHD_SOURCE_DIR;
  ASSERT_EQ(Ctl({"maps", "create", "dstar_example", "--from",
                 source_dir + "/maps/dstar_example.map"})
                .exit_code,
            0);
  const ProcessResult r =
      Ctl({"navigate", "dstar_example", "4", "2", "0", "0", "--script",
           source_dir + "/examples/navigate/dstar_example.nav"});
  ASSERT_EQ(r.exit_code, 0) << r;
  const std::vector<std::string> paths = NavigatePaths(r.out);
  // OPENED, MOVED, OBSERVED, then one answer per step.
  ASSERT_GE(paths.size(), 4u) << r;
  EXPECT_EQ(paths[0], "(4,2) (3,2) (2,2) (1,2) (0,2) (0,1) (0,0)") << r;
  EXPECT_EQ(paths[1], "(3,2) (2,2) (1,2) (0,2) (0,1) (0,0)") << r;
  // The only optimal detour: no corner cutting past (2,2) or (1,1).
  EXPECT_EQ(paths[2], "(3,2) (3,3) (2,3) (1,3) (0,2) (0,1) (0,0)") << r;
  for (size_t i = 2; i < paths.size(); ++i) {
    EXPECT_FALSE(absl::StrContains(paths[i], "(2,2)")) << paths[i];
  }
  EXPECT_TRUE(absl::StrContains(r.out, "[OPENED] seq 1")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "found, cost 6.000000, 7 cells")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "found, cost 6.414214, 7 cells")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "at the goal (0,0)")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "closed: ")) << r;
  // The demo's observation is private: the shared map is untouched.
  const ProcessResult get = Ctl({"maps", "get", "dstar_example"});
  EXPECT_TRUE(absl::StrContains(get.out, "version:     1")) << get;

  // Without a script: the first path, then a clean close.
  const ProcessResult open =
      Ctl({"navigate", "dstar_example", "4", "2", "0", "0"});
  ASSERT_EQ(open.exit_code, 0) << open;
  EXPECT_EQ(NavigatePaths(open.out),
            std::vector<std::string>{"(4,2) (3,2) (2,2) (1,2) (0,2) (0,1) (0,0)"})
      << open;
}

// The issue's headline: a robot driven by pathctl navigate sees its path
// change when another client blocks a cell on it, without asking.
TEST_F(E2eTest, NavigateSessionReceivesAPushWhenAnotherClientBlocksItsPath) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const std::string script = MapFile("push.nav", "expect-push 1000\n");
  std::unique_ptr<PathctlProcess> robot =
      StartCtl({"navigate", "room", "0", "0", "9", "9", "--script", script});
  ASSERT_TRUE(robot->WaitForLine(" cells): ")) << robot->Finish();
  const std::vector<std::string> first = NavigatePaths(robot->out());
  ASSERT_EQ(first.size(), 1u) << robot->out();
  // The open room's only shortest path is the diagonal; block its middle.
  ASSERT_TRUE(absl::StrContains(first[0], "(4,4)")) << first[0];
  const ProcessResult set = Ctl({"maps", "set", "room", "4", "4", "lethal"});
  ASSERT_EQ(set.exit_code, 0) << set;

  const ProcessResult r = robot->Finish();
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "[MAP_CHANGED, unasked] seq 0")) << r;
  const std::vector<std::string> paths = NavigatePaths(r.out);
  ASSERT_EQ(paths.size(), 2u) << r;
  EXPECT_FALSE(absl::StrContains(paths[1], "(4,4)")) << paths[1];
  EXPECT_TRUE(absl::StartsWith(paths[1], "(0,0) ")) << paths[1];
  EXPECT_TRUE(absl::EndsWith(paths[1], " (9,9)")) << paths[1];
}

TEST_F(E2eTest, MapsWatchSeesAnotherClientsUpdateAndTheDelete) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  std::unique_ptr<PathctlProcess> watch = StartCtl({"maps", "watch", "room"});
  std::unique_ptr<PathctlProcess> json =
      StartCtl({"maps", "watch", "room", "--json", "--count", "2"});
  // Without --from_version the whole map comes first, which also shows the
  // stream is open before the update is made.
  ASSERT_TRUE(watch->WaitForLine("version 1 resync: whole map 10x10")) << watch->Finish();
  ASSERT_TRUE(json->WaitForLine("MAP_EVENT_KIND_RESYNC")) << json->Finish();
  const ProcessResult rect = Ctl({"maps", "rect", "room", "2", "3", "4", "5", "lethal"});
  ASSERT_EQ(rect.exit_code, 0) << rect;

  const ProcessResult json_result = json->Finish();
  ASSERT_EQ(json_result.exit_code, 0) << json_result;
  const std::vector<std::string> lines =
      absl::StrSplit(json_result.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 2u) << json_result;
  const auto updated = ParseJson<v1::MapEvent>(lines[1]);
  EXPECT_EQ(updated.kind(), v1::MAP_EVENT_KIND_UPDATED);
  EXPECT_EQ(updated.version(), 2u);
  ASSERT_EQ(updated.changes_size(), 1);
  EXPECT_EQ(updated.changes(0).rect().x_min(), 2);
  EXPECT_EQ(updated.changes(0).rect().y_max(), 5);
  EXPECT_EQ(updated.changes(0).costs(), std::string(9, '\xfe'));

  const ProcessResult deleted = Ctl({"maps", "delete", "room"});
  ASSERT_EQ(deleted.exit_code, 0) << deleted;
  const ProcessResult r = watch->Finish();
  EXPECT_EQ(r.exit_code, 0) << r;
  EXPECT_EQ(r.out,
            "version 1 resync: whole map 10x10\n"
            "version 2 updated: 9 cells in 1 rect: (2,3)-(4,5)\n"
            "version 2 deleted\n");
}

TEST_F(E2eTest, NavigateScriptErrorsAndFailedExpectations) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  // A bad line is reported with its place before anything is sent.
  const std::string bad = MapFile("bad.nav", "move 1 1\njump 2 2\n");
  const ProcessResult r =
      Ctl({"navigate", "room", "0", "0", "9", "9", "--script", bad});
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_EQ(r.err, absl::StrCat("error: ", bad,
                                ":2: unknown command 'jump'; expected move, "
                                "follow, block, free, cost, rect, private, "
                                "wait or expect-push\n"));
  EXPECT_EQ(r.out, "") << r;
  // Nobody else updates the map, so no push comes.
  const std::string lonely = MapFile("lonely.nav", "move 1 1\nexpect-push 50\n");
  ExpectRpcError({"navigate", "room", "0", "0", "9", "9", "--script", lonely},
                 "DEADLINE_EXCEEDED", {"lonely.nav:2: expect-push"});
  // A move off the map ends the session with the server's reason.
  const std::string off = MapFile("off.nav", "move 40 1\n");
  ExpectRpcError({"navigate", "room", "0", "0", "9", "9", "--script", off},
                 "INVALID_ARGUMENT");
  ExpectRpcError({"navigate", "nosuch", "0", "0", "9", "9"}, "NOT_FOUND",
                 {"nosuch"});
}

TEST_F(E2eTest, CostToGoPrintsAWindowOrWritesItsCsv) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  // Columns 9..11 of rows 0..1 straddle the wall at x = 10.
  const ProcessResult table =
      Ctl({"cost-to-go", "walled", "17", "3", "--window", "9,0,3,2"});
  ASSERT_EQ(table.exit_code, 0) << table;
  EXPECT_TRUE(absl::StrContains(table.out, "goal:        (17,3)")) << table;
  EXPECT_TRUE(absl::StrContains(table.out, "window:      x 9..11, y 0..1 (3x2 cells)"))
      << table;
  EXPECT_TRUE(absl::StrContains(table.out, "reachable:   4 of 6 cells")) << table;
  EXPECT_TRUE(absl::StrContains(table.out, "  y\\x       9      10      11\n"))
      << table;
  EXPECT_TRUE(absl::StrContains(table.out, "     inf ")) << table;

  const std::string csv = (temp_dir_ / "window.csv").string();
  const ProcessResult written = Ctl({"cost-to-go", "walled", "17", "3", "--window",
                                     "15,2,4,3", "--cost_to_go_file", csv});
  ASSERT_EQ(written.exit_code, 0) << written;
  EXPECT_TRUE(absl::StrContains(written.out, "12 cells written to")) << written;
  std::ifstream in(csv);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    rows.push_back(absl::StrSplit(line, ','));
  }
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& row : rows) ASSERT_EQ(row.size(), 4u);
  EXPECT_EQ(rows[1][2], "0.000000");  // the goal (17,3)
  EXPECT_EQ(rows[0][1], "1.414214");  // (16,2), one diagonal away
  EXPECT_EQ(rows[1][3], "1.000000");  // (18,3)

  // The whole field agrees with A* from a far start.
  const std::string whole = (temp_dir_ / "whole.csv").string();
  ASSERT_EQ(Ctl({"cost-to-go", "walled", "17", "3", "--cost_to_go_file", whole})
                .exit_code,
            0);
  std::ifstream whole_in(whole);
  std::vector<std::vector<std::string>> field;
  for (std::string line; std::getline(whole_in, line);) {
    field.push_back(absl::StrSplit(line, ','));
  }
  ASSERT_EQ(field.size(), 12u);
  double start_cost = 0;
  ASSERT_TRUE(absl::SimpleAtod(field[2][2], &start_cost));
  const v1::PlanResponse astar = PlanJson({"walled", "2", "2", "17", "3"});
  EXPECT_NEAR(start_cost, astar.cost(), 1e-4);  // the field holds floats

  ExpectRpcError({"cost-to-go", "walled", "17", "3", "--window", "18,0,5,5"},
                 "INVALID_ARGUMENT", {"window"});
  ExpectRpcError({"cost-to-go", "walled", "10", "0"}, "INVALID_ARGUMENT",
                 {"goal"});
}

TEST_F(E2eTest, CacheStatsCountSpmHits) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse first =
      PlanJson({"room", "0", "0", "9", "9", "--planner=spm"});
  EXPECT_FALSE(first.cache_hit());
  // Another start, the same goal and cost options: the cached field answers.
  const v1::PlanResponse second =
      PlanJson({"room", "0", "5", "9", "9", "--planner=spm"});
  EXPECT_TRUE(second.cache_hit());
  EXPECT_NEAR(second.cost(), 5 + 4 * kSqrt2, 1e-9);

  const ProcessResult stats = Ctl({"cache-stats", "--json"});
  ASSERT_EQ(stats.exit_code, 0) << stats;
  const auto response = ParseJson<v1::GetCacheStatsResponse>(stats.out);
  const v1::CacheStats* spm = nullptr;
  for (const v1::CacheStats& c : response.caches()) {
    if (c.name() == "spm") spm = &c;
  }
  ASSERT_NE(spm, nullptr) << stats;
  EXPECT_GE(spm->hits(), 1) << stats;
  EXPECT_GE(spm->misses(), 1) << stats;
  EXPECT_GE(spm->entries(), 1) << stats;
  EXPECT_GT(spm->bytes(), 0) << stats;

  const ProcessResult text = Ctl({"cache-stats"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StartsWith(text.out, "CACHE ")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "\nspm ")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "\nsessions:    0 open")) << text;
}

TEST_F(E2eTest, DstarLitePlansFromAMovingStartReuseTheirState) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse first =
      PlanJson({"room", "0", "0", "9", "9", "--planner=dstar_lite"});
  EXPECT_FALSE(first.cache_hit());
  EXPECT_NEAR(first.cost(), 9 * kSqrt2, 1e-9);
  // The robot moved one step along its path.
  const ProcessResult moved =
      Ctl({"plan", "room", "1", "1", "9", "9", "--planner=dstar_lite"});
  ASSERT_EQ(moved.exit_code, 0) << moved;
  EXPECT_TRUE(absl::StrContains(moved.out, "cache hit:   yes\n")) << moved;
  EXPECT_TRUE(absl::StrContains(moved.out, "repaired:    0 cells\n")) << moved;
  EXPECT_TRUE(absl::StrContains(moved.out, "cost:        11.313708")) << moved;
  // Other planners do not claim a cache.
  const ProcessResult astar = Ctl({"plan", "room", "1", "1", "9", "9"});
  EXPECT_FALSE(absl::StrContains(astar.out, "cache hit")) << astar;
}

// Plans a spread of the benchmark's own scenarios on the bundled map and
// checks the optimal lengths it publishes.
TEST_F(E2eTest, Arena2ScenariosHaveTheirOptimalLengths) {
  const std::string source_dir = PATHD_SOURCE_DIR;
  const ProcessResult created = Ctl(
      {"maps", "create", "arena2", "--from", source_dir + "/maps/arena2.map"});
  ASSERT_EQ(created.exit_code, 0) << created;
  EXPECT_TRUE(absl::StrContains(created.out, "281 x 209 cells")) << created;

  const std::vector<std::string> lines =
      absl::StrSplit(ReadFile(source_dir + "/maps/arena2.map.scen"), '\n',
                     absl::SkipWhitespace());
  ASSERT_GT(lines.size(), 100u);
  std::vector<size_t> picks;
  for (size_t i = 1; i < lines.size(); i += 97) picks.push_back(i);
  picks.push_back(lines.size() - 1);  // the longest
  for (size_t i : picks) {
    SCOPED_TRACE(lines[i]);
    // bucket, map, width, height, start x, start y, goal x, goal y, length
    const std::vector<std::string> f =
        absl::StrSplit(lines[i], absl::ByAnyChar(" \t"), absl::SkipEmpty());
    ASSERT_EQ(f.size(), 9u);
    double optimal = 0;
    ASSERT_TRUE(absl::SimpleAtod(f[8], &optimal));
    // Half a unit in the last stored decimal, plus float slack.
    const size_t dot = f[8].find('.');
    const int decimals =
        dot == std::string::npos ? 0 : static_cast<int>(f[8].size() - dot - 1);
    const double tolerance = 0.5 * std::pow(10.0, -decimals) + 1e-6;

    const v1::PlanResponse astar = PlanJson({"arena2", f[4], f[5], f[6], f[7]});
    ASSERT_TRUE(astar.found()) << astar.reason();
    EXPECT_NEAR(astar.length(), optimal, tolerance);
    // Every cell is free or lethal, so cost equals length.
    EXPECT_NEAR(astar.cost(), astar.length(), 1e-6);
    EXPECT_EQ(astar.path(0).x(), std::stoi(f[4]));
    EXPECT_EQ(astar.path(0).y(), std::stoi(f[5]));
    EXPECT_EQ(astar.path(astar.path_size() - 1).x(), std::stoi(f[6]));
    EXPECT_EQ(astar.path(astar.path_size() - 1).y(), std::stoi(f[7]));
  }
  const std::vector<std::string> longest =
      absl::StrSplit(lines.back(), absl::ByAnyChar(" \t"), absl::SkipEmpty());
  const v1::PlanResponse dijkstra =
      PlanJson({"arena2", longest[4], longest[5], longest[6], longest[7],
                "--planner=dijkstra"});
  double optimal = 0;
  ASSERT_TRUE(absl::SimpleAtod(longest[8], &optimal));
  EXPECT_NEAR(dijkstra.length(), optimal, 1e-3);
}

TEST_F(E2eTest, SigtermExitsCleanly) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_EQ(Ctl({"plan", "room", "0", "0", "9", "9"}).exit_code, 0);
  const std::string address = address_;
  EXPECT_EQ(StopDaemon(), 0);
  // With the daemon gone the client reports the transport error, exit 5.
  const ProcessResult r = RunPathctl(
      {absl::StrCat("--server=", address), "--timeout=5s", "maps", "list"});
  EXPECT_EQ(r.exit_code, 5) << r;
  EXPECT_TRUE(absl::StartsWith(r.err, "error: UNAVAILABLE: ")) << r;
}

// Runs pathd with `args` to its exit (a usage error, or --help).
ProcessResult RunPathd(const std::vector<std::string>& args) {
  return PathctlProcess(args, {}, PATHD_BIN).Finish();
}

// The flags `pathd --help` documents, from its "    --name (meaning)" lines.
std::vector<std::string> HelpFlagNames(const std::string& help) {
  std::vector<std::string> names;
  for (absl::string_view line : absl::StrSplit(help, '\n')) {
    if (!absl::ConsumePrefix(&line, "    --")) continue;
    names.emplace_back(line.substr(0, line.find(' ')));
  }
  std::sort(names.begin(), names.end());
  return names;
}

// The keys a config file sets, from its "name: value" lines.
std::vector<std::string> ConfigKeys(const std::string& yaml) {
  std::vector<std::string> keys;
  for (absl::string_view line : absl::StrSplit(yaml, '\n')) {
    if (line.empty() || line[0] == '#') continue;
    keys.emplace_back(line.substr(0, line.find(':')));
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

// The shipped examples/pathd.yaml sets every flag --help documents (but
// --config) to its default, and pathd starts with it.
TEST_F(E2eTest, HelpDocumentsEveryFlagAndTheExampleConfigSetsEach) {
  const ProcessResult help = RunPathd({"--help"});
  const std::vector<std::string> flags = HelpFlagNames(help.out);
  for (const char* flag : {"config", "address", "cache_bytes", "max_sessions",
                           "session_idle_timeout", "shutdown_grace"}) {
    EXPECT_NE(std::find(flags.begin(), flags.end(), flag), flags.end())
        << "--help misses --" << flag << "\n" << help;
  }
  // Each flag's entry ends with its default.
  std::vector<absl::string_view> defaults = absl::StrSplit(help.out, "default: ");
  EXPECT_EQ(defaults.size() - 1, flags.size()) << help;
  EXPECT_TRUE(absl::StrContains(help.out, "a flag given on the command line "
                                          "overrides the file"))
      << help;

  const std::string example =
      absl::StrCat(PATHD_SOURCE_DIR, "/examples/pathd.yaml");
  std::vector<std::string> settable = flags;
  settable.erase(std::find(settable.begin(), settable.end(), "config"));
  EXPECT_EQ(ConfigKeys(ReadFile(example)), settable);

  EXPECT_EQ(StopDaemon(), 0);
  ASSERT_NO_FATAL_FAILURE(StartDaemon({absl::StrCat("--config=", example)}));
  EXPECT_EQ(Ctl({"health"}).out, "SERVING\n");
}

TEST_F(E2eTest, ConfigFileSetsFlagsAndTheCommandLineOverridesIt) {
  // 192.0.2.1 is a documentation address no host has: pathd only starts
  // because StartDaemon's --address=127.0.0.1:0 overrides the file's.
  const std::string config = MapFile(
      "pathd.yaml",
      "address: 192.0.2.1:50051\nmax_expansions: 10\nshutdown_grace: 2s\n");
  EXPECT_EQ(StopDaemon(), 0);
  ASSERT_NO_FATAL_FAILURE(StartDaemon({absl::StrCat("--config=", config)}));
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse limited =
      PlanJson({"room", "0", "0", "9", "9", "--planner=dijkstra"}, 3);
  EXPECT_EQ(limited.outcome(), v1::PLAN_OUTCOME_EXPANSION_LIMIT);
  EXPECT_TRUE(absl::StrContains(limited.reason(), "expansion limit of 10"))
      << limited.reason();

  EXPECT_EQ(StopDaemon(), 0);
  ASSERT_NO_FATAL_FAILURE(StartDaemon(
      {absl::StrCat("--config=", config), "--max_expansions=0"}));
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse found =
      PlanJson({"room", "0", "0", "9", "9", "--planner=dijkstra"});
  EXPECT_TRUE(found.found());
  EXPECT_EQ(PathCells(found).size(), 10u);
}

TEST_F(E2eTest, StartupLineShowsTheEffectiveConfiguration) {
  const std::string config =
      MapFile("pathd.yaml", "max_sessions: 7\nshutdown_grace: 2s\n");
  const std::unique_ptr<e2e::PathdProcess> pathd =
      StartOwnPathd({absl::StrCat("--config=", config), "--shutdown_grace=1s"});
  ASSERT_TRUE(pathd->listening());
  const ProcessResult r = StopOwnPathd(*pathd);
  EXPECT_EQ(r.exit_code, 0) << r;
  const size_t at = r.err.find("pathd starting: ");
  ASSERT_NE(at, std::string::npos) << r;
  const std::string line = r.err.substr(at, r.err.find('\n', at) - at);
  for (const std::string& expected :
       {std::string("max_sessions=7"), std::string("shutdown_grace=1s"),
        std::string("address='127.0.0.1:0'"),
        absl::StrCat("config='", config, "'"), std::string("threads=0"),
        std::string("map_dir=''")}) {
    EXPECT_TRUE(absl::StrContains(line, expected))
        << "missing " << expected << " in\n" << line;
  }
  for (const std::string& flag : HelpFlagNames(RunPathd({"--help"}).out)) {
    EXPECT_TRUE(absl::StrContains(line, absl::StrCat(" ", flag, "=")))
        << "missing --" << flag << " in\n" << line;
  }
}

TEST_F(E2eTest, BadConfigFileExitsTwoNamingFileLineAndKey) {
  struct Case {
    std::string yaml;
    std::string says;  // after "pathd: FILE:"
  };
  const std::vector<Case> cases = {
      {"max_expansions: 10\nthreads: many\n",
       "2: key 'threads': Illegal value 'many' specified for flag 'threads'"},
      {"threads: 2\nworkers: 4\n",
       "2: key 'workers': not a pathd setting; valid keys: address, "},
      {"config: other.yaml\n",
       "1: key 'config': only the command line can name the config file"},
      {"threads: 2\nthreads: 3\n", "2: key 'threads': set twice in this file"},
      {"map_dir: [a, b]\n", "1: key 'map_dir': must be a single value"},
      // Range checks name the file's line too.
      {"threads: 1\nqueue_depth: 0\n", "2: key 'queue_depth': must be >= 1"},
      {"log_level: loud\n", "1: key 'log_level': 'loud' is not one of"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.yaml);
    const std::string config = MapFile("bad.yaml", c.yaml);
    const ProcessResult r =
        RunPathd({"--address=127.0.0.1:0", absl::StrCat("--config=", config)});
    EXPECT_EQ(r.exit_code, 2) << r;
    EXPECT_TRUE(absl::StartsWith(r.err, absl::StrCat("pathd: ", config, ":",
                                                     c.says)))
        << r;
    EXPECT_EQ(r.out, "") << r;
  }
  // A value the command line overrides is not the file's problem.
  const std::string config = MapFile("bad.yaml", "queue_depth: 0\n");
  const ProcessResult overridden =
      RunPathd({"--address=127.0.0.1:0", absl::StrCat("--config=", config),
                "--queue_depth=-1"});
  EXPECT_EQ(overridden.exit_code, 2) << overridden;
  EXPECT_TRUE(absl::StartsWith(overridden.err, "pathd: --queue_depth must be >= 1"))
      << overridden;

  const ProcessResult missing = RunPathd(
      {"--address=127.0.0.1:0", absl::StrCat("--config=", temp_dir_.string(),
                                             "/absent.yaml")});
  EXPECT_EQ(missing.exit_code, 2) << missing;
  EXPECT_TRUE(absl::StrContains(missing.err, "cannot read config file ")) << missing;

  // A stray word (a forgotten "--") is refused rather than ignored.
  const ProcessResult stray = RunPathd({"--address=127.0.0.1:0", "threads=2"});
  EXPECT_EQ(stray.exit_code, 2) << stray;
  EXPECT_TRUE(absl::StrContains(stray.err, "unexpected argument 'threads=2'")) << stray;
}

TEST_F(E2eTest, CheckTellsValidFromInvalidPathsAndExitsFour) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse plan = PlanJson({"room", "0", "0", "9", "9"});
  ASSERT_TRUE(plan.found());
  std::vector<std::string> check = {"check", "room"};
  for (const v1::Cell& c : plan.path()) {
    check.push_back(absl::StrCat(c.x()));
    check.push_back(absl::StrCat(c.y()));
  }
  const ProcessResult valid = Ctl(check);
  ASSERT_EQ(valid.exit_code, 0) << valid;
  EXPECT_TRUE(absl::StrContains(valid.out, "valid:         yes")) << valid;
  EXPECT_TRUE(absl::StrContains(valid.out, "map version:   1")) << valid;
  EXPECT_TRUE(absl::StrContains(valid.out, "poses:         10")) << valid;

  // Block the fourth pose: the same path is now invalid at version 2.
  const v1::Cell blocked = plan.path(3);
  ASSERT_EQ(Ctl({"maps", "set", "room", absl::StrCat(blocked.x()),
                 absl::StrCat(blocked.y()), "lethal"})
                .exit_code,
            0);
  const ProcessResult invalid = Ctl(check);
  EXPECT_EQ(invalid.exit_code, 4) << invalid;
  EXPECT_TRUE(absl::StrContains(invalid.out, "valid:         no")) << invalid;
  EXPECT_TRUE(absl::StrContains(invalid.out, "map version:   2")) << invalid;
  EXPECT_TRUE(absl::StrContains(invalid.out, "invalid poses: 3\n")) << invalid;
  EXPECT_TRUE(absl::StrContains(invalid.out, "reason:        pose 3 (3, 3) is on a "
                                             "blocked cell (cost 254)"))
      << invalid;

  // The same from a file, as JSON; plus a corner cut around the new
  // obstacle and a jump.
  const std::string file = MapFile("path.txt",
                                   "# x y\n"
                                   "2 2\n3 2\n4 3\n\n4 5\n");
  const ProcessResult json = Ctl({"check", "room", "--path_file", file, "--json"});
  EXPECT_EQ(json.exit_code, 4) << json;
  const auto response = ParseJson<v1::IsPathValidResponse>(json.out);
  EXPECT_FALSE(response.valid());
  EXPECT_EQ(response.invalid_indices_size(), 0);
  ASSERT_EQ(response.invalid_steps_size(), 2);
  EXPECT_EQ(response.invalid_steps(0), 2);
  EXPECT_EQ(response.invalid_steps(1), 3);
  EXPECT_EQ(response.map_version(), 2u);

  // An odd number of coordinates is a usage error.
  EXPECT_EQ(Ctl({"check", "room", "1", "2", "3"}).exit_code, 2);
}

TEST_F(E2eTest, GoalToleranceSubstitutesTheNearestFreeCell) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_EQ(Ctl({"maps", "set", "room", "9", "9", "lethal"}).exit_code, 0);
  ExpectRpcError({"plan", "room", "0", "0", "9", "9"}, "INVALID_ARGUMENT",
                 {"goal (9, 9) is on a blocked cell"});
  // (9,8) and (8,9) are both 1 away; the smaller row wins.
  const ProcessResult text =
      Ctl({"plan", "room", "0", "0", "9", "9", "--goal_tolerance", "1.5"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(
      text.out, "goal:        (9,8) (substituted for blocked (9,9))\n"))
      << text;
  const v1::PlanResponse plan = PlanJson(
      {"room", "0", "0", "9", "9", "--goal_tolerance=1.5", "--planner=spm"});
  EXPECT_TRUE(plan.goal_substituted());
  EXPECT_EQ(plan.goal().y(), 8);
  EXPECT_EQ(plan.requested_goal().y(), 9);
  ExpectRpcError({"plan", "room", "0", "0", "9", "9", "--goal_tolerance", "0.5"},
                 "INVALID_ARGUMENT", {"goal tolerance of 0.5 cells"});
}

TEST_F(E2eTest, MetricsCountRequestsAndPathctlPrintsThem) {
  // A daemon of its own, to read its metrics port from its log.
  const std::unique_ptr<e2e::PathdProcess> pathd = StartOwnPathd(
      {"--metrics_address=127.0.0.1:0", "--threads=2", "--log_level=debug"});
  ASSERT_TRUE(pathd->listening());
  constexpr char kMetricsLine[] = "serving Prometheus metrics on http://";
  const std::string metrics_line = pathd->WaitForLogLine({kMetricsLine});
  ASSERT_NE(metrics_line, "") << pathd->Log();
  const size_t at = metrics_line.find(kMetricsLine) + strlen(kMetricsLine);
  const std::string metrics_address =
      metrics_line.substr(at, metrics_line.find("/metrics", at) - at);
  const std::string server = absl::StrCat("--server=", pathd->address());
  const std::string metrics_flag = absl::StrCat("--metrics_address=", metrics_address);

  ASSERT_EQ(RunPathctl({server, "maps", "create", "room", "--from",
                        MapFile("room.map", OpenRoomMap())})
                .exit_code,
            0);
  ASSERT_EQ(RunPathctl({server, "plan", "room", "0", "0", "9", "9"}).exit_code, 0);
  ASSERT_EQ(RunPathctl({server, "plan", "room", "0", "0", "9", "9", "--planner=jps"})
                .exit_code,
            0);
  EXPECT_EQ(RunPathctl({server, "plan", "nowhere", "0", "0", "9", "9"}).exit_code, 7);

  const ProcessResult filtered = RunPathctl(
      {"metrics", metrics_flag, "pathd_requests_total", "pathd_maps"});
  ASSERT_EQ(filtered.exit_code, 0) << filtered;
  for (const char* line : {R"(pathd_requests_total{code="OK",rpc="CreateMap"} 1)",
                           R"(pathd_requests_total{code="OK",rpc="Plan"} 2)",
                           R"(pathd_requests_total{code="NOT_FOUND",rpc="Plan"} 1)",
                           "# TYPE pathd_maps gauge", "pathd_maps 1"}) {
    EXPECT_TRUE(absl::StrContains(filtered.out, absl::StrCat(line, "\n")))
        << "missing " << line << "\n" << filtered;
  }
  // Only the asked-for names.
  EXPECT_FALSE(absl::StrContains(filtered.out, "pathd_cache")) << filtered;

  const ProcessResult all = RunPathctl({"metrics", metrics_flag});
  ASSERT_EQ(all.exit_code, 0) << all;
  for (const char* line :
       {"# TYPE pathd_plan_duration_seconds histogram",
        R"(pathd_plan_duration_seconds_count{planner="jps"} 1)",
        R"(pathd_request_duration_seconds_count{rpc="Plan"} 3)",
        R"(pathd_map_version{map="room"} 1)", "pathd_worker_threads 2"}) {
    EXPECT_TRUE(absl::StrContains(all.out, absl::StrCat(line, "\n")))
        << "missing " << line << "\n" << all;
  }

  const ProcessResult daemon = StopOwnPathd(*pathd);
  EXPECT_EQ(daemon.exit_code, 0) << daemon;
  // The debug request log has one line per request, with its planner.
  EXPECT_TRUE(absl::StrContains(
      daemon.err, "rpc=Plan map=room planner=jps outcome=FOUND status=OK us="))
      << daemon;

  // Nobody serves the endpoint any more.
  const ProcessResult gone = RunPathctl({"metrics", metrics_flag, "--timeout=5s"});
  EXPECT_EQ(gone.exit_code, 5) << gone;
  EXPECT_TRUE(absl::StartsWith(gone.err, "error: UNAVAILABLE: cannot fetch")) << gone;
}

TEST_F(E2eTest, PlanProgressStreamsProgressLinesThenTheSamePlan) {
  EXPECT_EQ(StopDaemon(), 0);
  ASSERT_NO_FATAL_FAILURE(StartDaemon({"--progress_interval=1ms"}));
  // Dijkstra on an open 512 x 512 room: about 260 000 expansions, over 250
  // stop-condition polls, so the 1 ms interval passes many times.
  ASSERT_NO_FATAL_FAILURE(CreateMap("big", OpenRoomMap(512, 512)));
  const std::vector<std::string> plan = {"plan", "big", "0", "0", "511", "300",
                                         "--planner=dijkstra"};
  std::vector<std::string> with_progress = plan;
  with_progress.push_back("--progress");
  const ProcessResult streamed = Ctl(with_progress);
  ASSERT_EQ(streamed.exit_code, 0) << streamed;
  // stderr is a pipe here, not a terminal: one line per event.
  const std::vector<std::string> lines =
      absl::StrSplit(streamed.err, '\n', absl::SkipEmpty());
  ASSERT_FALSE(lines.empty()) << streamed;
  for (const std::string& line : lines) {
    EXPECT_TRUE(absl::StartsWith(line, "progress: ")) << line;
    EXPECT_TRUE(absl::StrContains(line, " expansions, best f ")) << line;
  }
  const ProcessResult unary = Ctl(plan);
  ASSERT_EQ(unary.exit_code, 0) << unary;
  EXPECT_EQ(unary.err, "");
  // The same answer, line for line, except the planning time.
  const auto without_time = [](const std::string& out) {
    std::vector<std::string> kept;
    for (absl::string_view line : absl::StrSplit(out, '\n')) {
      if (!absl::StartsWith(line, "time:")) kept.emplace_back(line);
    }
    return kept;
  };
  EXPECT_EQ(without_time(streamed.out), without_time(unary.out));

  ExpectRpcError({"plan", "big", "0", "0", "600", "0", "--progress"},
                 "INVALID_ARGUMENT",
                 {"goal (600, 0) is outside", "(outcome GOAL_OUTSIDE_MAP)"});
}

TEST_F(E2eTest, BatchAnswersEveryLineAndExitsOneOnItemErrors) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_NO_FATAL_FAILURE(CreateMap("hall", OpenRoomMap(30, 5)));
  ASSERT_EQ(Ctl({"maps", "set", "room", "5", "5", "lethal"}).exit_code, 0);
  const std::string good = MapFile("good.txt",
                                   "# ID MAP SX SY GX GY [PLANNER]\n"
                                   "r1 room 0 0 9 9\n"
                                   "\n"
                                   "h1 hall 0 0 29 4 dijkstra\n"
                                   "r2 room 0 9 9 0 jps\n");
  const ProcessResult ok = Ctl({"batch", good, "--cost_weight", "0"});
  ASSERT_EQ(ok.exit_code, 0) << ok;
  std::vector<std::string> lines = absl::StrSplit(ok.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 4u) << ok;
  std::sort(lines.begin(), lines.end() - 1);
  // 25 straight + 4 diagonal moves; r2 cannot cut the corner at (5,5), so
  // 8 diagonal + 2 straight.
  EXPECT_TRUE(absl::StartsWith(lines[0], "h1 found cost 30.656854 ")) << lines[0];
  EXPECT_TRUE(absl::StartsWith(lines[1], "r1 found cost ")) << lines[1];
  EXPECT_TRUE(absl::StartsWith(lines[2], "r2 found cost 13.313708 ")) << lines[2];
  EXPECT_TRUE(absl::StartsWith(lines[3], "summary: 3 of 3 answered: 3 found, 0 no path, "
                                         "0 errors in "))
      << lines[3];

  const std::string mixed = MapFile("mixed.txt",
                                    "a room 0 0 9 9\n"
                                    "b room 5 5 0 0\n"
                                    "c room 0 0 10 0\n"
                                    "d nowhere 0 0 1 1\n"
                                    "e hall 0 0 29 0\n");
  const ProcessResult r = Ctl({"batch", mixed});
  EXPECT_EQ(r.exit_code, 1) << r;
  lines = absl::StrSplit(r.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 6u) << r;
  std::sort(lines.begin(), lines.end() - 1);
  EXPECT_TRUE(absl::StartsWith(lines[0], "a found ")) << lines[0];
  EXPECT_EQ(lines[1],
            "b error INVALID_ARGUMENT START_OCCUPIED: start (5, 5) is on a blocked "
            "cell (cost 254)");
  EXPECT_EQ(lines[2],
            "c error INVALID_ARGUMENT GOAL_OUTSIDE_MAP: goal (10, 0) is outside the "
            "10 x 10 map");
  EXPECT_TRUE(absl::StartsWith(lines[3], "d error NOT_FOUND MAP_NOT_FOUND: ")) << lines[3];
  EXPECT_TRUE(absl::StartsWith(lines[4], "e found ")) << lines[4];
  EXPECT_TRUE(absl::StartsWith(
      lines[5], "summary: 5 of 5 answered: 2 found, 0 no path, 3 errors in "))
      << lines[5];

  const ProcessResult json = Ctl({"batch", mixed, "--json"});
  EXPECT_EQ(json.exit_code, 1) << json;
  // Only JSON on stdout; the summary goes to stderr.
  lines = absl::StrSplit(json.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 5u) << json;
  EXPECT_TRUE(absl::StartsWith(json.err, "summary: 5 of 5 answered: ")) << json;
  int errors = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto answer = ParseJson<v1::PlanBatchResponse>(lines[i]);
    if (answer.request_id() == "d") {
      EXPECT_EQ(answer.error().outcome(), v1::PLAN_OUTCOME_MAP_NOT_FOUND);
    }
    errors += answer.has_error();
  }
  EXPECT_EQ(errors, 3);

  const std::string malformed = MapFile("bad.txt", "a room 0 0 9 9\nb room 0 x 9 9\n");
  const ProcessResult bad = Ctl({"batch", malformed});
  EXPECT_EQ(bad.exit_code, 2) << bad;
  EXPECT_TRUE(absl::StrContains(bad.err, "bad.txt:2: '0 x' is not two integers")) << bad;
}

// WalledRoomMap with the goal corner (17..19, 0..1) walled off by column 16
// and row 2 there.
std::string PocketRoomMap() {
  std::string text = "type octile\nheight 12\nwidth 20\nmap\n";
  for (int y = 0; y < 12; ++y) {
    std::string row(20, '.');
    if (y < 8 || y > 9) row[10] = '@';
    if (y <= 2) row[16] = '@';
    if (y == 2) row.replace(16, 4, "@@@@");
    text += row + "\n";
  }
  return text;
}

TEST_F(E2eTest, PlanThroughViaPointsWithAllowPartialAndExpansions) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  // Through (12,0) and (5,11): the cost is the sum of the three legs alone.
  const v1::PlanResponse via =
      PlanJson({"walled", "2", "2", "17", "3", "--via", "12,0;5,11"});
  ASSERT_TRUE(via.found());
  EXPECT_EQ(via.reached_goal_index(), 2);
  ASSERT_EQ(via.leg_end_indices_size(), 3);
  EXPECT_EQ(via.path(via.leg_end_indices(0)).x(), 12);
  EXPECT_EQ(via.path(via.leg_end_indices(0)).y(), 0);
  EXPECT_EQ(via.path(via.leg_end_indices(1)).x(), 5);
  EXPECT_EQ(via.path(via.leg_end_indices(1)).y(), 11);
  double legs = 0.0;
  for (const auto& leg : std::vector<std::vector<std::string>>{
           {"2", "2", "12", "0"}, {"12", "0", "5", "11"}, {"5", "11", "17", "3"}}) {
    std::vector<std::string> args = {"walled"};
    args.insert(args.end(), leg.begin(), leg.end());
    args.push_back("--planner=dijkstra");
    legs += PlanJson(args).cost();
  }
  EXPECT_NEAR(via.cost(), legs, 1e-9);
  const ProcessResult text =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--via=12,0;5,11"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "via:         2 points; reached the goal\n"))
      << text;
  EXPECT_TRUE(absl::StrContains(
      text.out, absl::StrFormat("legs end at: path[%d], path[%d], path[%d]\n",
                                via.leg_end_indices(0), via.leg_end_indices(1),
                                via.leg_end_indices(2))))
      << text;

  // The goal in a walled-off corner: the last leg fails.
  ASSERT_NO_FATAL_FAILURE(CreateMap("pocket", PocketRoomMap()));
  const ProcessResult failed =
      Ctl({"plan", "pocket", "2", "2", "18", "0", "--via", "12,5"});
  EXPECT_EQ(failed.exit_code, 3) << failed;
  EXPECT_TRUE(absl::StrContains(
      failed.out,
      "reason:      leg 1 (via[0] -> goal): no path from (12, 5) to (18, 0)\n"))
      << failed;
  EXPECT_FALSE(absl::StrContains(failed.out, "path (")) << failed;
  const ProcessResult partial =
      Ctl({"plan", "pocket", "2", "2", "18", "0", "--via", "12,5", "--allow_partial"});
  EXPECT_EQ(partial.exit_code, 3) << partial;
  EXPECT_TRUE(absl::StrContains(partial.out, "reached via[0] (goal index 0)")) << partial;
  EXPECT_TRUE(absl::StrContains(partial.out, " (12,5)\n")) << partial;
  const v1::PlanResponse partial_json = PlanJson(
      {"pocket", "2", "2", "18", "0", "--via", "12,5", "--allow_partial"}, 3);
  EXPECT_EQ(partial_json.reached_goal_index(), 0);
  EXPECT_EQ(partial_json.outcome(), v1::PLAN_OUTCOME_NO_PATH);

  ExpectRpcError({"plan", "walled", "2", "2", "17", "3", "--via", "1,1;10,0"},
                 "INVALID_ARGUMENT", {"via[1] (10, 0) is on a blocked cell"});
  EXPECT_EQ(Ctl({"plan", "walled", "2", "2", "17", "3", "--via", "1;2"}).exit_code, 2);

  // --expansions: as many cells as expansions, until the server's cap.
  const v1::PlanResponse expanded =
      PlanJson({"walled", "2", "2", "17", "3", "--expansions"});
  EXPECT_GT(expanded.expansions(), 0);
  EXPECT_EQ(expanded.expanded_size(), expanded.expansions());
  const ProcessResult count =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--expansions"});
  EXPECT_TRUE(absl::StrContains(
      count.out, absl::StrFormat("expanded:    %d cells returned\n",
                                 expanded.expansions())))
      << count;
  EXPECT_EQ(StopDaemon(), 0);
  ASSERT_NO_FATAL_FAILURE(StartDaemon({"--max_returned_expansions=5"}));
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const v1::PlanResponse capped =
      PlanJson({"walled", "2", "2", "17", "3", "--expansions"});
  EXPECT_EQ(capped.expanded_size(), 5);
  EXPECT_TRUE(capped.expanded_truncated());
}

// pathctl bench: a one-second closed loop at concurrency 4 against the real
// daemon answers every request (the shape of the report, not its timing),
// and --movingai loads a map and sends exactly its scenarios.
TEST_F(E2eTest, BenchRunsAClosedLoopWithoutErrors) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap(32, 32)));
  const ProcessResult text = Ctl({"bench", "room", "--duration", "1s", "--warmup",
                                  "200ms", "--concurrency", "4", "--planner", "astar"});
  ASSERT_EQ(text.exit_code, 0) << text;
  for (const char* line :
       {"map:         room\n", "planner:     astar\n",
        "queries:     1000 random pairs of free cells\n",
        "load:        4 concurrent requests over 1 channel(s)", "throughput:  ",
        "latency us:  p50 ", "errors:      none\n"}) {
    EXPECT_TRUE(absl::StrContains(text.out, line)) << "missing '" << line << "'\n"
                                                   << text;
  }
  // stderr is a pipe here, not a terminal: no progress line.
  EXPECT_EQ(text.err, "") << text;

  const ProcessResult json = Ctl({"bench", "room", "--duration=1s", "--warmup=0s",
                                  "--concurrency=4", "--channels=2", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json;
  const auto report = ParseJson<google::protobuf::Struct>(json.out);
  const auto& f = report.fields();
  ASSERT_TRUE(f.contains("requests") && f.contains("latency_us")) << json;
  const double requests = f.at("requests").number_value();
  EXPECT_GT(requests, 0) << json;
  EXPECT_EQ(f.at("ok").number_value(), requests) << json;
  EXPECT_EQ(f.at("errors").number_value(), 0) << json;
  EXPECT_EQ(f.at("no_path").number_value(), 0) << json;  // one open room
  EXPECT_TRUE(f.at("errors_by_code").struct_value().fields().empty()) << json;
  EXPECT_EQ(f.at("concurrency").number_value(), 4) << json;
  EXPECT_EQ(f.at("channels").number_value(), 2) << json;
  EXPECT_GT(f.at("requests_per_second").number_value(), 0) << json;
  const auto& latency = f.at("latency_us").struct_value().fields();
  EXPECT_LE(latency.at("min").number_value(), latency.at("p50").number_value());
  EXPECT_LE(latency.at("p50").number_value(), latency.at("p95").number_value());
  EXPECT_LE(latency.at("p95").number_value(), latency.at("p99").number_value());
  EXPECT_LE(latency.at("p99").number_value(), latency.at("max").number_value());

  // --movingai: the map is created under its stem, the queries are its
  // scenarios; --duration 0 --requests 30 sends exactly 30 requests.
  const std::string map = MapFile("open.map", OpenRoomMap());
  WriteFile(map + ".scen",
            "version 1\n"
            "0\topen.map\t10\t10\t0\t0\t9\t9\t12.72792206\n"
            "0\topen.map\t10\t10\t9\t0\t0\t9\t12.72792206\n"
            "0\topen.map\t10\t10\t0\t5\t9\t5\t9.00000000\n");
  const ProcessResult scen =
      Ctl({"bench", "--movingai", map, "--duration=0", "--requests=30", "--json"});
  ASSERT_EQ(scen.exit_code, 0) << scen;
  const auto scen_report = ParseJson<google::protobuf::Struct>(scen.out);
  EXPECT_EQ(scen_report.fields().at("map").string_value(), "open") << scen;
  EXPECT_TRUE(absl::StartsWith(scen_report.fields().at("queries").string_value(),
                               "3 scenarios of "))
      << scen;
  EXPECT_EQ(scen_report.fields().at("requests").number_value(), 30) << scen;
  EXPECT_EQ(scen_report.fields().at("errors").number_value(), 0) << scen;
  EXPECT_EQ(Ctl({"maps", "get", "open"}).exit_code, 0);

  // A map that does not exist fails like any call; bad options are usage.
  ExpectRpcError({"bench", "nope", "--duration=1s"}, "NOT_FOUND");
  EXPECT_EQ(Ctl({"bench"}).exit_code, 2);
  EXPECT_EQ(Ctl({"bench", "room", "--duration=0"}).exit_code, 2);
  EXPECT_EQ(Ctl({"bench", "room", "--concurrency=0"}).exit_code, 2);
  EXPECT_EQ(Ctl({"bench", "room", "--planner=nope"}).exit_code, 2);
}

// --output csv: a header row, then rows, for a single result (maps get), a
// list (maps list), a path (plan), a stream (maps watch, batch) and figures
// (bench, check, cost-to-go).
TEST_F(E2eTest, OutputCsvPrintsAHeaderAndRows) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_NO_FATAL_FAILURE(CreateMap("hall", OpenRoomMap(30, 5)));
  const std::string kMapHeader =
      "name,width,height,resolution,origin_x,origin_y,origin_yaw,version,"
      "free_cells,blocked_cells\n";
  const ProcessResult list = Ctl({"maps", "list", "--output", "csv"});
  ASSERT_EQ(list.exit_code, 0) << list;
  std::vector<std::string> rows = absl::StrSplit(list.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(rows.size(), 3u) << list;
  EXPECT_EQ(rows[0] + "\n", kMapHeader);
  std::sort(rows.begin() + 1, rows.end());
  EXPECT_EQ(rows[1], "hall,30,5,1,0,0,0,1,150,0");
  EXPECT_EQ(rows[2], "room,10,10,1,0,0,0,1,100,0");

  const ProcessResult get = Ctl({"maps", "get", "room", "--output=csv"});
  ASSERT_EQ(get.exit_code, 0) << get;
  EXPECT_EQ(get.out, kMapHeader + "room,10,10,1,0,0,0,1,100,0\n");

  const ProcessResult plan = Ctl({"plan", "room", "0", "0", "3", "3", "--output=csv"});
  ASSERT_EQ(plan.exit_code, 0) << plan;
  EXPECT_EQ(plan.out,
            "x,y,world_x,world_y\n0,0,0.5,0.5\n1,1,1.5,1.5\n2,2,2.5,2.5\n3,3,3.5,3.5\n");
  // No path: the header alone, and the exit code says why.
  ASSERT_EQ(Ctl({"maps", "rect", "room", "0", "5", "9", "5", "lethal"}).exit_code, 0);
  const ProcessResult none = Ctl({"plan", "room", "0", "0", "9", "9", "--output=csv"});
  EXPECT_EQ(none.exit_code, 3) << none;
  EXPECT_EQ(none.out, "x,y,world_x,world_y\n");

  const ProcessResult check =
      Ctl({"check", "room", "0", "0", "1", "1", "--output=csv"});
  ASSERT_EQ(check.exit_code, 0) << check;
  EXPECT_EQ(check.out,
            "valid,map_version,poses,cost,length,invalid_poses,invalid_steps,reason\n"
            "true,2,2,1.41421356,1.41421356,,,\n");

  const ProcessResult field = Ctl(
      {"cost-to-go", "room", "1", "1", "--window", "0,0,2,1", "--output=csv"});
  ASSERT_EQ(field.exit_code, 0) << field;
  EXPECT_EQ(field.out, "x,y,cost\n0,0,1.41421354\n1,0,1\n");

  // A stream: one row per event, the header first.
  std::unique_ptr<PathctlProcess> watch =
      StartCtl({"maps", "watch", "hall", "--output=csv", "--count=2"});
  ASSERT_TRUE(watch->WaitForLine("1,RESYNC,30,5,0,0,")) << watch->Finish();
  ASSERT_EQ(Ctl({"maps", "rect", "hall", "2", "1", "3", "1", "lethal"}).exit_code, 0);
  const ProcessResult events = watch->Finish();
  ASSERT_EQ(events.exit_code, 0) << events;
  EXPECT_EQ(events.out,
            "version,kind,width,height,changed_cells,changed_rects,rects\n"
            "1,RESYNC,30,5,0,0,\n"
            "2,UPDATED,,,2,1,\"(2,1)-(3,1)\"\n");  // quoted: it holds commas

  const std::string items = MapFile("items.txt",
                                    "a hall 0 0 4 0\n"
                                    "b nowhere 0 0 1 1\n");
  const ProcessResult batch = Ctl({"batch", items, "--output=csv"});
  EXPECT_EQ(batch.exit_code, 1) << batch;  // item b errored
  rows = absl::StrSplit(batch.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(rows.size(), 3u) << batch;
  EXPECT_EQ(rows[0], "id,status,outcome,cost,length,expansions,time_us,code,message");
  std::sort(rows.begin() + 1, rows.end());
  EXPECT_TRUE(absl::StartsWith(rows[1], "a,found,FOUND,4,4,")) << rows[1];
  EXPECT_TRUE(absl::StartsWith(rows[2], "b,error,")) << rows[2];
  EXPECT_TRUE(absl::StrContains(rows[2], ",NOT_FOUND,")) << rows[2];
  // The summary is not a row: it goes to stderr.
  EXPECT_TRUE(absl::StartsWith(batch.err, "summary: 2 of 2 answered")) << batch;

  const ProcessResult bench = Ctl({"bench", "hall", "--duration=0", "--requests=20",
                                   "--warmup=0s", "--output=csv"});
  ASSERT_EQ(bench.exit_code, 0) << bench;
  rows = absl::StrSplit(bench.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(rows.size(), 2u) << bench;
  const std::vector<std::string> header = absl::StrSplit(rows[0], ',');
  const std::vector<std::string> figures = absl::StrSplit(rows[1], ',');
  ASSERT_EQ(header.size(), figures.size()) << bench;
  EXPECT_EQ(header[0], "map");
  EXPECT_EQ(figures[0], "hall");
  EXPECT_EQ(header[6], "requests");
  EXPECT_EQ(figures[6], "20");
  EXPECT_EQ(header[9], "errors");
  EXPECT_EQ(figures[9], "0");
}

TEST_F(E2eTest, OutputJsonIsTheJsonAliasAndTableTheDefault) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const ProcessResult alias = Ctl({"plan", "room", "0", "0", "9", "9", "--json"});
  const ProcessResult json = Ctl({"plan", "room", "0", "0", "9", "9", "--output=json"});
  ASSERT_EQ(json.exit_code, 0) << json;
  const v1::PlanResponse a = ParseJson<v1::PlanResponse>(alias.out);
  const v1::PlanResponse j = ParseJson<v1::PlanResponse>(json.out);
  EXPECT_EQ(PathCells(a), PathCells(j));
  EXPECT_EQ(j.cost(), a.cost());
  EXPECT_EQ(Ctl({"maps", "list", "--output", "json"}).out,
            Ctl({"maps", "list", "--json"}).out);

  const ProcessResult table = Ctl({"maps", "list", "--output=table"});
  EXPECT_EQ(table.out, Ctl({"maps", "list"}).out);
  EXPECT_EQ(table.out,
            "NAME  SIZE   RESOLUTION  VERSION  FREE  BLOCKED\n"
            "room  10x10           1        1   100        0\n");
  const ProcessResult health = Ctl({"health", "--output=csv"});
  EXPECT_EQ(health.out, "service,status\n,SERVING\n") << health;
}

TEST_F(E2eTest, FormatsACommandCannotPrintAreUsageErrors) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{"metrics", "--output=json"}, "metrics has no --output json"},
      {{"metrics", "--output=csv"}, "metrics has no --output csv"},
      {{"navigate", "room", "0", "0", "9", "9", "--output=csv"},
       "navigate has no --output csv"},
      {{"maps", "get", "room", "--cells", "--output=csv"},
       "maps get --cells has no --output csv"},
      {{"completion", "bash", "--json"}, "completion has no --output json"},
      {{"maps", "list", "--output=xml"}, "--output: unknown format 'xml'"},
      {{"maps", "list", "--output=csv", "--json"},
       "--json is --output=json; it contradicts --output=csv"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(absl::StrJoin(c.args, " "));
    const ProcessResult r = Ctl(c.args);
    EXPECT_EQ(r.exit_code, 2) << r;
    EXPECT_TRUE(absl::StartsWith(r.err, absl::StrCat("error: ", c.says))) << r;
    EXPECT_EQ(r.out, "") << r;
  }
}

// The exit codes scripts branch on, from real failures: every one is
// documented in --help.
TEST_F(E2eTest, ExitCodesTellScriptsWhatWentWrong) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", OpenRoomMap()));
  ASSERT_EQ(Ctl({"maps", "rect", "walled", "0", "5", "9", "5", "lethal"}).exit_code, 0);
  struct Case {
    std::vector<std::string> args;
    int exit_code;
    std::string stderr_starts;
  };
  const std::vector<Case> cases = {
      {{"plan", "room", "0", "0", "9", "9"}, 0, ""},
      {{"maps", "create", "room", "--from", MapFile("again.map", OpenRoomMap())},
       1, "error: ALREADY_EXISTS: "},
      {{"plan", "room", "0", "0"}, 2, "error: plan takes"},
      {{"plan", "walled", "0", "0", "9", "9"}, 3, ""},
      {{"check", "walled", "0", "4", "0", "5"}, 4, ""},
      // A deadline that has passed before the call is sent.
      {{"plan", "room", "0", "0", "9", "9", "--timeout=1ns"}, 6,
       "error: DEADLINE_EXCEEDED: "},
      {{"plan", "nosuch", "0", "0", "9", "9"}, 7, "error: NOT_FOUND: "},
      // A missing folder is NOT_FOUND naming it, not PERMISSION_DENIED.
      {{"cost-to-go", "room", "1", "1", "--cost_to_go_file",
        (temp_dir_ / "no_such_dir" / "field.csv").string()},
       7, "error: NOT_FOUND: cannot write "},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(absl::StrJoin(c.args, " "));
    const ProcessResult r = Ctl(c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << r;
    EXPECT_TRUE(absl::StartsWith(r.err, c.stderr_starts)) << r;
  }
  // Nobody listens on the daemon's port once it has stopped.
  const std::string address = address_;
  EXPECT_EQ(StopDaemon(), 0);
  const ProcessResult down =
      RunPathctl({absl::StrCat("--server=", address), "--timeout=5s", "health"});
  EXPECT_EQ(down.exit_code, 5) << down;
  EXPECT_TRUE(absl::StartsWith(down.err, "error: UNAVAILABLE: ")) << down;

  const ProcessResult help = RunPathctl({"--help"});
  for (const char* line :
       {"\n  5  UNAVAILABLE", "\n  6  DEADLINE_EXCEEDED", "\n  7  NOT_FOUND",
        "\n  8  UNAUTHENTICATED or PERMISSION_DENIED"}) {
    EXPECT_TRUE(absl::StrContains(help.out, line)) << "missing " << line;
  }
}

// Progress bars are for a person at a terminal: with stdout and stderr piped
// (as here, and in every script) long work draws none.
TEST_F(E2eTest, NoProgressBarsWhenOutputIsNotATerminal) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap(32, 32)));
  std::string items;
  for (int i = 0; i < 200; ++i) {
    absl::StrAppend(&items, "q", i, " room 0 0 ", i % 32, " 31\n");
  }
  const ProcessResult batch = Ctl({"batch", MapFile("many.txt", items)});
  ASSERT_EQ(batch.exit_code, 0) << batch;
  EXPECT_EQ(batch.err, "") << batch;
  EXPECT_FALSE(absl::StrContains(batch.out + batch.err, "\r")) << batch;
  const ProcessResult quiet =
      Ctl({"batch", MapFile("few.txt", "a room 0 0 1 1\n"), "--no_progress"});
  EXPECT_EQ(quiet.exit_code, 0) << quiet;
  EXPECT_EQ(quiet.err, "") << quiet;
}

// Runs `script` in bash after loading pathctl's completion script, with the
// helper `complete_line WORD...` printing the candidates for the last word.
ProcessResult RunCompletion(const std::string& completion_file,
                            const std::string& script) {
  const std::string program = absl::StrCat(
      "source '", completion_file, "'\n",
      "complete_line() {\n"
      "  COMP_WORDS=(\"$@\"); COMP_CWORD=$(( ${#COMP_WORDS[@]} - 1 )); COMPREPLY=()\n"
      "  _pathctl\n"
      "  echo \"${COMPREPLY[*]}\"\n"
      "}\n",
      script);
  return PathctlProcess({"--norc", "--noprofile", "-c", program}, {}, "/bin/bash")
      .Finish();
}

TEST_F(E2eTest, BashCompletionCompletesCommandsFlagsPlannersAndMapNames) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_NO_FATAL_FAILURE(CreateMap("hall", OpenRoomMap(30, 5)));
  const ProcessResult generated = RunPathctl({"completion", "bash"});
  ASSERT_EQ(generated.exit_code, 0) << generated;
  const std::string file = MapFile("pathctl.bash", generated.out);
  const std::string ctl = PATHCTL_BIN;
  const std::string server = absl::StrCat("--server=", address_);
  const ProcessResult r = RunCompletion(
      file, absl::StrCat("complete_line ", ctl, " ''\n",
                         "complete_line ", ctl, " ma\n",
                         "complete_line ", ctl, " maps ''\n",
                         "complete_line ", ctl, " plan room 0 0 9 9 --plann\n",
                         "complete_line ", ctl, " plan room --planner dstar\n",
                         // Bash splits --flag=value at '='.
                         "complete_line ", ctl, " --output = c\n",
                         "complete_line ", ctl, " ", server, " maps get ''\n",
                         "complete_line ", ctl, " ", server, " --json plan h\n",
                         // An unreachable server completes no map names.
                         "complete_line ", ctl, " --server=127.0.0.1:1 plan ''\n",
                         "complete_line ", ctl, " completion ''\n"));
  ASSERT_EQ(r.exit_code, 0) << r;
  const std::vector<std::string> lines = absl::StrSplit(r.out, '\n');
  ASSERT_GE(lines.size(), 10u) << r;
  EXPECT_EQ(lines[0],
            "maps plan batch navigate cost-to-go check cache-stats health metrics "
            "bench render completion help");
  EXPECT_EQ(lines[1], "maps");
  EXPECT_EQ(lines[2], "create list get delete set rect watch import export");
  EXPECT_EQ(lines[3], "--planner");
  EXPECT_EQ(lines[4], "dstar_lite");
  EXPECT_EQ(lines[5], "csv");
  std::vector<std::string> names = absl::StrSplit(lines[6], ' ');
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"hall", "room"})) << r;
  EXPECT_EQ(lines[7], "hall");
  EXPECT_EQ(lines[8], "");
  EXPECT_EQ(lines[9], "bash");
}

// The cell glyphs of `maps get --cells` output (the lines after the blank
// line that ends the map's info).
std::string CellsText(const ProcessResult& r) {
  const size_t blank = r.out.find("\n\n");
  return blank == std::string::npos ? "" : r.out.substr(blank + 2);
}

// pathctl render: a plan drawn into a PNG that decodes to the map's size at
// the default scale with the path, markers and expanded cells in their
// colours; the same as text; no path still draws the map and exits 3.
TEST_F(E2eTest, RenderDrawsAPlanAsPngAndAsText) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const std::string png = (temp_dir_ / "walled.png").string();
  const ProcessResult r = Ctl({"render", "walled", "--plan", "2", "2", "17",
                               "3", "--expansions", "-o", png});
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(absl::StrContains(
      r.out, absl::StrCat("wrote ", png, " (320x192 pixels, 16 per cell)\n")))
      << r;
  EXPECT_TRUE(absl::StrContains(r.out, "path (astar): ")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "expanded cells drawn")) << r;

  const absl::StatusOr<pathctl::Image> image =
      pathctl::DecodePngRgba(ReadFile(png), png, int64_t{1} << 24);
  ASSERT_TRUE(image.ok()) << image.status();
  ASSERT_EQ(image->width, 20 * 16);
  ASSERT_EQ(image->height, 12 * 16);
  const auto pixel = [&](int x, int y) {
    const size_t i = (static_cast<size_t>(y) * image->width + x) * 4;
    return pathctl::Rgb{image->pixels[i], image->pixels[i + 1],
                        image->pixels[i + 2]};
  };
  int64_t path_pixels = 0, expanded_pixels = 0;
  const pathctl::Rgb expanded_free = {255, 213, 128};
  for (int y = 0; y < image->height; ++y) {
    for (int x = 0; x < image->width; ++x) {
      path_pixels += pixel(x, y) == pathctl::kPathColour;
      expanded_pixels += pixel(x, y) == expanded_free;
    }
  }
  EXPECT_GT(path_pixels, 16 * 15) << "the path spans at least 15 cells";
  EXPECT_GT(expanded_pixels, 0);
  EXPECT_EQ(pixel(2 * 16 + 8, 2 * 16 + 8), pathctl::kStartColour);
  EXPECT_EQ(pixel(17 * 16 + 8, 3 * 16 + 8), pathctl::kGoalColour);
  EXPECT_EQ(pixel(10 * 16, 0), pathctl::kLethalColour);  // the wall at (10,0)

  // Text: the same plan's cells, start and goal.
  const v1::PlanResponse plan = PlanJson({"walled", "2", "2", "17", "3"});
  const ProcessResult text =
      Ctl({"render", "walled", "2", "2", "17", "3", "--ascii"});
  ASSERT_EQ(text.exit_code, 0) << text;
  const std::vector<std::string> lines = absl::StrSplit(text.out, '\n');
  ASSERT_GE(lines.size(), 12u) << text;
  EXPECT_EQ(lines[2][2], 'S') << text;
  EXPECT_EQ(lines[3][17], 'G') << text;
  EXPECT_EQ(lines[0][10], '#') << text;
  int64_t stars = 0;
  for (int y = 0; y < 12; ++y)
    stars += std::count(lines[y].begin(), lines[y].end(), '*');
  EXPECT_EQ(stars, plan.path_size() - 2) << text;

  // The map alone, and a plan with no path: the map is still drawn.
  const ProcessResult map_only = Ctl({"render", "walled", "--ascii"});
  ASSERT_EQ(map_only.exit_code, 0) << map_only;
  EXPECT_TRUE(absl::StartsWith(map_only.out, "..........#.........\n"))
      << map_only;
  ASSERT_NO_FATAL_FAILURE(CreateMap("pocket", PocketRoomMap()));
  const std::string pocket_png = (temp_dir_ / "pocket.png").string();
  const ProcessResult none = Ctl(
      {"render", "pocket", "--plan", "2", "2", "18", "0", "-o", pocket_png});
  EXPECT_EQ(none.exit_code, 3) << none;
  EXPECT_TRUE(absl::StrContains(none.out, "no path (astar): NO_PATH")) << none;
  EXPECT_TRUE(fs::exists(pocket_png));

  // Usage errors exit 2; a missing map is the server's NOT_FOUND.
  for (const std::vector<std::string>& args :
       std::vector<std::vector<std::string>>{
           {"render", "walled"},
           {"render", "walled", "--plan", "--ascii"},
           {"render", "walled", "--expansions", "--ascii"},
           {"render", "walled", "-o", "walled.jpg"},
           {"render", "walled", "--ascii", "-o", png, "--scale", "65"},
           {"render", "walled", "2", "2", "17", "--ascii"},
           {"render", "walled", "2", "2", "17", "3", "--ascii",
            "--planner=nope"}}) {
    EXPECT_EQ(Ctl(args).exit_code, 2) << absl::StrJoin(args, " ");
  }
  ExpectRpcError({"render", "nope", "--ascii"}, "NOT_FOUND", {"nope"});
}

// maps import / export through the server: the bundled ROS map exported as
// YAML + PGM and imported again has the same cells; as a .map its unknown
// cells become blocked (with a warning); a PNG occupancy image imports with
// map_server's thresholds.
TEST_F(E2eTest, MapsImportAndExportRoundTrip) {
  const std::string warehouse =
      absl::StrCat(PATHD_SOURCE_DIR, "/maps/warehouse.yaml");
  const ProcessResult imported = Ctl({"maps", "import", "wh", warehouse});
  ASSERT_EQ(imported.exit_code, 0) << imported;
  EXPECT_TRUE(absl::StartsWith(imported.out, "created map wh from "))
      << imported;
  const std::string original = CellsText(Ctl({"maps", "get", "wh", "--cells"}));
  ASSERT_FALSE(original.empty());

  const std::string yaml = (temp_dir_ / "out" / "wh.yaml").string();
  fs::create_directories(temp_dir_ / "out");
  const ProcessResult exported = Ctl({"maps", "export", "wh", yaml});
  ASSERT_EQ(exported.exit_code, 0) << exported;
  EXPECT_EQ(exported.err, "") << exported;
  EXPECT_TRUE(fs::exists(temp_dir_ / "out" / "wh.pgm"));
  ASSERT_EQ(Ctl({"maps", "import", "wh_yaml", yaml}).exit_code, 0);
  EXPECT_EQ(CellsText(Ctl({"maps", "get", "wh_yaml", "--cells"})), original);
  const auto info = ParseJson<v1::GetMapResponse>(
                        Ctl({"maps", "get", "wh_yaml", "--json"}).out)
                        .info();
  EXPECT_DOUBLE_EQ(info.resolution(), 0.1);
  EXPECT_DOUBLE_EQ(info.origin().x(), -3.0);
  EXPECT_DOUBLE_EQ(info.origin().y(), -2.0);

  const std::string map = (temp_dir_ / "out" / "wh.map").string();
  const ProcessResult as_map = Ctl({"maps", "export", "wh", map});
  ASSERT_EQ(as_map.exit_code, 0) << as_map;
  EXPECT_TRUE(absl::StrContains(as_map.err, "unknown (255) written as 'O'"))
      << as_map;
  ASSERT_EQ(Ctl({"maps", "import", "wh_map", map}).exit_code, 0);
  std::string blocked = original;
  std::replace(blocked.begin(), blocked.end(), '?', '#');
  EXPECT_EQ(CellsText(Ctl({"maps", "get", "wh_map", "--cells"})), blocked);

  // A picture of the map at one pixel per cell, rows as map_server's, is an
  // occupancy image of the same cells.
  const std::string picture_png = (temp_dir_ / "out" / "wh_map.png").string();
  ASSERT_EQ(
      Ctl({"render", "wh", "--scale=1", "--y_up", "-o", picture_png}).exit_code,
      0);
  ASSERT_EQ(Ctl({"maps", "import", "wh_png", picture_png}).exit_code, 0);
  EXPECT_EQ(CellsText(Ctl({"maps", "get", "wh_png", "--cells"})), original);

  // A weighted cell is written as passable, and said so.
  ASSERT_EQ(Ctl({"maps", "set", "wh", "5", "5", "100"}).exit_code, 0);
  const ProcessResult weighted = Ctl({"maps", "export", "wh", yaml});
  ASSERT_EQ(weighted.exit_code, 0) << weighted;
  EXPECT_TRUE(absl::StrContains(weighted.err, "warning: 1 cell of cost 1..252"))
      << weighted;

  // A 3x2 PNG: black, white, grey (205) over white, white, black.
  pathctl::Image picture;
  picture.width = 3;
  picture.height = 2;
  picture.pixels = {0,   0,   0,   255, 255, 255, 205, 205, 205,
                    255, 255, 255, 255, 255, 255, 0,   0,   0};
  const std::string png = (temp_dir_ / "room.png").string();
  ASSERT_TRUE(pathctl::WritePngFile(picture, png).ok());
  const ProcessResult from_png =
      Ctl({"maps", "import", "room", png, "--resolution", "0.5", "--json"});
  ASSERT_EQ(from_png.exit_code, 0) << from_png;
  EXPECT_DOUBLE_EQ(
      ParseJson<v1::CreateMapResponse>(from_png.out).info().resolution(), 0.5);
  // Row 0 is the image's bottom row.
  EXPECT_EQ(CellsText(Ctl({"maps", "get", "room", "--cells"})), "..#\n#.?\n");
  ASSERT_EQ(
      Ctl({"maps", "import", "room", png, "--replace", "--negate"}).exit_code,
      0);
  // Negated, grey 205 is p = 0.80: occupied.
  EXPECT_EQ(CellsText(Ctl({"maps", "get", "room", "--cells"})), "##.\n.##\n");

  EXPECT_EQ(
      Ctl({"maps", "import", "x", map, "--occupied_thresh=0.5"}).exit_code, 2);
  EXPECT_EQ(Ctl({"maps", "import", "x", yaml, "--resolution=2"}).exit_code, 2);
  EXPECT_EQ(Ctl({"maps", "import", "x", png, "--free_thresh=0.7"}).exit_code,
            2);
  EXPECT_EQ(Ctl({"maps", "import", "x", "room.bmp"}).exit_code, 2);
  EXPECT_EQ(Ctl({"maps", "export", "wh", "wh.png"}).exit_code, 2);
  ExpectRpcError({"maps", "import", "x", (temp_dir_ / "missing.png").string()},
                 "NOT_FOUND", {"missing.png"});
  ExpectRpcError({"maps", "export", "nope", yaml}, "NOT_FOUND", {"nope"});
}

// pathd with TLS and --auth_tokens, driven by pathctl with --tls_ca and
// --token_file / $PATHD_TOKEN; the daemon's whole log (trace level) is
// captured and must not contain a token.
TEST_F(E2eTest, TlsAndTokensThroughPathctl) {
  const fs::path cert_dir = temp_dir_ / "certs";
  fs::create_directory(cert_dir);
  testing::TestCerts certs;
  ASSERT_TRUE(testing::MakeTestCerts(cert_dir, &certs))
      << "the openssl tool failed (is Debian's openssl package installed?)";
  const std::string read_token(64, 'r');
  const std::string write_token = "w0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcd";
  const fs::path tokens = temp_dir_ / "tokens.yaml";
  WriteFile(tokens, absl::StrCat("tokens:\n  - {name: robot-7, role: read, token: ",
                                 read_token, "}\n  - {name: mapper, role: write, token: ",
                                 write_token, "}\n"));
  fs::permissions(tokens, fs::perms::owner_read | fs::perms::owner_write);
  const fs::path read_file = temp_dir_ / "read.token";
  const fs::path write_file = temp_dir_ / "write.token";
  WriteFile(read_file, read_token + "\n");
  WriteFile(write_file, write_token + "\n");

  const std::unique_ptr<e2e::PathdProcess> daemon = StartOwnPathd(
      {"--tls_cert=" + certs.server_cert, "--tls_key=" + certs.server_key,
       "--auth_tokens=" + tokens.string(), "--log_level=trace"});
  ASSERT_TRUE(daemon->listening());
  const std::string server = "--server=" + daemon->address();
  const std::string tls = "--tls_ca=" + certs.ca;

  const std::string map = MapFile("room.map", OpenRoomMap());
  ProcessResult r = RunPathctl({server, tls, "--token_file=" + write_file.string(),
                                "maps", "create", "room", "--from", map});
  ASSERT_EQ(r.exit_code, 0) << r;
  r = RunPathctl({server, tls, "--token_file=" + read_file.string(), "plan", "room",
                  "0", "0", "9", "9"});
  EXPECT_EQ(r.exit_code, 0) << r;
  EXPECT_EQ(r.err, "") << r;
  r = RunPathctl({server, tls, "--token_file=" + read_file.string(), "maps", "set",
                  "room", "5", "5", "lethal"});
  EXPECT_EQ(r.exit_code, 8) << r;
  EXPECT_EQ(r.err,
            "error: PERMISSION_DENIED: token 'robot-7' has role read; "
            "/pathd.v1.MapService/UpdateMap needs role write\n");
  // The token from the environment.
  r = RunPathctl({server, tls, "maps", "set", "room", "5", "5", "lethal"},
                 {"PATHD_TOKEN=" + write_token});
  EXPECT_EQ(r.exit_code, 0) << r;
  r = RunPathctl({server, tls, "maps", "list"});
  EXPECT_EQ(r.exit_code, 8) << r;
  EXPECT_TRUE(absl::StartsWith(r.err, "error: UNAUTHENTICATED: missing")) << r;
  r = RunPathctl({server, tls, "--token=" + std::string(64, 'x'), "maps", "list"});
  EXPECT_EQ(r.err, "error: UNAUTHENTICATED: unknown token\n") << r;
  // Health needs no token; plaintext cannot reach a TLS server.
  r = RunPathctl({server, tls, "health"});
  EXPECT_EQ(r.out, "SERVING\n") << r;
  r = RunPathctl({server, "--token_file=" + read_file.string(), "health"});
  EXPECT_EQ(r.exit_code, 5) << r;
  EXPECT_TRUE(absl::StartsWith(r.err, "error: UNAVAILABLE")) << r;
  // gRPC only says "Socket closed"; pathctl suggests what is missing.
  EXPECT_TRUE(absl::StrContains(r.err, "\nhint: ")) << r;
  EXPECT_TRUE(absl::StrContains(r.err, "give --tls_ca FILE")) << r;
  // Flag mistakes are usage errors.
  r = RunPathctl({server, tls, "--tls_cert=" + certs.client_cert, "health"});
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(absl::StrContains(r.err, "--tls_cert and --tls_key must be given together"))
      << r;
  r = RunPathctl({server, "--token_file=" + (temp_dir_ / "none").string(), "health"});
  EXPECT_EQ(r.exit_code, 7) << r;
  EXPECT_TRUE(absl::StrContains(r.err, "--token_file: cannot open")) << r;

  const ProcessResult log = StopOwnPathd(*daemon);
  EXPECT_EQ(log.exit_code, 0) << log;
  EXPECT_TRUE(absl::StrContains(log.err, "transport: TLS; authentication: bearer tokens"))
      << log.err;
  EXPECT_TRUE(absl::StrContains(log.err, "refused UpdateMap")) << log.err;
  EXPECT_TRUE(absl::StrContains(log.err, "rpc=UpdateMap map=room")) << log.err;
  for (const std::string& token : {read_token, write_token}) {
    EXPECT_FALSE(absl::StrContains(log.err, token)) << "a token is in pathd's log";
  }
}

// pathctl help CMD, CMD --help and --version: generated from the command
// table, with the flags the command reads.
TEST_F(E2eTest, HelpForOneCommandAndVersion) {
  const ProcessResult help = RunPathctl({"help", "maps", "rect"});
  EXPECT_EQ(help.exit_code, 0) << help;
  EXPECT_TRUE(absl::StartsWith(
      help.out, "usage: pathctl [flags] maps rect NAME X0 Y0 X1 Y1 COST"))
      << help;
  EXPECT_TRUE(absl::StrContains(help.out, "--expected_version")) << help;
  EXPECT_FALSE(absl::StrContains(help.out, "--planner")) << help;
  const ProcessResult same = RunPathctl({"maps", "rect", "--help"});
  EXPECT_EQ(same.exit_code, 0) << same;
  EXPECT_EQ(same.out, help.out);
  const ProcessResult group = RunPathctl({"help", "maps"});
  EXPECT_EQ(group.exit_code, 0) << group;
  EXPECT_TRUE(absl::StrContains(group.out, "maps watch NAME")) << group;
  const ProcessResult unknown = RunPathctl({"help", "frobnicate"});
  EXPECT_EQ(unknown.exit_code, 2) << unknown;
  EXPECT_TRUE(absl::StrContains(unknown.err, "unknown command 'frobnicate'")) << unknown;
  const ProcessResult version = RunPathctl({"--version"});
  EXPECT_EQ(version.exit_code, 0) << version;
  EXPECT_TRUE(absl::StartsWith(version.out, "pathctl ")) << version;
  EXPECT_TRUE(absl::StrContains(version.out, ".")) << version;
}

// Regression (a 100 KiB name failed with gRPC's metadata-size error): map
// names are checked in pathctl by the server's rule and message before they
// go into the routing header; the server never sees the call.
TEST_F(E2eTest, MapNamesAreCheckedBeforeTheHeader) {
  const std::string map = MapFile("room.map", OpenRoomMap());
  const ProcessResult huge =
      Ctl({"maps", "create", std::string(100 * 1024, 'a'), "--from", map});
  EXPECT_EQ(huge.exit_code, 1) << huge.err.substr(0, 300);
  EXPECT_EQ(huge.err,
            "error: INVALID_ARGUMENT: map name is 102400 characters long; the "
            "limit is 128\n");
  const ProcessResult slash = Ctl({"plan", "a/b", "0", "0", "1", "1"});
  EXPECT_EQ(slash.exit_code, 1) << slash;
  EXPECT_TRUE(absl::StartsWith(
      slash.err, "error: INVALID_ARGUMENT: map name 'a/b' has character 0x2f"))
      << slash;
  const ProcessResult batch =
      Ctl({"batch", MapFile("bad.txt", "q1 .hidden 0 0 1 1\n")});
  EXPECT_EQ(batch.exit_code, 2) << batch;
  EXPECT_TRUE(absl::StrContains(batch.err, "must not start with '.'")) << batch;
}

// Regression: maps rect swapped inverted corners that the API refuses; now it
// refuses them with the server's message and the map keeps its version.
TEST_F(E2eTest, MapsRectRefusesInvertedCorners) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const ProcessResult r = Ctl({"maps", "rect", "room", "9", "5", "0", "5", "lethal"});
  EXPECT_EQ(r.exit_code, 1) << r;
  EXPECT_EQ(r.err, "error: INVALID_ARGUMENT: change 0: rect (9, 5)-(0, 5) has min > max\n");
  const ProcessResult info = Ctl({"maps", "get", "room", "--output=csv"});
  EXPECT_TRUE(absl::StrContains(info.out, ",1,100,0\n")) << info;  // version 1
}

// Regression: a missing export folder was reported as PERMISSION_DENIED.
TEST_F(E2eTest, ExportToAMissingFolderIsNotFoundNamingIt) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const std::string folder = (temp_dir_ / "no" / "such" / "dir").string();
  ExpectRpcError({"maps", "export", "room", folder + "/x.map"}, "NOT_FOUND",
                 {"folder " + folder + " does not exist"});
}

}  // namespace
}  // namespace pathd
