// pathd: the path-planning daemon. Reads the optional config file and the
// flags, sets up logging, starts a PathdServer and waits for SIGINT/SIGTERM to
// shut it down gracefully.
#include <pthread.h>
#include <signal.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/flags/commandlineflag.h"
#include "absl/flags/flag.h"
#include "absl/flags/internal/parse.h"
#include "absl/flags/parse.h"
#include "absl/flags/reflection.h"
#include "absl/flags/usage.h"
#include "absl/flags/usage_config.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/synchronization/mutex.h"
#include "absl/synchronization/notification.h"
#include "absl/time/time.h"
#include "absl/types/span.h"
#include "server/config_file.h"
#include "server/listening_line.h"
#include "server/memory_budget.h"
#include "server/server.h"
#include "spdlog/sinks/stdout_color_sinks.h"
#include "spdlog/spdlog.h"

ABSL_FLAG(std::string, config, "",
          "YAML file of 'flag_name: value' lines setting any other pathd flag; "
          "flags given on the command line override it; empty = none");
ABSL_FLAG(std::string, address, "127.0.0.1:50051",
          "host:port to listen on; port 0 picks a free port (the 'pathd "
          "listening on' line on stdout names it)");
ABSL_FLAG(int32_t, threads, 0, "planning worker threads; 0 = hardware threads");
ABSL_FLAG(int32_t, queue_depth, 256,
          "interactive requests (Plan, CostToGo, Navigate messages) that may "
          "wait for a worker before RESOURCE_EXHAUSTED with a retry-after-ms "
          "hint");
ABSL_FLAG(int64_t, max_map_cells, int64_t{1} << 28,
          "largest map accepted, in cells (width * height; the default is one "
          "16384 x 16384 map, 256 MiB); also bounds the cells UploadMap "
          "calls in progress hold together");
ABSL_FLAG(int64_t, max_expansions, 0,
          "cap on search expansions per plan request; 0 = unlimited");
ABSL_FLAG(int32_t, batch_queue_depth, 1024,
          "PlanBatch requests that may wait for a worker (always behind the "
          "interactive ones) before RESOURCE_EXHAUSTED with a retry-after-ms "
          "hint");
ABSL_FLAG(absl::Duration, inline_max_job_time, absl::Milliseconds(1),
          "Plan and IsPathValid calls run on the gRPC thread that received "
          "them (no hand-off to a worker) while a worker is free, none waits "
          "and such calls took at most this long on average recently; 0 = "
          "always on a worker");
ABSL_FLAG(int64_t, max_path_points, int64_t{1} << 20,
          "most points a plan may return (RESOURCE_EXHAUSTED beyond) and most "
          "poses an IsPathValid request may hold (INVALID_ARGUMENT beyond)");
ABSL_FLAG(int64_t, max_cost_to_go_cells, int64_t{1} << 22,
          "most cells of a cost-to-go field returned in one message (Plan "
          "return_cost_to_go: INVALID_ARGUMENT beyond; CostToGo windows: "
          "RESOURCE_EXHAUSTED beyond)");
ABSL_FLAG(int64_t, max_table_entries, 250'000,
          "most entries (sources x destinations) a Table call may ask for "
          "(RESOURCE_EXHAUSTED beyond)");
ABSL_FLAG(int64_t, max_trip_stops, 256,
          "most waypoints a Trip call may order (RESOURCE_EXHAUSTED beyond)");
ABSL_FLAG(int64_t, max_fleet_robots, 1000,
          "most robots a PlanFleet call may plan (RESOURCE_EXHAUSTED beyond)");
ABSL_FLAG(int64_t, max_message_bytes, 0,
          "largest gRPC message received or sent (gRPC answers "
          "RESOURCE_EXHAUSTED beyond); 0 = min(max_map_cells, 64 Mi) + 1 "
          "MiB, so a CreateMap of a map up to 64 Mi cells fits (larger maps "
          "stream through UploadMap and DownloadMap)");
ABSL_FLAG(int64_t, max_returned_expansions, 1'000'000,
          "most expanded cells one Plan response returns for "
          "options.return_expansions (the response says when it was "
          "truncated); about 10 bytes each on the wire");
