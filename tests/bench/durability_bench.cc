// durability_bench: UpdateMap throughput through a real in-process pathd,
// in memory and with --data_dir (every update fdatasync'ed before its reply),
// for 1 and for N concurrent writers (each updating its own map, one update
// in flight each), so the effect of group commit shows as records per sync.
// Figures, not assertions.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/client_context.h>
#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <unistd.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "server/server.h"
#include "spdlog/spdlog.h"

ABSL_FLAG(int, writers, 8, "concurrent writers of the second run of each mode");
ABSL_FLAG(int, updates, 400, "updates per writer and run");
ABSL_FLAG(std::string, dir, "",
          "parent of the temporary --data_dir (default: the system temp dir); "
          "choose the disk you want to measure");

namespace {

struct Result {
  double updates_per_second = 0;
  int64_t records = 0;
  int64_t syncs = 0;
};

Result Run(const std::string& data_dir, int writers, int updates) {
  pathd::server::ServerOptions options;
  options.address = "127.0.0.1:0";
  options.threads = 2;
  options.data_dir = data_dir;
  pathd::server::PathdServer server(options);
  if (absl::Status s = server.Start(); !s.ok()) {
    std::fprintf(stderr, "cannot start: %s\n", s.ToString().c_str());
    std::exit(1);
  }
  auto channel =
      grpc::CreateChannel(server.listen_address(), grpc::InsecureChannelCredentials());
  auto stub = pathd::v1::MapService::NewStub(channel);
  for (int w = 0; w < writers; ++w) {
    pathd::v1::CreateMapRequest request;
    request.set_name(absl::StrFormat("bench%d", w));
    request.set_replace(true);
    request.mutable_raw()->set_width(64);
    request.mutable_raw()->set_height(64);
    request.mutable_raw()->set_cells(std::string(64 * 64, '\0'));
    pathd::v1::CreateMapResponse response;
    grpc::ClientContext context;
    if (!stub->CreateMap(&context, request, &response).ok()) std::exit(1);
  }
  const pathd::server::DurableStore::Stats before =
      server.durable_store() != nullptr ? server.durable_store()->stats()
                                        : pathd::server::DurableStore::Stats{};
  const absl::Time start = absl::Now();
  std::vector<std::thread> threads;
  for (int w = 0; w < writers; ++w) {
    threads.emplace_back([&stub, w, updates] {
      for (int i = 0; i < updates; ++i) {
        pathd::v1::UpdateMapRequest request;
        request.set_name(absl::StrFormat("bench%d", w));
        pathd::v1::CellChange* change = request.add_changes();
        change->mutable_cell()->set_x(i % 64);
        change->mutable_cell()->set_y(i / 64 % 64);
        change->set_cost(static_cast<uint32_t>(1 + i % 250));
        pathd::v1::UpdateMapResponse response;
        grpc::ClientContext context;
        if (!stub->UpdateMap(&context, request, &response).ok()) std::exit(1);
      }
    });
  }
  for (std::thread& t : threads) t.join();
  const double seconds = absl::ToDoubleSeconds(absl::Now() - start);
  Result result;
  result.updates_per_second = writers * updates / seconds;
  if (server.durable_store() != nullptr) {
    const pathd::server::DurableStore::Stats after = server.durable_store()->stats();
    result.records = after.records - before.records;
    result.syncs = after.syncs - before.syncs;
  }
  server.Shutdown();
  return result;
}

// The same updates through MapStore::Update directly (no gRPC), to separate
// the log's cost and its group commit from the transport's.
Result RunDirect(const std::string& data_dir, int writers, int updates) {
  pathd::server::MapStore store(int64_t{1} << 20);
  std::unique_ptr<pathd::server::DurableStore> durable;
  if (!data_dir.empty()) {
    pathd::server::DurableStore::Options options;
    options.dir = data_dir;
    durable = *pathd::server::DurableStore::Open(options, store);
  }
  for (int w = 0; w < writers; ++w) {
    if (!store.Create(absl::StrFormat("bench%d", w), *pathd::Grid::Create(64, 64), false)
             .ok()) {
      std::exit(1);
    }
  }
  const pathd::server::DurableStore::Stats before =
      durable != nullptr ? durable->stats() : pathd::server::DurableStore::Stats{};
  const absl::Time start = absl::Now();
  std::vector<std::thread> threads;
  for (int w = 0; w < writers; ++w) {
    threads.emplace_back([&store, w, updates] {
      const std::string name = absl::StrFormat("bench%d", w);
      for (int i = 0; i < updates; ++i) {
        const pathd::server::MapChange change = pathd::server::MapChange::ForCell(
            i % 64, i / 64 % 64, static_cast<uint32_t>(1 + i % 250));
        if (!store.Update(name, {change}, std::nullopt).ok()) std::exit(1);
      }
    });
  }
  for (std::thread& t : threads) t.join();
  const double seconds = absl::ToDoubleSeconds(absl::Now() - start);
  Result result;
  result.updates_per_second = writers * updates / seconds;
  if (durable != nullptr) {
    const pathd::server::DurableStore::Stats after = durable->stats();
    result.records = after.records - before.records;
    result.syncs = after.syncs - before.syncs;
  }
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "durability_bench [--writers 8] [--updates 400] [--dir DIR]\n"
      "UpdateMap throughput in memory and with --data_dir, 1 and N writers.");
  absl::ParseCommandLine(argc, argv);
  spdlog::set_level(spdlog::level::warn);
  const int writers = absl::GetFlag(FLAGS_writers);
  const int updates = absl::GetFlag(FLAGS_updates);
  const std::filesystem::path parent = absl::GetFlag(FLAGS_dir).empty()
                                           ? std::filesystem::temp_directory_path()
                                           : std::filesystem::path(absl::GetFlag(FLAGS_dir));
  const std::string data_dir =
      (parent / absl::StrFormat("pathd_durability_bench_%d", getpid())).string();
  std::printf("%-8s %-12s %8s %12s %10s %14s\n", "path", "mode", "writers", "updates/s",
              "syncs", "records/sync");
  for (const bool grpc : {true, false}) {
    for (const bool durable : {false, true}) {
      for (const int w : {1, writers}) {
      std::filesystem::remove_all(data_dir);
      const Result r = grpc ? Run(durable ? data_dir : "", w, updates)
                            : RunDirect(durable ? data_dir : "", w, updates);
      std::printf("%-8s %-12s %8d %12.0f %10s %14s\n", grpc ? "gRPC" : "store",
                  durable ? "--data_dir" : "in memory", w, r.updates_per_second,
                  durable ? absl::StrFormat("%d", r.syncs).c_str() : "-",
                  durable && r.syncs > 0
                      ? absl::StrFormat("%.2f", double(r.records) / r.syncs).c_str()
                      : "-");
      }
    }
  }
  std::filesystem::remove_all(data_dir);
  return 0;
}
