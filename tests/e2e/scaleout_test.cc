// Scale-out on loopback: the topology of docker/compose.yaml (three pathd
// replicas behind nginx routing by the x-pathd-map header) run as plain
// processes, with nginx's configuration rendered from the same template
// (docker/nginx/pathd.conf.template) by scripts/render_nginx_conf.py. Creates
// 30 maps through the balancer, checks that every call about a map (from the
// C++ client and from pathctl) reaches the one replica holding it, then kills
// a replica and checks that only its maps answer UNAVAILABLE, call after
// call, while the others keep serving. Skipped when nginx is not installed
// (scripts/setup.sh installs it).
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/client_context.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/client.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "tests/e2e/process.h"
#include "tests/testing/requests.h"

namespace pathd {
namespace {

namespace fs = std::filesystem;
using e2e::ReadFile;
using e2e::WriteFile;
using Clock = std::chrono::steady_clock;

// Hang guard only: a process that never comes up fails the test instead of
// hanging it.
constexpr auto kBound = std::chrono::seconds(120);
constexpr int kReplicas = 3;
constexpr int kMaps = 30;
constexpr absl::Duration kCallTimeout = absl::Seconds(30);

// nginx from $PATHD_NGINX, else $PATH or Debian's /usr/sbin (not on a
// normal user's PATH); empty when there is none.
std::string FindNginx() {
  if (const char* env = std::getenv("PATHD_NGINX"); env != nullptr && *env) {
    return access(env, X_OK) == 0 ? env : "";
  }
  std::vector<std::string> dirs;
  if (const char* path = std::getenv("PATH"); path != nullptr) {
    dirs = absl::StrSplit(path, ':', absl::SkipEmpty());
  }
  dirs.push_back("/usr/sbin");
  dirs.push_back("/sbin");
  for (const std::string& dir : dirs) {
    const std::string candidate = dir + "/nginx";
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return "";
}


// A port free at the time of the call, for nginx, which cannot listen on
// port 0 and report the port it got.
int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in address = {};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof(address);
  int port = 0;
  if (bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0 &&
      getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0) {
    port = ntohs(address.sin_port);
  }
  close(fd);
  return port;
}

// Runs `argv` to completion with stdout and stderr in files under `dir`;
// returns the exit code (-1 for a signal) and fills `out` with stdout and
// stderr.
int RunToExit(const std::vector<std::string>& argv, const fs::path& dir,
              std::string* out) {
  static int runs = 0;
  const fs::path out_file = dir / absl::StrCat("run", ++runs, ".out");
  const int fd =
      open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  const pid_t pid = e2e::Spawn(argv, {}, fd, fd, true);
  close(fd);
  const int code = e2e::WaitForExit(pid);
  *out = ReadFile(out_file);
  return code;
}

// One pathd replica on a free loopback port, named by --replica_name, its
// log in `dir`.
class Replica {
 public:
  Replica(const std::string& name, const fs::path& dir)
      : name_(name),
        pathd_(e2e::PathdProcessOptions{.binary = PATHD_BIN,
                                        .flags = {"--replica_name=" + name},
                                        .log_file = dir / (name + ".log")}) {
    EXPECT_TRUE(pathd_.listening()) << name << " did not start: " << pathd_.status();
  }

  void Kill() { pathd_.Kill(); }

  const std::string& name() const { return name_; }
  const std::string& address() const { return pathd_.address(); }

 private:
  std::string name_;
  e2e::PathdProcess pathd_;
};

// nginx with the configuration rendered from the project's template, run as
// the test's user: pid file, temp files and logs all live in `dir`.
class Balancer {
 public:
  Balancer(const std::string& nginx, const std::vector<std::string>& upstreams,
           const fs::path& dir)
      : error_log_(dir / "nginx-error.log"), access_log_(dir / "nginx-access.log") {
    const fs::path runtime = dir / "nginx";
    fs::create_directories(runtime);
    port_ = FreePort();
    address_ = absl::StrCat("127.0.0.1:", port_);
    const fs::path conf = dir / "nginx.conf";
    std::vector<std::string> render = {
        PYTHON3_BIN, PATHD_SOURCE_DIR "/scripts/render_nginx_conf.py", "render",
        "--listen", address_, "--runtime_dir", runtime.string(),
        "--error_log", error_log_.string(), "--access_log", access_log_.string(),
        // One process, killed with the test even if the test crashes.
        "--single_process", "-o", conf.string()};
    for (const std::string& upstream : upstreams) {
      render.push_back("--upstream");
      render.push_back(upstream);
    }
    std::string output;
    const int rendered = RunToExit(render, dir, &output);
    EXPECT_EQ(rendered, 0) << output;
    if (rendered != 0) return;
    pid_ = e2e::Spawn({nginx, "-p", runtime.string(), "-c", conf.string(), "-e",
                       error_log_.string()},
                      {}, -1, -1, true);
  }
  Balancer(const Balancer&) = delete;
  Balancer& operator=(const Balancer&) = delete;
  ~Balancer() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    e2e::WaitForExit(pid_);
  }

