// load_bench: what the gRPC service costs over calling the planner directly.
// Starts the real pathd on loopback with --threads=W, then for each Moving AI
// map (by default every 512x512 one) runs the same scenario queries in a
// closed loop both ways, alternating for a few rounds: in this process on W
// threads, each with its own scratch, and as gRPC Plan calls at 2W
// concurrency through the load generator `pathctl bench` uses. Prints both
// throughputs, their ratio and the gRPC latency percentiles, and the CPU
// time per query of the planner alone, of the daemon and of the client, which
// other load on the machine disturbs far less than the wall clock. Figures,
// not assertions: docs/performance.md records them with the command that produced
// them.
//
// --baseline_flags starts a second pathd with those flags added (e.g.
// --inline_max_job_time=0), --baseline_pathd a second binary (e.g. a build
// of the previous commit), and each round's gRPC load goes to both, so a
// change is compared with what it replaces in one run.
//
// --path_encodings=readable,packed sends the gRPC load once per listed
// PlanOptions.path_encoding in every round (the first is the main columns,
// the others get their own), and before the rounds plans every query once
// per encoding to print the mean response bytes and, for packed answers,
// the client's decode time per plan (UnpackPlanPath; the load generator
// itself parses answers but does not decode them).
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/strip.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "client/client.h"
#include "client/pathctl/load_generator.h"
#include "client/pathctl/map_source.h"
#include "client/pathctl/pathctl.h"
#include "grpcpp/create_channel.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "proto/path_codec.h"
#include "core/search/registry.h"
#include "core/map_io/map_io.h"
#include "core/search/planner.h"
#include "server/convert.h"
#include "tests/bench/movingai_maps.h"
#include "tests/testing/pathd_process.h"

ABSL_FLAG(std::string, pathd, PATHD_BIN, "the pathd binary to start");
ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map and <map>.map.scen files");
ABSL_FLAG(std::string, maps, "",
          "comma-separated map paths relative to --movingai_dir; empty = every "
          "512x512 map found");
ABSL_FLAG(std::string, planner, "astar", "planner name (server and in-process)");
ABSL_FLAG(int, threads, 2, "W: pathd's worker threads and the in-process threads");
ABSL_FLAG(int, concurrency, 0, "gRPC requests in flight; 0 = 2W");
ABSL_FLAG(int, channels, 1, "gRPC connections the load shares");
ABSL_FLAG(int, sample, 1000,
          "scenarios per map, spread evenly over the scenario file (which is "
          "sorted by length); 0 = all");
ABSL_FLAG(std::string, baseline_flags, "",
          "comma-separated flags for a second pathd measured in the same rounds "
          "(e.g. --inline_max_job_time=0); empty = none");
ABSL_FLAG(std::string, baseline_pathd, "",
          "the second pathd's binary (e.g. a build of an older commit); empty "
          "= --pathd. Either this or --baseline_flags starts the second one");
ABSL_FLAG(int, passes, 1, "each measured run sends every query this many times");
ABSL_FLAG(int, rounds, 3,
          "alternating in-process / gRPC runs per map; each side's fastest is "
          "reported");
ABSL_FLAG(absl::Duration, warmup, absl::Milliseconds(500),
          "unmeasured load before each measured run");
ABSL_FLAG(absl::Duration, timeout, absl::Seconds(60), "deadline of each gRPC call");
ABSL_FLAG(std::string, path_encodings, "readable",
          "comma-separated PlanOptions.path_encoding values (readable, packed, both, "
          "unspecified) the gRPC load is sent with, each in every round");

namespace fs = std::filesystem;

