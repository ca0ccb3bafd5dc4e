// PathdServer: owns the map store, the worker pool and the gRPC services,
// loads --map_dir at start-up, listens, and shuts everything down in the
// order that lets in-flight calls answer.
#ifndef PATHD_SERVER_SERVER_H_
#define PATHD_SERVER_SERVER_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include <grpcpp/server.h>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "server/auth.h"
#include "server/storage/durable_store.h"
#include "server/derived_cache.h"
#include "server/http/http_gateway.h"
#include "server/incremental_cache.h"
#include "server/rpc/map_service.h"
#include "server/map_store.h"
#include "server/memory_budget.h"
#include "server/metrics.h"
#include "server/rpc/navigate.h"
#include "server/rpc/planner_service.h"
#include "server/worker_pool.h"

namespace pathd::server {

struct ServerOptions {
  // host:port to listen on; port 0 picks a free port (see PathdServer::port).
  std::string address = "127.0.0.1:50051";
  // Worker threads; 0 = hardware threads.
  int threads = 0;
  // Interactive jobs (Plan, CostToGo, Navigate...) that may wait for a worker
  // before RESOURCE_EXHAUSTED.
  size_t queue_depth = 256;
  // PlanBatch jobs that may wait for a worker before RESOURCE_EXHAUSTED.
  size_t batch_queue_depth = 1024;
  // Plan and IsPathValid calls run on the gRPC thread that received them
  // while the recent ones took at most this on average and a worker is free
  // (WorkerPool::SubmitShort); zero: always on a worker.
  absl::Duration inline_max_job_time = absl::Milliseconds(1);
  // Largest map accepted, in cells: by default one 16384 x 16384 map.
  int64_t max_map_cells = int64_t{1} << 28;
  // Per-request expansion cap; 0 = unlimited.
  int64_t max_expansions = 0;
  // Most points in a returned path / poses in a checked one.
  int64_t max_path_points = int64_t{1} << 20;
  // Most cells of a cost-to-go field returned in one message.
  int64_t max_cost_to_go_cells = int64_t{1} << 22;
  // Table: most entries (sources x destinations) per call.
  int64_t max_table_entries = 250'000;
  // Trip: most waypoints per call.
  int64_t max_trip_stops = 256;
  // PlanFleet: most robots per call.
  int64_t max_fleet_robots = 1000;
  // Largest gRPC message received or sent; 0 = min(max_map_cells, 64 MiB)
  // + 1 MiB, so a raw CreateMap of a map up to 64 Mi cells fits (larger
  // ones stream through UploadMap).
  int64_t max_message_bytes = 0;
  // Most expanded cells one Plan response returns (options.return_expansions).
  int64_t max_returned_expansions = 1'000'000;
  // Directory of maps loaded at start-up and readable via map_dir_file;
  // empty = none.
  std::string map_dir;
  // How long Shutdown lets in-flight calls finish before cancelling them.
  absl::Duration shutdown_grace = absl::Seconds(5);
  // Inflated map versions kept for robot_radius requests.
  size_t inflation_cache_entries = 16;
  // Byte budget of the incremental-state caches (shortest path maps and D*
  // Lite searches, half each).
  size_t cache_bytes = size_t{1} << 30;
  // Byte budget of the derived representations of map versions (free-space
  // bitmaps, visibility graphs, navigation meshes, Voronoi graphs, Euclidean
  // shortest path maps), LRU beyond it.
  size_t derived_cache_bytes = size_t{512} << 20;
  // World coordinates apply maps' origin yaw (Grid::honour_origin_yaw).
  bool honour_origin_yaw = false;
  // Navigate sessions: idle expiry and the most open at once.
  absl::Duration session_idle_timeout = absl::Minutes(10);
  size_t max_sessions = 1024;
  // WatchMap events queued per stream before a slow reader's backlog is
  // replaced by one whole-map RESYNC event.
  size_t watch_queue_events = 64;
  // The same bound in bytes of queued events; 0 = the map's size (at least
  // 64 KiB).
  size_t watch_backlog_bytes = 0;
  // The memory budget (server/memory_budget.h): caches, sessions and WatchMap
  // streams together (0 = unbounded); sessions alone (0 = only the total);
  // WatchMap streams open at once; the share of each one caller may hold.
  int64_t memory_budget_bytes = int64_t{4} << 30;
  int64_t session_memory_bytes = int64_t{1} << 30;
  int64_t max_watchers = 1024;
  double caller_memory_share = 0.5;
  // "IP:PORT" serving Prometheus text metrics at /metrics; port 0 picks a
  // free port (see PathdServer::metrics_port); empty = no metrics.
  std::string metrics_address;
  // "host:port" of the HTTP/JSON API and the viewer (server/http/); port 0
  // picks a free port (see PathdServer::http_port); empty = no HTTP.
  std::string http_address;
  // Server-Sent Event streams the HTTP API serves at once.
  int http_max_streams = 16;
  // Non-stream requests taking at least this long are logged at warn level;
  // zero = never. Process-wide (server/request_log.h).
  absl::Duration slow_request_threshold = absl::Seconds(1);
  // PlanStream: least time between two progress events.
  absl::Duration progress_interval = absl::Milliseconds(100);
  // PlanBatch: items in flight per stream; 0 = twice the worker threads.
  int batch_max_inflight = 0;
  // TLS: PEM certificate chain and key (both or neither; neither =
  // plaintext) and the CA of client certificates (non-empty = mutual TLS).
  // The metrics endpoint stays plain HTTP.
  std::string tls_cert;
  std::string tls_key;
  std::string tls_client_ca;
  // YAML file of tokens and their roles (server/auth.h); empty = every
  // caller may do everything.
  std::string auth_tokens;
  // Sent in the "pathd-replica" initial metadata of every response, so a
  // client behind a load balancer sees which replica served it; empty = not
  // sent. Printable ASCII (a metadata value).
  std::string replica_name;
  // Directory keeping the maps across restarts (server/storage/durable_store.h);
  // empty = in memory only.
  std::string data_dir;
  // With data_dir: snapshot changed maps and drop old log segments once the
  // active segment holds this many bytes, or after snapshot_interval (zero =
  // only by size).
  int64_t snapshot_log_bytes = int64_t{64} << 20;
  absl::Duration snapshot_interval = absl::Minutes(10);
};

// Start() once, Shutdown() once (the destructor calls it). Shutdown may be
// called from any thread except a gRPC or pool thread.
class PathdServer {
 public:
  explicit PathdServer(ServerOptions options);
  ~PathdServer();
  PathdServer(const PathdServer&) = delete;
  PathdServer& operator=(const PathdServer&) = delete;