  bool started() const { return pid_ > 0; }

  // Whether nginx accepts TCP connections on its port yet.
  bool Accepting() const {
    const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in address = {};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    address.sin_port = htons(static_cast<uint16_t>(port_));
    const bool connected =
        connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0;
    close(fd);
    return connected;
  }

  // Whether nginx exited (e.g. on a configuration error); reaps it if so.
  bool Exited() {
    if (pid_ <= 0) return true;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) != pid_) return false;
    pid_ = -1;
    return true;
  }
  const std::string& address() const { return address_; }
  std::string ErrorLog() const { return ReadFile(error_log_); }

  // The upstream (replica address) of every request of the access log
  // whose x-pathd-map was `map`, in order.
  std::vector<std::string> UpstreamsOf(const std::string& map) const {
    std::vector<std::string> upstreams;
    std::istringstream lines(ReadFile(access_log_));
    const std::string key = absl::StrCat(" map=\"", map, "\" upstream=");
    for (std::string line; std::getline(lines, line);) {
      const size_t at = line.find(key);
      if (at == std::string::npos) continue;
      const size_t start = at + key.size();
      upstreams.push_back(line.substr(start, line.find(' ', start) - start));
    }
    return upstreams;
  }

 private:
  fs::path error_log_;
  fs::path access_log_;
  int port_ = 0;
  std::string address_;
  pid_t pid_ = -1;
};

std::string MapName(int i) { return absl::StrFormat("map-%02d", i); }

v1::CreateMapRequest OpenRoom(const std::string& name) {
  v1::CreateMapRequest request;
  request.set_name(name);
  std::string text = "type octile\nheight 8\nwidth 8\nmap\n";
  for (int y = 0; y < 8; ++y) text += "........\n";
  request.set_movingai_text(text);
  return request;
}

v1::PlanRequest PlanAcross(const std::string& map) {
  return testing::PlanBetween(map, 0, 0, 7, 7, v1::PLANNER_UNSPECIFIED);
}

