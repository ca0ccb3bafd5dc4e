// PathdServer: wiring, start-up map loading, listening and shutdown order.
#include "server/server.h"

#include <algorithm>
#include <climits>
#include <filesystem>
#include <utility>
#include <vector>

#include <grpc/grpc.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server_builder.h>
#include <grpcpp/support/channel_arguments.h>
#include <grpcpp/support/server_interceptor.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/map/inflation.h"
#include "core/status_macros.h"
#include "server/storage/map_dir.h"
#include "server/parse_error_interceptor.h"
#include "server/request_log.h"
#include "server/tls.h"
#include "spdlog/spdlog.h"

namespace pathd::server {
namespace {

// Room for the non-cell fields of a CreateMap request (name, YAML text).
constexpr int64_t kMessageOverheadBytes = int64_t{1} << 20;
// Map cells the default --max_message_bytes makes room for.
constexpr int64_t kMaxDefaultMessageCells = int64_t{64} << 20;

// Response metadata naming the replica (client/client.h kReplicaHeader).
constexpr char kReplicaHeader[] = "pathd-replica";

// Adds kReplicaHeader to the initial metadata of every call, whichever
// service answers it, so routing through a load balancer can be observed by
// clients and tests.
class ReplicaHeaderInterceptor : public grpc::experimental::Interceptor {
 public:
  explicit ReplicaHeaderInterceptor(const std::string& name) : name_(name) {}

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(
            grpc::experimental::InterceptionHookPoints::PRE_SEND_INITIAL_METADATA)) {
      methods->GetSendInitialMetadata()->emplace(kReplicaHeader, name_);
    }
    methods->Proceed();
  }

 private:
  const std::string& name_;
};

class ReplicaHeaderFactory
    : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  // `name` must outlive the server.
  explicit ReplicaHeaderFactory(const std::string& name) : name_(name) {}

  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo*) override {
    // gRPC owns the interceptor and deletes it when the call ends.
    return new ReplicaHeaderInterceptor(name_);
  }

 private:
  const std::string& name_;
};

}  // namespace

std::string ReplacePort(const std::string& address, int port) {
  const size_t colon = address.rfind(':');
  // A bare IPv6 literal has colons but no port; only "]:" or a single colon
  // marks one.
  const bool has_port =
      colon != std::string::npos &&
      (address.find(':') == colon || (colon > 0 && address[colon - 1] == ']'));
  const std::string host = has_port ? address.substr(0, colon) : address;
  return absl::StrCat(host, ":", port);
}

PathdServer::PathdServer(ServerOptions options)
    : options_(std::move(options)),
      store_(options_.max_map_cells),
      inflation_(options_.inflation_cache_entries),
      cache_(inflation_, options_.cache_bytes),
      derived_(options_.derived_cache_bytes) {
  store_.SetHonourOriginYaw(options_.honour_origin_yaw);
}

PathdServer::~PathdServer() { Shutdown(); }

absl::StatusOr<int> PathdServer::LoadMapDir() {
  PATHD_ASSIGN_OR_RETURN(const std::vector<std::string> files,
                         ListMapDirFiles(options_.map_dir));
  int loaded = 0;
  for (const std::string& file : files) {
    const std::string name = std::filesystem::path(file).stem().string();
    if (store_.Get(name).ok()) {
      // Recovered from --data_dir: its updates since it was loaded win over
      // the file (docs/decisions.md, "Durable maps").
      spdlog::info("map '{}' was recovered from --data_dir; not loading {}", name, file);
      continue;
    }
    const absl::Time start = absl::Now();
    absl::StatusOr<Grid> grid =
        LoadMapDirFile(options_.map_dir, file, store_.max_cells());
    if (!grid.ok()) {
      // One bad file should not keep the daemon (and every other map) down.
      spdlog::error("skipping map file {}: {}", file, grid.status().ToString());
      continue;
    }
    absl::StatusOr<std::shared_ptr<const MapSnapshot>> snapshot =
        store_.Create(name, *std::move(grid), /*replace=*/false);
    if (!snapshot.ok()) {
      spdlog::error("skipping map file {}: {}", file, snapshot.status().ToString());
      continue;
    }
    const Grid& g = *(*snapshot)->grid;
    spdlog::info("loaded map '{}' from {}: {} x {} cells, {} free, {} blocked ({} ms)",
                 name, file, g.width(), g.height(), g.CountFree(), g.CountBlocked(),
                 absl::ToInt64Milliseconds(absl::Now() - start));
    ++loaded;
  }
  return loaded;
}

