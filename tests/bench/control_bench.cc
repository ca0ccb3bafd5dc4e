// Control-cycle latency through gRPC (issue 20): starts the real pathd on
// loopback (--threads=W), makes a 25.6 x 25.6 m map (256 x 256 cells of 0.1 m
// with rows of shelves), opens N control sessions on it, and drives each
// robot from its own client thread: send the state, read the command, move
// the robot by the command for one control period (a unicycle integrated
// here), wait for the next period. Prints per N the round-trip latency of
// each state message (p50, p99, max), the messages per second, and the
// daemon's CPU use (from /proc) over the measured window.
//
//   control_bench [--robots 10,50,200] [--seconds 10] [--threads 2]
//                 [--planner orca|dwa|firas] [--lockstep]
//
// --lockstep sends the next state as soon as the answer came (no period
// wait): the daemon's throughput, not a fleet's real load.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "tests/testing/pathd_process.h"

ABSL_FLAG(std::string, robots, "10,50,200", "robot counts, comma-separated");
ABSL_FLAG(int, seconds, 10, "measured seconds per robot count (after 1 s of warm-up)");
ABSL_FLAG(int, threads, 2, "pathd --threads");
ABSL_FLAG(std::string, planner, "orca", "local planner: orca, dwa or firas");
ABSL_FLAG(bool, lockstep, false, "send states as fast as answers come");

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kSize = 256;
constexpr double kRes = 0.1;
constexpr double kPeriod = 0.1;

std::string MapCells() {
  std::string cells(kSize * kSize, '\0');
  // Shelves: 1 m x 8 m blocks in rows, 2 m aisles between them.
  for (int y = 20; y < kSize - 20; ++y) {
    if ((y - 20) % 100 >= 80) continue;
    for (int x = 20; x < kSize - 20; ++x) {
      if ((x - 20) % 30 < 10) cells[static_cast<size_t>(y) * kSize + x] = static_cast<char>(254);
    }
  }
  return cells;
}

bool Free(const std::string& cells, double x, double y, double margin) {
  for (double dy = -margin; dy <= margin; dy += kRes) {
    for (double dx = -margin; dx <= margin; dx += kRes) {
      const int cx = static_cast<int>((x + dx) / kRes), cy = static_cast<int>((y + dy) / kRes);
      if (cx < 0 || cy < 0 || cx >= kSize || cy >= kSize) return false;
      if (cells[static_cast<size_t>(cy) * kSize + cx] != 0) return false;
    }
  }
  return true;
}

double CpuSeconds(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(stat, line);
  // Fields after the command's closing parenthesis; utime and stime are the
  // 14th and 15th of the whole line.
  const size_t close = line.rfind(')');
  std::vector<std::string> fields = absl::StrSplit(line.substr(close + 2), ' ');
  double utime = 0, stime = 0;
  if (fields.size() > 12 && absl::SimpleAtod(fields[11], &utime) &&
      absl::SimpleAtod(fields[12], &stime)) {
    return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
  }
  return 0;
}

double Percentile(std::vector<double>& v, double p) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

pathd::v1::LocalPlanner PlannerFlag() {
  const std::string name = absl::GetFlag(FLAGS_planner);
  if (name == "dwa") return pathd::v1::LOCAL_PLANNER_DWA;
  if (name == "firas") return pathd::v1::LOCAL_PLANNER_FIRAS;
  return pathd::v1::LOCAL_PLANNER_ORCA;
}

struct Robot {
  double x, y, yaw, gx, gy;
};