class ScaleOutTest : public ::testing::Test {
 protected:
  void SetUp() override {
    nginx_ = FindNginx();
    if (nginx_.empty()) {
      GTEST_SKIP() << "nginx not found ($PATHD_NGINX, PATH, /usr/sbin); "
                      "scripts/setup.sh installs it (Debian package nginx)";
    }
    dir_ = fs::temp_directory_path() /
           absl::StrCat("pathd_scaleout_", getpid());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::vector<std::string> upstreams;
    for (int i = 1; i <= kReplicas; ++i) {
      replicas_.push_back(
          std::make_unique<Replica>(absl::StrCat("replica-", i), dir_));
      ASSERT_FALSE(replicas_.back()->address().empty());
      upstreams.push_back(replicas_.back()->address());
    }
    balancer_ = std::make_unique<Balancer>(nginx_, upstreams, dir_);
    ASSERT_TRUE(balancer_->started());
    // nginx opens its port a moment after it starts. Wait for a TCP
    // connection before the first call: a gRPC channel that failed to
    // connect backs off for seconds before it tries again.
    const Clock::time_point bound = Clock::now() + kBound;
    while (!balancer_->Accepting()) {
      ASSERT_FALSE(balancer_->Exited()) << "nginx exited:\n"
                                        << balancer_->ErrorLog();
      ASSERT_LT(Clock::now(), bound) << "nginx never listened:\n"
                                     << balancer_->ErrorLog();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    channel_ = client::MakeChannel(balancer_->address());
    maps_ = v1::MapService::NewStub(channel_);
    planner_ = v1::PlannerService::NewStub(channel_);
  }

  void TearDown() override {
    balancer_.reset();
    replicas_.clear();
    if (!dir_.empty() && !HasFailure()) fs::remove_all(dir_);
  }

  // The replica (by name) whose own ListMaps lists each map, asking every
  // live replica directly, not through the balancer.
  std::map<std::string, std::vector<std::string>> HoldersByMap() {
    std::map<std::string, std::vector<std::string>> holders;
    for (const auto& replica : replicas_) {
      client::PathdClient direct(replica->address(), kCallTimeout);
      absl::StatusOr<v1::ListMapsResponse> list = direct.ListMaps();
      EXPECT_TRUE(list.ok()) << replica->name() << ": " << list.status();
      if (!list.ok()) continue;
      for (const v1::MapInfo& info : list->maps()) {
        holders[info.name()].push_back(replica->name());
      }
    }
    return holders;
  }

  // Plans on `map` through the balancer with the header set; returns the
  // status and sets `served_by` from the response metadata.
  grpc::Status PlanThrough(const std::string& map, std::string* served_by) {
    std::unique_ptr<grpc::ClientContext> context =
        client::MakeContext(kCallTimeout, map);
    v1::PlanResponse response;
    const grpc::Status status =
        planner_->Plan(context.get(), PlanAcross(map), &response);
    *served_by = client::ServedBy(*context);
    if (status.ok()) {
      EXPECT_TRUE(response.found()) << map;
    }
    return status;
  }

  // pathctl through the balancer; returns its exit code, output in `out`.
  int Pathctl(const std::vector<std::string>& args, std::string* out) {
    std::vector<std::string> argv = {PATHCTL_BIN, "--server",
                                     balancer_->address()};
    argv.insert(argv.end(), args.begin(), args.end());
    return RunToExit(argv, dir_, out);
  }

  std::string nginx_;
  fs::path dir_;
  std::vector<std::unique_ptr<Replica>> replicas_;
  std::unique_ptr<Balancer> balancer_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::MapService::Stub> maps_;
  std::unique_ptr<v1::PlannerService::Stub> planner_;
};

TEST_F(ScaleOutTest, EachMapLivesOnOneReplicaAndAFailedReplicaOnlyTakesItsOwn) {
  // Create through the balancer: the replica that answers is the one that
  // holds the map from then on.
  std::map<std::string, std::string> owner;  // map -> replica name
  for (int i = 0; i < kMaps; ++i) {
    const std::string map = MapName(i);
    std::unique_ptr<grpc::ClientContext> context =
        client::MakeContext(kCallTimeout, map);
    v1::CreateMapResponse response;
    ASSERT_TRUE(maps_->CreateMap(context.get(), OpenRoom(map), &response).ok())
        << map;
    owner[map] = client::ServedBy(*context);
    ASSERT_FALSE(owner[map].empty()) << "no pathd-replica header for " << map;
  }
  std::map<std::string, int> maps_per_replica;
  for (const auto& [map, replica] : owner) ++maps_per_replica[replica];
  for (const auto& [replica, count] : maps_per_replica) {
    std::cout << replica << " holds " << count << " of " << kMaps << " maps\n";
  }
  // 30 maps on a hash ring of 3 replicas: all on one replica would mean the
  // header is not what nginx hashes on.
  EXPECT_GE(maps_per_replica.size(), 2u);

  // Each map exists on exactly the replica that answered its creation.
  std::map<std::string, std::vector<std::string>> holders = HoldersByMap();
  for (const auto& [map, replica] : owner) {
    EXPECT_EQ(holders[map], std::vector<std::string>{replica}) << map;
  }

  // Plans and updates, from the raw stubs and from PathdClient, keep going to
  // the owner.
  client::PathdClient through(channel_, kCallTimeout);
  for (const auto& [map, replica] : owner) {
    for (int round = 0; round < 3; ++round) {
      std::string served_by;
      const grpc::Status status = PlanThrough(map, &served_by);
      EXPECT_TRUE(status.ok()) << map << ": " << status.error_message();
      EXPECT_EQ(served_by, replica) << map;
      // PathdClient hides the metadata; a call not routed by the map would
      // reach a replica without it and fail NOT_FOUND.
      EXPECT_TRUE(through.Plan(PlanAcross(map)).ok()) << map;
    }
    std::unique_ptr<grpc::ClientContext> context =
        client::MakeContext(kCallTimeout, map);
    v1::UpdateMapRequest update;
    update.set_name(map);
    v1::CellChange* change = update.add_changes();
    change->mutable_cell()->set_x(3);
    change->mutable_cell()->set_y(3);
    change->set_cost(254);
    v1::UpdateMapResponse updated;
    ASSERT_TRUE(maps_->UpdateMap(context.get(), update, &updated).ok()) << map;
    EXPECT_EQ(client::ServedBy(*context), replica) << map;
    EXPECT_EQ(updated.version(), 2u) << map;
    v1::UpdateMapRequest again = update;
    again.mutable_changes(0)->set_cost(0);
    EXPECT_TRUE(through.UpdateMap(again).ok()) << map;
  }

  // An error answer names its replica too: a map created nowhere is
  // NOT_FOUND on the replica its name hashes to.
  {
    std::string served_by;
    const grpc::Status status = PlanThrough("no-such-map", &served_by);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_NE(served_by, "");
  }

  // pathctl sets the header on every command that names a map: each of these
  // would fail NOT_FOUND on a replica without the map. The access log shows
  // the header and the replica of every request.
  const std::string map = MapName(0);
  const fs::path batch_file = dir_ / "batch.txt";
  std::ofstream(batch_file) << "a " << map << " 0 0 7 7\nb " << map
                            << " 7 0 0 7\n";
  const std::vector<std::vector<std::string>> commands = {
      {"maps", "get", map},
      {"maps", "set", map, "5", "5", "254"},
      {"maps", "rect", map, "1", "5", "2", "6", "0"},
      {"maps", "watch", map, "--count", "1"},
      {"plan", map, "0", "0", "7", "7"},
      {"plan", map, "0", "0", "7", "7", "--progress"},
      {"batch", batch_file.string()},
      {"navigate", map, "0", "0", "7", "7"},
      {"cost-to-go", map, "7", "7"},
      {"check", map, "0", "0", "1", "1"},
      {"bench", map, "--requests", "20", "--duration", "0s", "--warmup", "0s",
       "--concurrency", "2"},
  };
  for (const std::vector<std::string>& command : commands) {
    std::string out;
    EXPECT_EQ(Pathctl(command, &out), 0)
        << "pathctl " << absl::StrJoin(command, " ") << "\n" << out;
  }
  std::map<std::string, std::string> owner_address;
  for (const auto& replica : replicas_) {
    owner_address[replica->name()] = replica->address();
  }
  for (const auto& [name, replica] : owner) {
    const std::vector<std::string> upstreams = balancer_->UpstreamsOf(name);
    EXPECT_GE(upstreams.size(), 9u) << name;
    for (const std::string& upstream : upstreams) {
      EXPECT_EQ(upstream, owner_address[replica]) << name;
    }
  }

  // Kill the replica holding the most maps. Its maps answer UNAVAILABLE,
  // again on every retry (nginx neither marks it failed nor moves its maps);
  // every other map keeps being served by its owner.
  std::string victim;
  for (const auto& [replica, count] : maps_per_replica) {
    if (victim.empty() || count > maps_per_replica[victim]) victim = replica;
  }
  for (auto& replica : replicas_) {
    if (replica->name() == victim) replica->Kill();
  }
  int unavailable = 0;
  int served = 0;
  for (int round = 0; round < 3; ++round) {
    for (const auto& [map, replica] : owner) {
      std::string served_by;
      const grpc::Status status = PlanThrough(map, &served_by);
      if (replica == victim) {
        EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE)
            << map << ": " << status.error_message();
        EXPECT_NE(status.error_message().find("unavailable"), std::string::npos)
            << status.error_message();
        ++unavailable;
      } else {
        EXPECT_TRUE(status.ok()) << map << ": " << status.error_message();
        EXPECT_EQ(served_by, replica) << map;
        ++served;
      }
    }
  }
  std::cout << "after killing " << victim << ": " << unavailable
            << " calls UNAVAILABLE, " << served << " served\n";
  // pathctl reports it as the gRPC error, with UNAVAILABLE's exit code 5.
  for (const auto& [map, replica] : owner) {
    if (replica != victim) continue;
    std::string out;
    EXPECT_EQ(Pathctl({"plan", map, "0", "0", "7", "7"}, &out), 5) << out;
    EXPECT_NE(out.find("error: UNAVAILABLE"), std::string::npos) << out;
    break;
  }
}

}  // namespace
}  // namespace pathd