absl::Status PathdServer::Start() {
  // Checked before anything starts, so a bad file leaves nothing to undo.
  PATHD_ASSIGN_OR_RETURN(
      const std::shared_ptr<grpc::ServerCredentials> credentials,
      MakeServerCredentials(
          TlsFiles{options_.tls_cert, options_.tls_key, options_.tls_client_ca}));
  if (!options_.auth_tokens.empty()) {
    PATHD_ASSIGN_OR_RETURN(authenticator_,
                           TokenAuthenticator::LoadFile(options_.auth_tokens));
    spdlog::info("--auth_tokens {}: {} token(s); Health needs none",
                 options_.auth_tokens, authenticator_->entries().size());
  }
  if (!options_.data_dir.empty()) {
    PATHD_ASSIGN_OR_RETURN(
        durable_, DurableStore::Open(DurableStore::Options{options_.data_dir,
                                                           options_.snapshot_log_bytes,
                                                           options_.snapshot_interval},
                                     store_));
  }
  if (!options_.map_dir.empty()) {
    PATHD_ASSIGN_OR_RETURN(const int loaded, LoadMapDir());
    spdlog::info("loaded {} map(s) from --map_dir {}", loaded, options_.map_dir);
  }

  pool_ = std::make_unique<WorkerPool>(WorkerPool::Options{
      options_.threads, options_.queue_depth, options_.batch_queue_depth,
      options_.inline_max_job_time});
  MemoryBudget::Options budget;
  budget.total_bytes = options_.memory_budget_bytes;
  budget.session_bytes = options_.session_memory_bytes;
  budget.max_watchers = options_.max_watchers;
  budget.caller_share = options_.caller_memory_share;
  budget.callers_by_token = authenticator_ != nullptr;
  budget.cache_bytes = [this] {
    return cache_.stats(IncrementalCache::Kind::kSpm).bytes +
           cache_.stats(IncrementalCache::Kind::kDStarLite).bytes +
           static_cast<int64_t>(inflation_.stats().bytes) +
           static_cast<int64_t>(derived_.stats().bytes);
  };
  budget_ = std::make_unique<MemoryBudget>(std::move(budget));
  // Before any service exists, as MapStore::AddListener requires.
  cache_.Follow(store_, *pool_);
  derived_.Follow(store_);
  map_service_ = std::make_unique<MapServiceImpl>(
      store_, options_.map_dir,
      MapWatchers::Options{options_.watch_queue_events, max_message_bytes(),
                           options_.watch_backlog_bytes, budget_.get()},
      max_message_bytes(), authenticator_.get());
  sessions_ = std::make_unique<NavigationSessions>(
      store_, *pool_, inflation_,
      NavigationSessions::Options{options_.session_idle_timeout, options_.max_sessions,
                                  options_.max_expansions, budget_.get(), &derived_});
  PlannerServiceImpl::Options planner_options;
  planner_options.max_expansions = options_.max_expansions;
  planner_options.max_path_points = options_.max_path_points;
  planner_options.max_cost_to_go_cells = options_.max_cost_to_go_cells;
  planner_options.max_table_entries = options_.max_table_entries;
  planner_options.max_trip_stops = options_.max_trip_stops;
  planner_options.max_fleet_robots = options_.max_fleet_robots;
  planner_options.max_message_bytes = max_message_bytes();
  planner_options.progress_interval = options_.progress_interval;
  planner_options.batch_max_inflight = options_.batch_max_inflight;
  planner_options.max_returned_expansions = options_.max_returned_expansions;
  planner_options.authenticator = authenticator_.get();
  planner_options.derived = &derived_;
  planner_service_ = std::make_unique<PlannerServiceImpl>(
      store_, *pool_, inflation_, cache_, *sessions_, planner_options);

  SetSlowRequestThreshold(options_.slow_request_threshold);
  if (!options_.metrics_address.empty()) {
    // Before the gRPC port opens, so a bad metrics address fails start-up
    // without a window in which the daemon serves unobserved.
    metrics_ = std::make_shared<ServerMetrics>(
        MetricsSources{.store = &store_,
                       .pool = pool_.get(),
                       .inflation = &inflation_,
                       .cache = &cache_,
                       .derived = &derived_,
                       .sessions = sessions_.get(),
                       .watchers = &map_service_->watchers(),
                       .budget = budget_.get()});
    if (absl::Status listening = metrics_->Listen(options_.metrics_address);
        !listening.ok()) {
      metrics_.reset();
      pool_->Shutdown(WorkerPool::ShutdownMode::kDrop);
      return listening;
    }
    SetRequestObserver(metrics_);
    spdlog::info("serving Prometheus metrics on http://{}/metrics",
                 ReplacePort(options_.metrics_address, metrics_->port()));
  }

  // Both are process-wide switches read when the builder is created.
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();

  grpc::ServerBuilder builder;
  builder.AddListeningPort(options_.address, credentials, &port_);
  // gRPC sets SO_REUSEPORT by default, so a second pathd on a busy port would
  // bind it too and the kernel would split the clients between the two.
  // Without it a busy port fails the bind, and start-up names the address.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.RegisterService(map_service_.get());
  builder.RegisterService(planner_service_.get());
  // gRPC refuses a larger request with RESOURCE_EXHAUSTED before reading it
  // into memory, and fails a larger response the same way.
  builder.SetMaxReceiveMessageSize(max_message_bytes());
  builder.SetMaxSendMessageSize(max_message_bytes());
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>>
      interceptors;
  interceptors.push_back(std::make_unique<ParseErrorInterceptorFactory>());
  if (!options_.replica_name.empty()) {
    interceptors.push_back(
        std::make_unique<ReplicaHeaderFactory>(options_.replica_name));
  }
  builder.experimental().SetInterceptorCreators(std::move(interceptors));
  server_ = builder.BuildAndStart();
  if (server_ == nullptr || port_ == 0) {
    server_.reset();
    pool_->Shutdown(WorkerPool::ShutdownMode::kDrop);
    if (metrics_ != nullptr) {
      ClearRequestObserver(metrics_.get());
      metrics_.reset();
    }
    return absl::UnavailableError(absl::StrFormat(
        "cannot listen on %s (--address): the address is in use (another "
        "pathd?), not local, or not a valid host:port",
        options_.address));
  }
  if (!options_.http_address.empty()) {
    grpc::ChannelArguments channel_args;
    channel_args.SetMaxReceiveMessageSize(-1);
    channel_args.SetMaxSendMessageSize(-1);
    absl::StatusOr<std::unique_ptr<HttpGateway>> http = HttpGateway::Start(
        HttpGatewayOptions{.address = options_.http_address,
                           .max_streams = options_.http_max_streams,
                           .max_body_bytes = max_message_bytes(),
                           .replica_name = options_.replica_name},
        server_->InProcessChannel(channel_args));
    if (!http.ok()) {
      server_->Shutdown();
      server_->Wait();
      server_.reset();
      pool_->Shutdown(WorkerPool::ShutdownMode::kDrop);
      if (metrics_ != nullptr) {
        ClearRequestObserver(metrics_.get());
        metrics_.reset();
      }
      return http.status();
    }
    http_ = *std::move(http);
    spdlog::info("serving the HTTP API and viewer on http://{}/",
                 ReplacePort(options_.http_address, http_->port()));
  }
  if (grpc::HealthCheckServiceInterface* health = server_->GetHealthCheckService()) {
    health->SetServingStatus(true);
  }
  spdlog::info(
      "serving on {} with {} worker thread(s), queue depth {} interactive / {} "
      "batch, messages up to {} bytes",
      listen_address(), pool_->threads(), pool_->queue_depth(),
      pool_->queue_depth(WorkerPool::Priority::kBatch), max_message_bytes());
  spdlog::info("transport: {}; authentication: {}",
               options_.tls_cert.empty()     ? "plaintext"
               : options_.tls_client_ca.empty() ? "TLS"
                                                : "mutual TLS (client certificates required)",
               authenticator_ == nullptr ? "none" : "bearer tokens");
  return absl::OkStatus();
}