  // Checks the TLS and token files, recovers data_dir's maps, then loads
  // every .map/.yaml in map_dir whose name is not taken (a bad file is
  // logged and skipped), starts the pool and listens. DATA_LOSS /
  // FAILED_PRECONDITION / INTERNAL from DurableStore::Open. UNAVAILABLE when
  // the address cannot be bound; NOT_FOUND / INVALID_ARGUMENT when map_dir is
  // missing or not a directory, or a TLS or token file is missing or
  // malformed (server/tls.h, auth.h).
  absl::Status Start();

  // Health NOT_SERVING, stop accepting, give in-flight calls the grace
  // period, cancel the rest, drop queued plan jobs (UNAVAILABLE) and join the
  // workers. Idempotent.
  void Shutdown();

  // max_message_bytes with 0 resolved; at most INT_MAX (gRPC's int).
  int max_message_bytes() const;

  // The bound port (the chosen one when the address said 0); 0 before Start.
  int port() const { return port_; }
  // "host:port" with the bound port, for the "listening" line and clients.
  std::string listen_address() const;
  // The bound HTTP port; 0 without --http_address or before Start.
  int http_port() const { return http_ == nullptr ? 0 : http_->port(); }
  // The bound metrics port; 0 without --metrics_address or before Start.
  int metrics_port() const { return metrics_ == nullptr ? 0 : metrics_->port(); }

  MapStore& store() { return store_; }
  // The --data_dir journal; null without data_dir or before Start.
  const DurableStore* durable_store() const { return durable_.get(); }
  const InflationCache& inflation_cache() const { return inflation_; }
  const DerivedCache& derived_cache() const { return derived_; }
  const IncrementalCache& incremental_cache() const { return cache_; }
  const ServerOptions& options() const { return options_; }
  // WatchMap streams; valid after Start.
  const MapWatchers& map_watchers() const { return map_service_->watchers(); }
  // The memory budget; valid after Start.
  const MemoryBudget& memory_budget() const { return *budget_; }
  // Navigate sessions; valid after Start.
  const NavigationSessions& navigation_sessions() const { return *sessions_; }
  // The planning pool, for tests (WorkerPool::FailNextJobsForTesting); null
  // before Start.
  WorkerPool* worker_pool_for_testing() { return pool_.get(); }

 private:
  // Loads map_dir's maps into the store; returns how many loaded.
  absl::StatusOr<int> LoadMapDir();

  const ServerOptions options_;
  MapStore store_;
  // Declared after the store it journals, before everything that writes to
  // it, so it is destroyed after them.
  std::unique_ptr<DurableStore> durable_;
  InflationCache inflation_;
  IncrementalCache cache_;
  DerivedCache derived_;
  std::unique_ptr<WorkerPool> pool_;
  // Sessions and watchers reserve here; declared before them so it outlives
  // them.
  std::unique_ptr<MemoryBudget> budget_;
  // Loaded from auth_tokens; null = no token checks. The services hold a
  // pointer to it, so it is declared before them.
  std::unique_ptr<TokenAuthenticator> authenticator_;
  // Registers a store listener: lives while the store can change.
  std::unique_ptr<NavigationSessions> sessions_;
  std::unique_ptr<MapServiceImpl> map_service_;
  std::unique_ptr<PlannerServiceImpl> planner_service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  // Forwards to server_ over its in-process channel: declared after it,
  // stopped before it.
  std::unique_ptr<HttpGateway> http_;

  absl::Mutex shutdown_mu_;
  bool shut_down_ ABSL_GUARDED_BY(shutdown_mu_) = false;
  // Reads the parts above on every scrape: declared last so it is destroyed
  // first; Shutdown releases it after the workers are joined.
  std::shared_ptr<ServerMetrics> metrics_;
};

// Splits "host:port" ("[v6]:port" too) at the last colon; returns the host
// part with the port replaced. Exposed for tests.
std::string ReplacePort(const std::string& address, int port);

}  // namespace pathd::server

#endif  // PATHD_SERVER_SERVER_H_