ABSL_FLAG(std::string, map_dir, "",
          "directory whose .map/.yaml files are loaded at start-up (named after "
          "the file stem) and readable via CreateMap map_dir_file; empty = none; "
          "not given (nor in --config): an installed pathd's bundled maps, "
          "PREFIX/share/pathd/maps, when that folder exists");
ABSL_FLAG(std::string, log_level, "info", "trace|debug|info|warn|error");
ABSL_FLAG(int, inflation_cache_entries, 16,
          "Inflated map versions (per robot radius) kept in memory");
ABSL_FLAG(int64_t, cache_bytes, int64_t{1} << 30,
          "byte budget of the cached incremental state (shortest path maps and "
          "D* Lite searches get half each); least recently used entries are "
          "evicted beyond it");
ABSL_FLAG(int64_t, derived_cache_bytes, int64_t{512} << 20,
          "byte budget of the structures derived from map versions for the "
          "geometric planners (free-space bitmaps, visibility graphs, "
          "navigation meshes, Voronoi graphs); least recently used beyond it");
ABSL_FLAG(bool, honour_origin_yaw, false,
          "apply a map's origin yaw in world coordinates; off (the default) "
          "world points and poses ignore it, as Nav2's costmap does");
ABSL_FLAG(absl::Duration, shutdown_grace, absl::Seconds(5),
          "on SIGINT/SIGTERM, time in-flight calls get before they are cancelled");
ABSL_FLAG(absl::Duration, session_idle_timeout, absl::Minutes(10),
          "a Navigate session without a client message for this long ends "
          "with DEADLINE_EXCEEDED");
ABSL_FLAG(int, max_sessions, 1024,
          "Navigate sessions open at once; more get RESOURCE_EXHAUSTED");
ABSL_FLAG(int, watch_queue_events, 64,
          "WatchMap events queued for a slow reader before its backlog is "
          "replaced by one whole-map RESYNC event");
ABSL_FLAG(int64_t, watch_backlog_bytes, 0,
          "bytes of WatchMap events queued for a slow reader before its "
          "backlog is replaced by one whole-map RESYNC event; 0 = the map's "
          "size (at least 64 KiB)");
ABSL_FLAG(int64_t, max_watchers, 1024,
          "WatchMap streams open at once; more get RESOURCE_EXHAUSTED");
ABSL_FLAG(int64_t, memory_budget_bytes, int64_t{4} << 30,
          "one memory budget for the caches (their current bytes), Navigate "
          "sessions and WatchMap streams: a session or stream that would take "
          "the sum past it gets RESOURCE_EXHAUSTED naming this flag; must be "
          "at least --cache_bytes + --session_memory_bytes; 0 = unbounded");
ABSL_FLAG(int64_t, session_memory_bytes, int64_t{1} << 30,
          "bytes all Navigate sessions may hold together (a session reserves "
          "about 16 bytes per map cell when it opens); beyond it "
          "RESOURCE_EXHAUSTED naming this flag; 0 = only "
          "--memory_budget_bytes");
ABSL_FLAG(double, caller_memory_share, 0.5,
          "share (0 < s <= 1) of --session_memory_bytes, --memory_budget_bytes "
          "and --max_watchers one caller may hold (a caller is a bearer token "
          "with --auth_tokens, else a peer IP address)");
ABSL_FLAG(absl::Duration, progress_interval, absl::Milliseconds(100),
          "PlanStream: least time between two progress events of a plan (none "
          "for plans that end sooner)");
ABSL_FLAG(int, batch_max_inflight, 0,
          "PlanBatch: items per stream read but not yet answered; the server "
          "stops reading the stream at this bound; 0 = twice the worker threads");

ABSL_FLAG(std::string, metrics_address, "",
          "IP:PORT serving Prometheus text metrics at /metrics over plain HTTP "
          "(e.g. 127.0.0.1:9464; port 0 picks a free port); empty = no "
          "metrics endpoint");
ABSL_FLAG(std::string, http_address, "",
          "HOST:PORT serving the HTTP/JSON API (one route per RPC, "
          "docs/http.md) and the map viewer at / (e.g. 127.0.0.1:8080; port 0 "
          "picks a free port); empty = no HTTP");
ABSL_FLAG(int, http_max_streams, 16,
          "HTTP Server-Sent Event streams (WatchMap, PlanStream, Navigate) "
          "served at once; more get 429 RESOURCE_EXHAUSTED");