namespace {

// CPU seconds (user + system) process `pid` (the daemon) has used so far,
// from /proc/PID/stat (clock-tick resolution); 0 when unreadable.
double ProcessCpuSeconds(pid_t pid) {
  std::ifstream stat(absl::StrCat("/proc/", pid, "/stat"));
  std::string text((std::istreambuf_iterator<char>(stat)),
                   std::istreambuf_iterator<char>());
  // Fields after the parenthesised command name; utime and stime are the
  // 14th and 15th of the whole line.
  const size_t paren = text.rfind(')');
  if (paren == std::string::npos) return 0;
  std::vector<std::string> fields =
      absl::StrSplit(text.substr(paren + 2), ' ', absl::SkipEmpty());
  double utime = 0, stime = 0;
  if (fields.size() < 13 || !absl::SimpleAtod(fields[11], &utime) ||
      !absl::SimpleAtod(fields[12], &stime)) {
    return 0;
  }
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// CPU seconds (user + system) this process has used so far.
double OwnCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6;
  };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

// The gRPC side against one daemon.
struct RemoteFigures {
  pathd::client::LoadReport load;
  double server_cpu_us = 0;
  double client_cpu_us = 0;
};

// One path encoding's answers, each query planned once.
struct EncodingSize {
  double response_bytes = 0;  // mean serialized PlanResponse
  double unpack_us = 0;       // mean UnpackPlanPath time (packed answers)
};

struct MapFigures {
  int queries = 0;
  double path_cells = 0;  // mean cells per path (readable answers)
  std::vector<EncodingSize> sizes;  // per --path_encodings entry
  pathd::client::LoadReport in_process;
  // CPU microseconds per query, the least over the rounds: in-process, and
  // for gRPC the daemon's and the client's (this process). Other processes
  // slow the wall clock down far more than they change these.
  double in_process_cpu_us = 0;
  // The daemon under test with each encoding, then the baseline daemon
  // (first encoding) when there is one.
  std::vector<RemoteFigures> remote;
};

// --path_encodings as values (exits with 2 on a name that is none).
std::vector<pathd::v1::PathEncoding> PathEncodings() {
  std::vector<pathd::v1::PathEncoding> out;
  for (const absl::string_view name :
       absl::StrSplit(absl::GetFlag(FLAGS_path_encodings), ',', absl::SkipEmpty())) {
    pathd::v1::PathEncoding e;
    if (!pathd::v1::PathEncoding_Parse(absl::StrCat("PATH_ENCODING_", absl::AsciiStrToUpper(name)),
                                       &e)) {
      std::fprintf(stderr, "unknown path encoding '%s'\n", std::string(name).c_str());
      std::exit(2);
    }
    out.push_back(e);
  }
  if (out.empty()) out.push_back(pathd::v1::PATH_ENCODING_READABLE);
  return out;
}

std::string EncodingName(pathd::v1::PathEncoding e) {
  return absl::AsciiStrToLower(
      absl::StripPrefix(pathd::v1::PathEncoding_Name(e), "PATH_ENCODING_"));
}

// Plans every query once with each encoding on `address`: the mean
// response bytes and packed answers' decode time, and the mean path length.
absl::Status MeasureSizes(const std::string& address,
                          const std::vector<std::vector<pathd::v1::PlanRequest>>& wire,
                          MapFigures* figures) {
  auto stub = pathd::v1::PlannerService::NewStub(
      grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
  for (const std::vector<pathd::v1::PlanRequest>& requests : wire) {
    EncodingSize& size = figures->sizes.emplace_back();
    int64_t cells = 0;
    for (const pathd::v1::PlanRequest& request : requests) {
      grpc::ClientContext context;
      context.set_deadline(absl::ToChronoTime(absl::Now() + absl::GetFlag(FLAGS_timeout)));
      pathd::v1::PlanResponse response;
      if (grpc::Status s = stub->Plan(&context, request, &response); !s.ok()) {
        return absl::Status(static_cast<absl::StatusCode>(s.error_code()), s.error_message());
      }
      size.response_bytes += static_cast<double>(response.ByteSizeLong());
      const absl::Time t0 = absl::Now();
      if (absl::Status s = pathd::UnpackPlanPath(&response); !s.ok()) return s;
      size.unpack_us += absl::ToDoubleMicroseconds(absl::Now() - t0);
      cells += response.path_size();
    }
    const auto n = static_cast<double>(std::max<size_t>(requests.size(), 1));
    size.response_bytes /= n;
    size.unpack_us /= n;
    figures->path_cells = static_cast<double>(cells) / n;
  }
  return absl::OkStatus();
}

// Keeps the smaller of `*best` (0: none yet) and `value`.
void KeepLeast(double value, double* best) {
  if (*best == 0 || value < *best) *best = value;
}

absl::StatusOr<MapFigures> MeasureMap(
    const std::vector<std::unique_ptr<pathd::testing::PathdProcess>>& daemons,
    const fs::path& map_path, const std::string& name, const pathd::Grid& grid) {
  const int threads = absl::GetFlag(FLAGS_threads);
  auto all_scenarios = pathd::ReadMovingAiScenarioFile(map_path.string() + ".scen");
  if (!all_scenarios.ok()) return all_scenarios.status();
  // Spread over the whole file: it is sorted by path length.
  const size_t total = all_scenarios->size();
  const size_t wanted = absl::GetFlag(FLAGS_sample) > 0
                            ? std::min(total, static_cast<size_t>(absl::GetFlag(FLAGS_sample)))
                            : total;
  std::vector<pathd::Scenario> scenarios_kept;
  for (size_t i = 0; i < wanted; ++i) scenarios_kept.push_back((*all_scenarios)[i * total / wanted]);
  if (scenarios_kept.empty()) return absl::NotFoundError("no scenarios");
  const std::vector<pathd::Scenario>* scenarios = &scenarios_kept;

  // The wire requests, and the core requests the server turns them into (the
  // same conversion), so both sides plan exactly the same queries.
  absl::StatusOr<pathd::v1::Planner> wire_planner =
      pathd::pathctl::PlannerFromName(absl::GetFlag(FLAGS_planner));
  if (!wire_planner.ok()) return wire_planner.status();
  const pathd::Planner* planner =
      pathd::PlannerRegistry::Default().Get(absl::GetFlag(FLAGS_planner));
  if (planner == nullptr) {
    return absl::InvalidArgumentError(
        absl::StrCat("planner ", absl::GetFlag(FLAGS_planner), " is not in the registry"));
  }
  std::vector<pathd::v1::PlanRequest> wire;
  std::vector<pathd::PlanRequest> core;
  for (const pathd::Scenario& s : *scenarios) {
    pathd::v1::PlanRequest& w = wire.emplace_back();
    w.set_map(name);
    w.set_planner(*wire_planner);
    *w.mutable_start()->mutable_cell() = pathd::server::ToProto(s.start);
    *w.mutable_goal()->mutable_cell() = pathd::server::ToProto(s.goal);
    pathd::PlanRequest c = pathd::PlanRequest::Between(s.start, s.goal);
    if (absl::Status st = pathd::server::PlanOptionsToRequest(w.options(), &c); !st.ok()) {
      return st;
    }
    core.push_back(c);
  }
  const std::vector<pathd::v1::PathEncoding> encodings = PathEncodings();
  std::vector<std::vector<pathd::v1::PlanRequest>> encoded;
  for (const pathd::v1::PathEncoding e : encodings) {
    std::vector<pathd::v1::PlanRequest>& requests = encoded.emplace_back(wire);
    for (pathd::v1::PlanRequest& r : requests) r.mutable_options()->set_path_encoding(e);
  }
  MapFigures figures;
  figures.queries = static_cast<int>(core.size());
  const int64_t measured = int64_t{absl::GetFlag(FLAGS_passes)} * figures.queries;

  pathd::v1::CreateMapRequest create;
  create.set_name(name);
  create.set_replace(true);
  if (absl::Status s = pathd::pathctl::SetMapSourceFromFile(map_path.string(), &create);
      !s.ok()) {
    return s;
  }
  for (const auto& daemon : daemons) {
    pathd::client::PathdClient client(daemon->address(), absl::Seconds(60));
    if (auto created = client.CreateMap(create); !created.ok()) return created.status();
  }
  // Daemon 0 with each encoding, then the baseline with the first.
  figures.remote.resize(encodings.size() + daemons.size() - 1);
  if (absl::Status s = MeasureSizes(daemons.front()->address(), encoded, &figures); !s.ok()) {
    return s;
  }

  pathd::client::LoadOptions in_process;
  in_process.concurrency = threads;
  in_process.duration = absl::ZeroDuration();
  in_process.max_requests = measured;
  in_process.warmup = absl::GetFlag(FLAGS_warmup);
  pathd::client::LoadOptions remote = in_process;
  const int concurrency = absl::GetFlag(FLAGS_concurrency);
  remote.concurrency = concurrency > 0 ? concurrency : 2 * threads;
  // One scratch per thread, as each pool worker owns one.
  std::vector<std::unique_ptr<pathd::SearchScratch>> scratch;
  for (int t = 0; t < threads; ++t) {
    scratch.push_back(std::make_unique<pathd::SearchScratch>());
  }
  const pathd::StopCondition stop(absl::InfiniteFuture(), nullptr, 0);
  const auto plan_locally = [&](int worker, int64_t index) {
    absl::StatusOr<pathd::PlanResult> result =
        planner->Plan(grid, core[static_cast<size_t>(index) % core.size()], stop,
                      *scratch[static_cast<size_t>(worker)]);
    pathd::client::CallResult r;
    r.code = result.status().code();
    r.found = result.ok() && result->found();
    return r;
  };
  // Alternating rounds, keeping each side's best: other processes on this
  // machine only ever slow a run down, so the fastest round is the closest
  // to what the code itself costs, and alternating exposes both sides to the
  // same conditions.
  for (int round = 0; round < absl::GetFlag(FLAGS_rounds); ++round) {
    double cpu = OwnCpuSeconds();
    absl::StatusOr<pathd::client::LoadReport> local =
        pathd::client::RunClosedLoop(in_process, plan_locally);
    if (!local.ok()) return local.status();
    // The warm-up's CPU is in the difference too; its requests are counted.
    const auto per_query = [](double seconds, int64_t requests) {
      return seconds * 1e6 / static_cast<double>(std::max<int64_t>(requests, 1));
    };
    KeepLeast(per_query(OwnCpuSeconds() - cpu, local->requests + local->warmup_requests),
              &figures.in_process_cpu_us);
    if (local->requests_per_second > figures.in_process.requests_per_second) {
      figures.in_process = *local;
    }
    for (size_t r = 0; r < figures.remote.size(); ++r) {
      const size_t d = r < encodings.size() ? 0 : r - encodings.size() + 1;
      const size_t e = r < encodings.size() ? r : 0;
      const pathd::testing::PathdProcess& daemon = *daemons[d];
      RemoteFigures& out = figures.remote[r];
      cpu = OwnCpuSeconds();
      const double server_cpu = ProcessCpuSeconds(daemon.pid());
      absl::StatusOr<pathd::client::LoadReport> grpc = pathd::client::RunPlanLoad(
          daemon.address(), absl::GetFlag(FLAGS_channels), absl::GetFlag(FLAGS_timeout),
          encoded[e], remote);
      if (!grpc.ok()) return grpc.status();
      const int64_t sent = grpc->requests + grpc->warmup_requests;
      KeepLeast(per_query(ProcessCpuSeconds(daemon.pid()) - server_cpu, sent),
                &out.server_cpu_us);
      KeepLeast(per_query(OwnCpuSeconds() - cpu, sent), &out.client_cpu_us);
      if (grpc->requests_per_second > out.load.requests_per_second) out.load = *grpc;
    }
  }
  // Keeps the daemons' memory flat across maps.
  for (const auto& daemon : daemons) {
    pathd::client::PathdClient client(daemon->address(), absl::Seconds(60));
    if (auto deleted = client.DeleteMap(name); !deleted.ok()) return deleted.status();
  }
  return figures;
}

double Ms(absl::Duration d) { return absl::ToDoubleMilliseconds(d); }

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "load_bench [--pathd BIN] [--movingai_dir DIR] [--maps a.map,...] "
      "[--planner astar] [--threads W] [--concurrency C] [--channels K] "
      "[--sample N] [--passes P] [--rounds R] [--baseline_flags F,...] "
      "[--baseline_pathd BIN] [--path_encodings readable,packed]\n"
      "Starts pathd --threads=W and prints per map: in-process throughput on W "
      "threads, gRPC Plan throughput at 2W concurrency on the same queries, "
      "their ratio, and the gRPC latency p50/p99.");
  absl::ParseCommandLine(argc, argv);
  // As in pathd and pathctl: Debian's Abseil would check every Mutex
  // acquisition of the gRPC client for deadlock cycles.
  absl::SetMutexDeadlockDetectionMode(absl::OnDeadlockCycle::kIgnore);
  const fs::path root = absl::GetFlag(FLAGS_movingai_dir);
  if (absl::GetFlag(FLAGS_maps).empty() && !fs::is_directory(root)) {
    std::printf("Moving AI benchmarks not found at %s; nothing to measure\n",
                root.c_str());
    return 0;
  }
  const int threads = absl::GetFlag(FLAGS_threads);
  if (threads < 1 || absl::GetFlag(FLAGS_passes) < 1 || absl::GetFlag(FLAGS_rounds) < 1) {
    std::fprintf(stderr, "--threads, --passes and --rounds must be at least 1\n");
    return 2;
  }
  // The daemon under test, and the baseline; their logs (warnings only) on
  // our stderr.
  std::vector<std::unique_ptr<pathd::testing::PathdProcess>> daemons;
  const std::vector<std::string> baseline_flags =
      absl::StrSplit(absl::GetFlag(FLAGS_baseline_flags), ',', absl::SkipEmpty());
  const std::string baseline_pathd = absl::GetFlag(FLAGS_baseline_pathd);
  const bool baseline = !baseline_flags.empty() || !baseline_pathd.empty();
  for (int d = 0; d < (baseline ? 2 : 1); ++d) {
    std::vector<std::string> flags = {absl::StrCat("--threads=", threads),
                                      "--log_level=warn"};
    if (d == 1) flags.insert(flags.end(), baseline_flags.begin(), baseline_flags.end());
    pathd::testing::PathdProcessOptions options;
    options.binary = d == 1 && !baseline_pathd.empty() ? baseline_pathd
                                                       : absl::GetFlag(FLAGS_pathd);
    options.flags = std::move(flags);
    daemons.push_back(std::make_unique<pathd::testing::PathdProcess>(options));
    if (!daemons.back()->listening()) {
      std::fprintf(stderr, "%s\n", daemons.back()->status().ToString().c_str());
      return 1;
    }
  }
  const pathd::testing::PathdProcess& daemon = *daemons.front();
  const int concurrency = absl::GetFlag(FLAGS_concurrency) > 0
                              ? absl::GetFlag(FLAGS_concurrency)
                              : 2 * threads;
  std::printf(
      "load_bench: %u hardware threads; pathd --threads=%d on %s; planner %s; "
      "in-process %d threads vs gRPC concurrency %d over %d channel(s); %d "
      "scenarios spread over each file x %d passes, best of %d rounds%s%s\n",
      std::thread::hardware_concurrency(), threads, daemon.address().c_str(),
      absl::GetFlag(FLAGS_planner).c_str(), threads, concurrency,
      absl::GetFlag(FLAGS_channels), absl::GetFlag(FLAGS_sample),
      absl::GetFlag(FLAGS_passes), absl::GetFlag(FLAGS_rounds),
      baseline ? "; baseline: " : "",
      baseline ? absl::StrCat(baseline_pathd.empty() ? absl::GetFlag(FLAGS_pathd)
                                                     : baseline_pathd,
                              " ", absl::GetFlag(FLAGS_baseline_flags))
                     .c_str()
               : "");
  std::printf("%-28s %7s %9s %9s %8s %9s %9s %9s %9s %8s %8s %8s %8s %8s %6s",
              "map", "queries", "local_q/s", "grpc_q/s", "grpc/loc", "local_p99",
              "grpc_p50", "grpc_p95", "grpc_p99", "loc_cpu", "srv_cpu", "cli_cpu",
              "loc/srv", "loc/all", "errors");
  const std::vector<pathd::v1::PathEncoding> encodings = PathEncodings();
  std::printf(" %7s", "cells");
  for (const pathd::v1::PathEncoding e : encodings) {
    std::printf(" %9s", absl::StrCat("B_", EncodingName(e)).c_str());
  }
  for (size_t e = 1; e < encodings.size(); ++e) {
    const std::string n = EncodingName(encodings[e]);
    std::printf(" %9s %8s %8s %8s %8s", absl::StrCat(n, "_q/s").c_str(),
                absl::StrCat(n, "/loc").c_str(), absl::StrCat(n, "_srv").c_str(),
                absl::StrCat(n, "_cli").c_str(), absl::StrCat(n, "_dec").c_str());
  }
  if (daemons.size() > 1) {
    std::printf(" %9s %8s %8s %9s %8s", "base_q/s", "base/loc", "base_srv", "base_p50",
                "grpc/base");
  }
  std::printf("\n");
  const bool all = absl::GetFlag(FLAGS_maps).empty();
  int failures = 0;
  for (const std::string& relative :
       pathd::bench::MovingAiMaps(root, absl::GetFlag(FLAGS_maps))) {
    const fs::path map_path = root / relative;
    auto grid = pathd::ReadMovingAiMapFile(map_path.string());
    if (!grid.ok()) {
      std::fprintf(stderr, "%s\n", std::string(grid.status().message()).c_str());
      return 1;
    }
    if (all && (grid->width() != 512 || grid->height() != 512)) continue;
    const std::string name = map_path.stem().string();
    absl::StatusOr<MapFigures> f = MeasureMap(daemons, map_path, name, *grid);
    if (!f.ok()) {
      std::fprintf(stderr, "%s: %s\n", relative.c_str(), f.status().ToString().c_str());
      ++failures;
      continue;
    }
    const auto fraction = [](double numerator, double denominator) {
      return denominator > 0 ? numerator / denominator : 0.0;
    };
    const RemoteFigures& g = f->remote.front();
    const double ratio =
        fraction(g.load.requests_per_second, f->in_process.requests_per_second);
    std::printf(
        "%-28s %7d %9.1f %9.1f %8.3f %9.2f %9.2f %9.2f %9.2f %8.0f %8.0f %8.0f %8.3f "
        "%8.3f %6lld",
        relative.c_str(), f->queries, f->in_process.requests_per_second,
        g.load.requests_per_second, ratio, Ms(f->in_process.latency.p99),
        Ms(g.load.latency.p50), Ms(g.load.latency.p95), Ms(g.load.latency.p99),
        f->in_process_cpu_us, g.server_cpu_us, g.client_cpu_us,
        fraction(f->in_process_cpu_us, g.server_cpu_us),
        fraction(f->in_process_cpu_us, g.server_cpu_us + g.client_cpu_us),
        static_cast<long long>(g.load.errors() + f->in_process.errors()));
    std::printf(" %7.0f", f->path_cells);
    for (const EncodingSize& size : f->sizes) std::printf(" %9.0f", size.response_bytes);
    for (size_t e = 1; e < encodings.size(); ++e) {
      const RemoteFigures& x = f->remote[e];
      std::printf(" %9.1f %8.3f %8.0f %8.0f %8.1f", x.load.requests_per_second,
                  fraction(x.load.requests_per_second, f->in_process.requests_per_second),
                  x.server_cpu_us, x.client_cpu_us, f->sizes[e].unpack_us);
    }
    if (daemons.size() > 1) {
      const RemoteFigures& b = f->remote.back();
      std::printf(" %9.1f %8.3f %8.0f %9.2f %8.3f", b.load.requests_per_second,
                  fraction(b.load.requests_per_second, f->in_process.requests_per_second),
                  b.server_cpu_us, Ms(b.load.latency.p50),
                  fraction(g.load.requests_per_second, b.load.requests_per_second));
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  for (const auto& d : daemons) {
    if (const int code = d->Stop(); code != 0) {
      std::fprintf(stderr, "pathd exited with %d on SIGTERM\n", code);
      ++failures;
    }
  }
  return failures == 0 ? 0 : 1;
}