// One robot's loop; returns its latencies (seconds) after `measure_from`.
void Drive(pathd::v1::PlannerService::Stub* stub, Robot robot, Clock::time_point measure_from,
           Clock::time_point until, std::vector<double>* latencies, std::atomic<int>* errors) {
  grpc::ClientContext context;
  auto stream = stub->Navigate(&context);
  pathd::v1::NavigateRequest open;
  open.set_seq(1);
  pathd::v1::NavigateOpen* o = open.mutable_open();
  o->set_map("bench");
  o->mutable_start()->mutable_world()->set_x(robot.x);
  o->mutable_start()->mutable_world()->set_y(robot.y);
  o->mutable_goal()->mutable_world()->set_x(robot.gx);
  o->mutable_goal()->mutable_world()->set_y(robot.gy);
  o->mutable_options()->set_robot_radius_m(0.25);
  o->mutable_control()->set_local_planner(PlannerFlag());
  o->mutable_control()->set_control_period(kPeriod);
  pathd::v1::NavigateResponse response;
  if (!stream->Write(open) || !stream->Read(&response)) {
    ++*errors;
    return;
  }
  double v = 0, w = 0;
  uint64_t seq = 1;
  Clock::time_point next = Clock::now();
  while (Clock::now() < until) {
    pathd::v1::NavigateRequest state;
    state.set_seq(++seq);
    auto* pose = state.mutable_state()->mutable_pose()->mutable_world_pose();
    pose->set_x(robot.x);
    pose->set_y(robot.y);
    pose->set_yaw(robot.yaw);
    state.mutable_state()->set_v(v);
    state.mutable_state()->set_w(w);
    const Clock::time_point sent = Clock::now();
    if (!stream->Write(state) || !stream->Read(&response)) {
      ++*errors;
      return;
    }
    const Clock::time_point answered = Clock::now();
    if (sent >= measure_from) {
      latencies->push_back(std::chrono::duration<double>(answered - sent).count());
    }
    v = response.command().v();
    w = response.command().w();
    for (int i = 0; i < 10; ++i) {
      const double h = kPeriod / 10;
      robot.x += v * std::cos(robot.yaw + w * h / 2) * h;
      robot.y += v * std::sin(robot.yaw + w * h / 2) * h;
      robot.yaw += w * h;
    }
    if (!absl::GetFlag(FLAGS_lockstep)) {
      next += std::chrono::milliseconds(static_cast<int>(kPeriod * 1000));
      std::this_thread::sleep_until(next);
    }
  }
  stream->WritesDone();
  while (stream->Read(&response)) {
  }
  stream->Finish();
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage("control-cycle latency of N control sessions through gRPC");
  absl::ParseCommandLine(argc, argv);
  std::vector<int> counts;
  for (absl::string_view part : absl::StrSplit(absl::GetFlag(FLAGS_robots), ',')) {
    int n = 0;
    if (!absl::SimpleAtoi(part, &n) || n < 1) {
      std::fprintf(stderr, "--robots: bad count '%s'\n", std::string(part).c_str());
      return 2;
    }
    counts.push_back(n);
  }
  pathd::testing::PathdProcess daemon(pathd::testing::PathdProcessOptions{
      .binary = PATHD_BIN,
      .flags = {absl::StrCat("--threads=", absl::GetFlag(FLAGS_threads)), "--log_level=warn",
                "--max_sessions=4096"}});
  if (!daemon.listening()) {
    std::fprintf(stderr, "pathd did not start: %s\n", daemon.status().ToString().c_str());
    return 1;
  }
  auto channel = grpc::CreateChannel(daemon.address(), grpc::InsecureChannelCredentials());
  auto maps = pathd::v1::MapService::NewStub(channel);
  auto planner = pathd::v1::PlannerService::NewStub(channel);
  const std::string cells = MapCells();
  {
    pathd::v1::CreateMapRequest create;
    create.set_name("bench");
    create.mutable_raw()->set_width(kSize);
    create.mutable_raw()->set_height(kSize);
    create.mutable_raw()->set_cells(cells);
    create.set_resolution(kRes);
    pathd::v1::CreateMapResponse created;
    grpc::ClientContext context;
    const grpc::Status status = maps->CreateMap(&context, create, &created);
    if (!status.ok()) {
      std::fprintf(stderr, "CreateMap: %s\n", status.error_message().c_str());
      return 1;
    }
  }
  std::printf("control_bench: %u hardware threads; pathd --threads=%d; planner %s; %s; "
              "map 256 x 256 cells of 0.1 m with shelves; robot radius 0.25 m, "
              "period %.2f s\n\n",
              std::thread::hardware_concurrency(), absl::GetFlag(FLAGS_threads),
              absl::GetFlag(FLAGS_planner).c_str(),
              absl::GetFlag(FLAGS_lockstep) ? "lock-step" : "states at the period",
              kPeriod);
  std::printf("| robots | messages/s | p50 ms | p99 ms | max ms | pathd CPU (cores) | errors |\n");
  std::printf("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  std::mt19937 rng(20);
  std::uniform_real_distribution<double> coord(0.5, kSize * kRes - 0.5);
  for (int n : counts) {
    std::vector<Robot> robots;
    while (static_cast<int>(robots.size()) < n) {
      Robot r{coord(rng), coord(rng), 0, coord(rng), coord(rng)};
      r.yaw = std::atan2(r.gy - r.y, r.gx - r.x);
      if (!Free(cells, r.x, r.y, 0.4) || !Free(cells, r.gx, r.gy, 0.4)) continue;
      if (std::hypot(r.gx - r.x, r.gy - r.y) < 10) continue;
      bool apart = true;
      for (const Robot& o : robots) apart = apart && std::hypot(o.x - r.x, o.y - r.y) > 0.8;
      if (apart) robots.push_back(r);
    }
    const Clock::time_point start = Clock::now();
    const Clock::time_point measure_from = start + std::chrono::seconds(1);
    const Clock::time_point until = measure_from + std::chrono::seconds(absl::GetFlag(FLAGS_seconds));
    std::vector<std::vector<double>> latencies(static_cast<size_t>(n));
    std::atomic<int> errors{0};
    std::vector<std::thread> threads;
    for (int i = 0; i < n; ++i) {
      threads.emplace_back(Drive, planner.get(), robots[static_cast<size_t>(i)], measure_from, until,
                           &latencies[static_cast<size_t>(i)], &errors);
    }
    std::this_thread::sleep_until(measure_from);
    const double cpu_before = CpuSeconds(daemon.pid());
    std::this_thread::sleep_until(until);
    const double cpu_after = CpuSeconds(daemon.pid());
    for (std::thread& t : threads) t.join();
    std::vector<double> all;
    for (const auto& v : latencies) all.insert(all.end(), v.begin(), v.end());
    const double seconds = absl::GetFlag(FLAGS_seconds);
    const double max = all.empty() ? 0 : *std::max_element(all.begin(), all.end());
    const double rate = static_cast<double>(all.size()) / seconds;
    const double p50 = Percentile(all, 0.50);
    const double p99 = Percentile(all, 0.99);
    std::printf("| %d | %.0f | %.3f | %.3f | %.3f | %.2f | %d |\n", n, rate, p50 * 1e3,
                p99 * 1e3, max * 1e3, (cpu_after - cpu_before) / seconds, errors.load());
    std::fflush(stdout);
  }
  return 0;
}