ABSL_FLAG(absl::Duration, slow_request_threshold, absl::Seconds(1),
          "requests (not Navigate/WatchMap streams) taking at least this long "
          "are logged at warn level and counted in pathd_slow_requests_total; "
          "0 = off");
ABSL_FLAG(std::string, replica_name, "",
          "name sent in the 'pathd-replica' response metadata of every call, "
          "so clients behind a load balancer see which replica served them "
          "(printable ASCII); empty = not sent");

ABSL_FLAG(std::string, tls_cert, "",
          "PEM certificate chain (server certificate first) to serve gRPC over "
          "TLS; needs --tls_key; empty = plaintext. The --metrics_address "
          "endpoint stays plain HTTP");
ABSL_FLAG(std::string, tls_key, "",
          "PEM private key of --tls_cert (unencrypted); needs --tls_cert");
ABSL_FLAG(std::string, tls_client_ca, "",
          "PEM CA certificate(s) for mutual TLS: clients must present a "
          "certificate signed by one of them; needs --tls_cert; empty = no "
          "client certificates");
ABSL_FLAG(std::string, auth_tokens, "",
          "YAML file mapping bearer tokens to roles (read, write, admin; see "
          "docs/security.md); calls without a valid 'authorization: Bearer "
          "<token>' get UNAUTHENTICATED, calls beyond the token's role "
          "PERMISSION_DENIED; Health needs no token; empty = no "
          "authentication");
ABSL_FLAG(std::string, data_dir, "",
          "directory keeping the maps across restarts: every acknowledged "
          "CreateMap/UpdateMap/DeleteMap is in its log, synced to disk before "
          "the reply; start-up recovers them (recovered maps win over "
          "--map_dir files of the same name); empty = maps live in memory only");
ABSL_FLAG(int64_t, snapshot_log_bytes, int64_t{64} << 20,
          "with --data_dir: once the active log segment holds this many bytes, "
          "snapshot the maps changed since their last snapshot and delete the "
          "older log segments (bounds start-up replay)");
ABSL_FLAG(absl::Duration, snapshot_interval, absl::Minutes(10),
          "with --data_dir: the same after this long when the log holds any "
          "record; 0 = only by --snapshot_log_bytes");