void PathdServer::Shutdown() {
  {
    absl::MutexLock lock(&shutdown_mu_);
    if (shut_down_) return;
    shut_down_ = true;
  }
  if (server_ != nullptr) {
    spdlog::info("shutting down (grace {})", absl::FormatDuration(options_.shutdown_grace));
    // Probes see NOT_SERVING first so a load balancer stops sending work.
    if (grpc::HealthCheckServiceInterface* health = server_->GetHealthCheckService()) {
      health->SetServingStatus(false);
    }
    // New HTTP requests are refused and its event streams end; HTTP calls in
    // flight finish with the gRPC calls they made.
    if (http_ != nullptr) http_->BeginShutdown();
    // Open sessions would otherwise hold the shutdown for the whole grace.
    sessions_->Shutdown();
    // Likewise for WatchMap streams, which never end on their own.
    map_service_->ShutdownWatchers();
    // The pool keeps running during the grace period so accepted plans can
    // answer; after it gRPC cancels what is left, which reaches running
    // planners through their cancel flag.
    server_->Shutdown(absl::ToChronoTime(absl::Now() + options_.shutdown_grace));
  }
  if (pool_ != nullptr) {
    // Anything still queued answers UNAVAILABLE; joining guarantees no job
    // touches a call after the server below is gone.
    pool_->Shutdown(WorkerPool::ShutdownMode::kDrop);
  }
  if (http_ != nullptr) {
    // Every HTTP handler has returned: their gRPC calls have ended.
    http_->Stop();
    http_.reset();
  }
  if (server_ != nullptr) {
    server_->Wait();
    server_.reset();
    spdlog::info("shut down");
  }
  if (metrics_ != nullptr) {
    // Scrapes stay answered through the grace period, so the drain is
    // visible; no request of this server logs any more.
    ClearRequestObserver(metrics_.get());
    metrics_.reset();
  }
}

int PathdServer::max_message_bytes() const {
  // By default a raw CreateMap of a map up to 64 Mi cells fits in one
  // message (gRPC's own default, 4 MiB, would refuse maps over ~2000 x
  // 2000); larger maps stream through UploadMap and DownloadMap in bands of
  // rows, so no message needs to hold a whole 268 MB map.
  const int64_t bytes =
      options_.max_message_bytes > 0
          ? options_.max_message_bytes
          : std::min(options_.max_map_cells, kMaxDefaultMessageCells) +
                kMessageOverheadBytes;
  return static_cast<int>(std::min<int64_t>(INT_MAX, bytes));
}

std::string PathdServer::listen_address() const {
  return ReplacePort(options_.address, port_);
}

}  // namespace pathd::server