namespace {

// How long past --shutdown_grace the process waits for Shutdown to return
// before it exits anyway: cancelled planners poll their flag every few
// thousand expansions and the workers are joined, which takes well under this.
constexpr absl::Duration kShutdownOverrun = absl::Seconds(10);

// absl 20220623's --help lists only flags from a file named after the binary
// (pathd.cc); ours live in server/main.cc, so widen the filter to server/.
bool IsPathdFlagFile(absl::string_view file) {
  return absl::StrContains(file, "server/");
}

std::string NormalizeFlagFile(absl::string_view file) {
  const size_t pos = file.rfind("server/");
  return std::string(pos == absl::string_view::npos ? file : file.substr(pos));
}

void SetUpFlagsUsage() {
  absl::FlagsUsageConfig config;
  config.contains_help_flags = &IsPathdFlagFile;
  config.contains_helpshort_flags = &IsPathdFlagFile;
  config.contains_helppackage_flags = &IsPathdFlagFile;
  config.normalize_filename = &NormalizeFlagFile;
  config.version_string = [] { return std::string("pathd 0.1.0\n"); };
  absl::SetFlagsUsageConfig(config);
  absl::SetProgramUsageMessage(
      "gRPC path-planning daemon over named 2D grid maps.\n"
      "Usage: pathd [--config=FILE] [--address=HOST:PORT] [--map_dir=DIR] "
      "[flags...]\n"
      "Every flag but --config can also be set in the --config YAML file "
      "('threads: 2', 'shutdown_grace: 5s'); a flag given on the command line "
      "overrides the file, the file overrides the default.\n"
      "Prints 'pathd listening on HOST:PORT' on stdout once it serves (and "
      "'pathd http on HOST:PORT' with --http_address); "
      "SIGINT/SIGTERM shut it down gracefully (exit 0).");
}

// pathd's own flags (not absl's --flagfile, --help...), sorted by name.
std::vector<const absl::CommandLineFlag*> PathdFlags() {
  std::vector<const absl::CommandLineFlag*> flags;
  for (const auto& [name, flag] : absl::GetAllFlags()) {
    if (IsPathdFlagFile(flag->Filename())) flags.push_back(flag);
  }
  std::sort(flags.begin(), flags.end(),
            [](const absl::CommandLineFlag* a, const absl::CommandLineFlag* b) {
              return a->Name() < b->Name();
            });
  return flags;
}

// The flags a config file may set: all of pathd's but the one naming it.
std::vector<std::string> ConfigFileSettableFlags() {
  std::vector<std::string> names;
  for (const absl::CommandLineFlag* flag : PathdFlags()) {
    if (flag->Name() != "config") names.emplace_back(flag->Name());
  }
  return names;
}

// "name=value ..." for every pathd flag, strings quoted so an empty one shows.
std::string EffectiveConfiguration() {
  std::vector<std::string> parts;
  for (const absl::CommandLineFlag* flag : PathdFlags()) {
    parts.push_back(flag->IsOfType<std::string>()
                        ? absl::StrCat(flag->Name(), "='", flag->CurrentValue(), "'")
                        : absl::StrCat(flag->Name(), "=", flag->CurrentValue()));
  }
  return absl::StrJoin(parts, " ");
}

// Where the --config file set which flag, so a value rejected below names its
// line in the file rather than a flag the user never typed. Leaked on purpose:
// no destructor runs at exit (Google style for non-trivial globals).
pathd::server::ConfigOrigins& ConfigFileOrigins() {
  static auto* const origins = new pathd::server::ConfigOrigins();
  return *origins;
}

// Reports a bad flag value the way absl reports a bad flag: on stderr, exit 2.
[[noreturn]] void UsageError(const std::string& message) {
  std::fprintf(stderr, "pathd: %s (see --help)\n", message.c_str());
  std::exit(2);
}

// UsageError for flag `name` whose value has `problem`, naming the config file
// line when the value came from there.
[[noreturn]] void FlagError(const std::string& name, const std::string& problem) {
  const std::string origin = ConfigFileOrigins().Of(name);
  if (origin.empty()) UsageError(absl::StrCat("--", name, " ", problem));
  std::fprintf(stderr, "pathd: %s: key '%s': %s\n", origin.c_str(), name.c_str(),
               problem.c_str());
  std::exit(2);
}

spdlog::level::level_enum ParseLogLevel(const std::string& text) {
  if (text == "trace") return spdlog::level::trace;
  if (text == "debug") return spdlog::level::debug;
  if (text == "info") return spdlog::level::info;
  if (text == "warn") return spdlog::level::warn;
  if (text == "error") return spdlog::level::err;
  FlagError("log_level", absl::StrFormat("'%s' is not one of "
                                         "trace|debug|info|warn|error", text));
}

// The maps an installed pathd bundles: <prefix>/share/pathd/maps, <prefix>
// being the parent of the folder that holds this executable (/usr/bin/pathd
// serves /usr/share/pathd/maps; cmake/install.cmake puts them there). Empty
// when the folder does not exist, as in a build tree.
std::string BundledMapDir() {
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return "";
  const std::filesystem::path maps =
      exe.parent_path().parent_path() / "share" / "pathd" / "maps";
  if (!std::filesystem::is_directory(maps, error)) return "";
  return maps.lexically_normal().string();
}

// --map_dir as given on the command line or in the --config file (an empty
// value there means no folder); when neither sets it, the bundled maps, so
// that an installed `pathd` with no flags serves them (docs/install.md).
// absl's WasPresentOnCommandLine tells "not given" from --map_dir="".
std::string MapDirFromFlags() {
  if (absl::flags_internal::WasPresentOnCommandLine("map_dir") ||
      !ConfigFileOrigins().Of("map_dir").empty()) {
    return absl::GetFlag(FLAGS_map_dir);
  }
  std::string bundled = BundledMapDir();
  if (!bundled.empty()) {
    spdlog::info("no --map_dir given: serving the bundled maps in {}", bundled);
  }
  return bundled;
}

pathd::server::ServerOptions OptionsFromFlags() {
  pathd::server::ServerOptions options;
  options.address = absl::GetFlag(FLAGS_address);
  const int32_t threads = absl::GetFlag(FLAGS_threads);
  const int32_t queue_depth = absl::GetFlag(FLAGS_queue_depth);
  options.max_map_cells = absl::GetFlag(FLAGS_max_map_cells);
  options.max_expansions = absl::GetFlag(FLAGS_max_expansions);
  options.map_dir = MapDirFromFlags();
  options.shutdown_grace = absl::GetFlag(FLAGS_shutdown_grace);
  if (absl::GetFlag(FLAGS_inflation_cache_entries) < 1) {
    FlagError("inflation_cache_entries", "must be >= 1");
  }
  options.inflation_cache_entries =
      static_cast<size_t>(absl::GetFlag(FLAGS_inflation_cache_entries));
  if (absl::GetFlag(FLAGS_cache_bytes) < 0) FlagError("cache_bytes", "must be >= 0");
  options.cache_bytes = static_cast<size_t>(absl::GetFlag(FLAGS_cache_bytes));
  if (absl::GetFlag(FLAGS_derived_cache_bytes) < 0) {
    FlagError("derived_cache_bytes", "must be >= 0");
  }
  options.derived_cache_bytes =
      static_cast<size_t>(absl::GetFlag(FLAGS_derived_cache_bytes));
  options.honour_origin_yaw = absl::GetFlag(FLAGS_honour_origin_yaw);
  if (threads < 0) FlagError("threads", "must be >= 0");
  if (absl::GetFlag(FLAGS_http_max_streams) < 1) FlagError("http_max_streams", "must be >= 1");
  if (queue_depth < 1) FlagError("queue_depth", "must be >= 1");
  if (options.max_map_cells < 1) FlagError("max_map_cells", "must be >= 1");
  if (options.max_expansions < 0) FlagError("max_expansions", "must be >= 0");
  if (absl::GetFlag(FLAGS_batch_queue_depth) < 1) {
    FlagError("batch_queue_depth", "must be >= 1");
  }
  options.batch_queue_depth =
      static_cast<size_t>(absl::GetFlag(FLAGS_batch_queue_depth));
  options.inline_max_job_time = absl::GetFlag(FLAGS_inline_max_job_time);
  if (options.inline_max_job_time < absl::ZeroDuration()) {
    FlagError("inline_max_job_time", "must be >= 0");
  }
  options.max_path_points = absl::GetFlag(FLAGS_max_path_points);
  if (options.max_path_points < 1) FlagError("max_path_points", "must be >= 1");
  options.max_cost_to_go_cells = absl::GetFlag(FLAGS_max_cost_to_go_cells);
  if (options.max_cost_to_go_cells < 1) {
    FlagError("max_cost_to_go_cells", "must be >= 1");
  }
  options.max_table_entries = absl::GetFlag(FLAGS_max_table_entries);
  if (options.max_table_entries < 1) FlagError("max_table_entries", "must be >= 1");
  options.max_trip_stops = absl::GetFlag(FLAGS_max_trip_stops);
  if (options.max_trip_stops < 2) FlagError("max_trip_stops", "must be >= 2");
  options.max_fleet_robots = absl::GetFlag(FLAGS_max_fleet_robots);
  if (options.max_fleet_robots < 1) FlagError("max_fleet_robots", "must be >= 1");
  options.max_message_bytes = absl::GetFlag(FLAGS_max_message_bytes);
  if (options.max_message_bytes < 0 || options.max_message_bytes > INT32_MAX) {
    FlagError("max_message_bytes", "must be in 0..2147483647 (gRPC's limit)");
  }
  options.max_returned_expansions = absl::GetFlag(FLAGS_max_returned_expansions);
  if (options.max_returned_expansions < 0) {
    FlagError("max_returned_expansions", "must be >= 0");
  }
  if (options.shutdown_grace < absl::ZeroDuration()) {
    FlagError("shutdown_grace", "must not be negative");
  }
  options.session_idle_timeout = absl::GetFlag(FLAGS_session_idle_timeout);
  if (options.session_idle_timeout <= absl::ZeroDuration()) {
    FlagError("session_idle_timeout", "must be positive");
  }
  if (absl::GetFlag(FLAGS_max_sessions) < 1) FlagError("max_sessions", "must be >= 1");
  options.max_sessions = static_cast<size_t>(absl::GetFlag(FLAGS_max_sessions));
  if (absl::GetFlag(FLAGS_watch_queue_events) < 1) {
    UsageError("--watch_queue_events must be >= 1");
  }
  options.watch_queue_events =
      static_cast<size_t>(absl::GetFlag(FLAGS_watch_queue_events));
  if (absl::GetFlag(FLAGS_watch_backlog_bytes) < 0) {
    FlagError("watch_backlog_bytes", "must be >= 0");
  }
  options.watch_backlog_bytes =
      static_cast<size_t>(absl::GetFlag(FLAGS_watch_backlog_bytes));
  options.max_watchers = absl::GetFlag(FLAGS_max_watchers);
  if (options.max_watchers < 1) FlagError("max_watchers", "must be >= 1");
  options.memory_budget_bytes = absl::GetFlag(FLAGS_memory_budget_bytes);
  if (options.memory_budget_bytes < 0) FlagError("memory_budget_bytes", "must be >= 0");
  options.session_memory_bytes = absl::GetFlag(FLAGS_session_memory_bytes);
  if (options.session_memory_bytes < 0) FlagError("session_memory_bytes", "must be >= 0");
  if (options.memory_budget_bytes > 0 &&
      static_cast<int64_t>(options.cache_bytes) + options.session_memory_bytes >
          options.memory_budget_bytes) {
    FlagError("memory_budget_bytes",
              absl::StrFormat("is %d, less than --cache_bytes (%d) + "
                              "--session_memory_bytes (%d); raise it or lower those",
                              options.memory_budget_bytes, options.cache_bytes,
                              options.session_memory_bytes));
  }
  options.caller_memory_share = absl::GetFlag(FLAGS_caller_memory_share);
  if (!(options.caller_memory_share > 0.0 && options.caller_memory_share <= 1.0)) {
    FlagError("caller_memory_share", "must be in (0, 1]");
  }
  options.progress_interval = absl::GetFlag(FLAGS_progress_interval);
  if (options.progress_interval <= absl::ZeroDuration()) {
    FlagError("progress_interval", "must be positive");
  }
  options.batch_max_inflight = absl::GetFlag(FLAGS_batch_max_inflight);
  if (options.batch_max_inflight < 0) FlagError("batch_max_inflight", "must be >= 0");
  options.threads = threads;
  options.queue_depth = static_cast<size_t>(queue_depth);
  options.metrics_address = absl::GetFlag(FLAGS_metrics_address);
  options.http_address = absl::GetFlag(FLAGS_http_address);
  options.http_max_streams = absl::GetFlag(FLAGS_http_max_streams);
  options.replica_name = absl::GetFlag(FLAGS_replica_name);
  for (const char c : options.replica_name) {
    if (c < 0x20 || c > 0x7e) {
      FlagError("replica_name", "must be printable ASCII (a gRPC metadata value)");
    }
  }
  options.slow_request_threshold = absl::GetFlag(FLAGS_slow_request_threshold);
  options.data_dir = absl::GetFlag(FLAGS_data_dir);
  options.snapshot_log_bytes = absl::GetFlag(FLAGS_snapshot_log_bytes);
  if (options.snapshot_log_bytes < 1) FlagError("snapshot_log_bytes", "must be >= 1");
  options.snapshot_interval = absl::GetFlag(FLAGS_snapshot_interval);
  if (options.snapshot_interval < absl::ZeroDuration()) {
    FlagError("snapshot_interval", "must not be negative");
  }
  if (options.slow_request_threshold < absl::ZeroDuration()) {
    FlagError("slow_request_threshold", "must not be negative");
  }
  options.tls_cert = absl::GetFlag(FLAGS_tls_cert);
  options.tls_key = absl::GetFlag(FLAGS_tls_key);
  options.tls_client_ca = absl::GetFlag(FLAGS_tls_client_ca);
  if (options.tls_cert.empty() != options.tls_key.empty()) {
    FlagError(options.tls_cert.empty() ? "tls_key" : "tls_cert",
              options.tls_cert.empty() ? "needs --tls_cert (both or neither)"
                                       : "needs --tls_key (both or neither)");
  }
  if (!options.tls_client_ca.empty() && options.tls_cert.empty()) {
    FlagError("tls_client_ca", "needs --tls_cert and --tls_key");
  }
  options.auth_tokens = absl::GetFlag(FLAGS_auth_tokens);
  return options;
}

}  // namespace

int main(int argc, char** argv) {
  pathd::server::PinAllocatorThresholds();
  SetUpFlagsUsage();
  // --data-dir reads as --data_dir (see NormalizeFlagSpelling).
  std::vector<std::string> spelled =
      pathd::server::NormalizeFlagSpelling(absl::MakeConstSpan(argv, argc));
  std::vector<char*> args;
  for (std::string& arg : spelled) args.push_back(arg.data());
  argc = static_cast<int>(args.size());
  argv = args.data();
  // The file is applied first so that absl::ParseCommandLine, run after it,
  // gives every flag on the command line the last word.
  const std::string config_path =
      pathd::server::FlagValueInArgv(absl::MakeConstSpan(argv, argc), "config");
  if (!config_path.empty()) {
    const absl::Status loaded = pathd::server::LoadConfigFile(
        config_path, ConfigFileSettableFlags(), &ConfigFileOrigins());
    if (!loaded.ok()) {
      std::fprintf(stderr, "pathd: %s\n", std::string(loaded.message()).c_str());
      return 2;
    }
  }
  const std::vector<char*> positional = absl::ParseCommandLine(argc, argv);
  // positional[0] is the program; pathd takes no arguments, only flags.
  if (positional.size() > 1) {
    UsageError(absl::StrCat("unexpected argument '", positional[1],
                            "': pathd takes only flags (--name=value)"));
  }
  if (absl::GetFlag(FLAGS_config) != config_path) {
    UsageError("--config must be given on the command line itself, not in a "
               "--flagfile or the environment");
  }

  // Debian's Abseil is built with absl::Mutex deadlock detection on, which
  // takes a global lock and updates a lock graph in every Mutex acquisition
  // and destruction -- gRPC's internal locks included -- costing several
  // per cent of a Plan call's CPU. Tests keep it; the daemon does not.
  absl::SetMutexDeadlockDetectionMode(absl::OnDeadlockCycle::kIgnore);
  const spdlog::level::level_enum level = ParseLogLevel(absl::GetFlag(FLAGS_log_level));
  // stderr: stdout carries only the "listening" line that scripts parse.
  spdlog::set_default_logger(spdlog::stderr_color_mt("pathd"));
  spdlog::set_level(level);
  const pathd::server::ServerOptions options = OptionsFromFlags();

  // Block the shutdown signals before any thread exists so every thread
  // inherits the mask and only sigwait() below ever receives them; no handler
  // runs, so nothing async-signal-unsafe can happen in one.
  sigset_t shutdown_signals;
  sigemptyset(&shutdown_signals);
  sigaddset(&shutdown_signals, SIGINT);
  sigaddset(&shutdown_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &shutdown_signals, nullptr);

  spdlog::info("pathd starting: {}", EffectiveConfiguration());

  pathd::server::PathdServer server(options);
  if (absl::Status status = server.Start(); !status.ok()) {
    spdlog::error("cannot start: {}", status.ToString());
    return 1;
  }
  std::printf("%s%s\n", pathd::server::kListeningPrefix,
              server.listen_address().c_str());
  if (server.http_port() != 0) {
    std::printf("%s%s\n", pathd::server::kHttpListeningPrefix,
                pathd::server::ReplacePort(options.http_address, server.http_port()).c_str());
  }
  std::fflush(stdout);

  int signal_number = 0;
  while (sigwait(&shutdown_signals, &signal_number) != 0) {
  }
  spdlog::info("received {}, shutting down", signal_number == SIGINT ? "SIGINT" : "SIGTERM");
  // A second signal means the operator will not wait for the grace period.
  std::thread([shutdown_signals] {
    int again = 0;
    while (sigwait(&shutdown_signals, &again) != 0) {
    }
    spdlog::warn("second signal during shutdown, exiting now");
    std::_Exit(1);
  }).detach();
  // Shutdown answers or cancels every call within the grace period; should a
  // call still never end (a bug), exit anyway rather than hang until SIGKILL.
  // Every acknowledged write is already synced (--data_dir), so this loses
  // nothing acknowledged.
  const absl::Duration overrun = options.shutdown_grace + kShutdownOverrun;
  auto shut_down = std::make_shared<absl::Notification>();
  std::thread([shut_down, overrun] {
    if (shut_down->WaitForNotificationWithTimeout(overrun)) return;
    spdlog::error("shutdown did not complete within --shutdown_grace + {}; exiting",
                  absl::FormatDuration(kShutdownOverrun));
    spdlog::default_logger()->flush();
    std::_Exit(1);
  }).detach();
  server.Shutdown();
  shut_down->Notify();
  return 0;
}
