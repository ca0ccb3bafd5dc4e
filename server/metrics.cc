// ServerMetrics: request counters and histograms, scrape-time state, exposer.
#include "server/metrics.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <limits>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/time/time.h"
#include "prometheus/client_metric.h"
#include "prometheus/collectable.h"
#include "prometheus/metric_family.h"
#include "prometheus/metric_type.h"

namespace pathd::server {
namespace {

// Seconds, as Prometheus names durations. From 50 µs (a cached SPM lookup or
// A* on a small map) to a minute (a D* Lite build on a 4096^2 map under
// load); roughly 1-2.5-5 per decade so a quantile is never off by more than
// that step.
const prometheus::Histogram::BucketBoundaries& LatencyBuckets() {
  static const auto* const buckets = new prometheus::Histogram::BucketBoundaries{
      0.00005, 0.0001, 0.00025, 0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05,
      0.1,     0.25,   0.5,     1.0,    2.5,   5.0,    10.0,  30.0,  60.0};
  return *buckets;
}

prometheus::ClientMetric Value(prometheus::MetricType type, double value,
                               std::vector<prometheus::ClientMetric::Label> labels = {}) {
  prometheus::ClientMetric metric;
  metric.label = std::move(labels);
  if (type == prometheus::MetricType::Counter) {
    metric.counter.value = value;
  } else {
    metric.gauge.value = value;
  }
  return metric;
}

prometheus::MetricFamily Family(std::string name, std::string help,
                                prometheus::MetricType type,
                                std::vector<prometheus::ClientMetric> metrics) {
  prometheus::MetricFamily family;
  family.name = std::move(name);
  family.help = std::move(help);
  family.type = type;
  family.metric = std::move(metrics);
  return family;
}

prometheus::MetricFamily Single(std::string name, std::string help,
                                prometheus::MetricType type, double value) {
  return Family(std::move(name), std::move(help), type, {Value(type, value)});
}

}  // namespace

// Reads the server's current state on every scrape, so gauges are never
// stale and nothing is updated on the request path for them.
class ServerMetrics::StateCollectable final : public prometheus::Collectable {
 public:
  explicit StateCollectable(MetricsSources sources) : s_(sources) {}

  std::vector<prometheus::MetricFamily> Collect() const override {
    using prometheus::MetricType;
    constexpr MetricType kGauge = MetricType::Gauge;
    constexpr MetricType kCounter = MetricType::Counter;
    std::vector<prometheus::MetricFamily> families;

    families.push_back(Single("pathd_worker_threads", "Planning worker threads.",
                              kGauge, s_.pool->threads()));
    families.push_back(Single("pathd_workers_busy",
                              "Workers running a job at scrape time.", kGauge,
                              s_.pool->busy()));
    families.push_back(Single(
        "pathd_worker_busy_seconds_total",
        "Time workers spent running jobs (counted when a job ends); "
        "rate() / pathd_worker_threads is the utilisation.",
        kCounter, absl::ToDoubleSeconds(s_.pool->busy_time())));
    families.push_back(Single(
        "pathd_worker_job_failures_total",
        "Jobs that threw (e.g. out of memory); each answered its call with "
        "RESOURCE_EXHAUSTED or INTERNAL.",
        kCounter, static_cast<double>(s_.pool->job_failures())));
    families.push_back(Single(
        "pathd_worker_inline_runs_total",
        "Plan and IsPathValid calls run on the gRPC thread that received them "
        "(a worker was free, none waited, recent ones were short: "
        "--inline_max_job_time); they count in the busy figures too.",
        kCounter, static_cast<double>(s_.pool->inline_runs())));
    // One series per priority queue (interactive: Plan, CostToGo, Navigate,
    // cache repairs; batch: PlanBatch items).
    std::vector<prometheus::ClientMetric> queued;
    std::vector<prometheus::ClientMetric> capacity;
    for (const auto& [priority, label] :
         {std::pair{WorkerPool::Priority::kInteractive, "interactive"},
          std::pair{WorkerPool::Priority::kBatch, "batch"}}) {
      queued.push_back(Value(kGauge, static_cast<double>(s_.pool->queued(priority)),
                             {{"priority", label}}));
      capacity.push_back(Value(kGauge,
                               static_cast<double>(s_.pool->queue_depth(priority)),
                               {{"priority", label}}));
    }
    families.push_back(Family("pathd_queued_jobs",
                              "Jobs waiting for a worker at scrape time.", kGauge,
                              std::move(queued)));
    families.push_back(Family("pathd_queue_capacity",
                              "Jobs that may wait before RESOURCE_EXHAUSTED.", kGauge,
                              std::move(capacity)));

    AddCaches(families);

    const std::vector<std::shared_ptr<const MapSnapshot>> maps = s_.store->List();
    families.push_back(Single("pathd_maps", "Maps in the store.", kGauge,
                              static_cast<double>(maps.size())));
    std::vector<prometheus::ClientMetric> versions;
    for (size_t i = 0; i < maps.size() && i < kMaxMapSeries; ++i) {
      versions.push_back(Value(kGauge, static_cast<double>(maps[i]->version),
                               {{"map", maps[i]->name}}));
    }
    families.push_back(Family(
        "pathd_map_version",
        absl::StrFormat("Current version of each map (the first %d by name).",
                        kMaxMapSeries),
        kGauge, std::move(versions)));

    families.push_back(Single("pathd_navigate_sessions", "Open Navigate sessions.",
                              kGauge, static_cast<double>(s_.sessions->count())));
    families.push_back(Single("pathd_navigate_session_bytes",
                              "Bytes of the open sessions' D* Lite state.", kGauge,
                              static_cast<double>(s_.sessions->bytes())));
    AddControl(families);
    families.push_back(Single("pathd_map_watchers", "Open WatchMap streams.", kGauge,
                              static_cast<double>(s_.watchers->count())));
    families.push_back(Single(
        "pathd_map_watch_backlog_drops_total",
        "WatchMap backlogs replaced by a RESYNC because a reader was too slow.",
        kCounter, static_cast<double>(s_.watchers->backlog_drops())));
    if (s_.budget != nullptr) AddMemoryBudget(families);
    return families;
  }

 private:
  // Control sessions: the cycle latency histogram and the robots per map
  // (the first kMaxMapSeries maps by name, as pathd_map_version).
  void AddControl(std::vector<prometheus::MetricFamily>& families) const {
    const CycleHistogram::Snapshot cycles = s_.sessions->control_cycles().Read();
    prometheus::ClientMetric histogram;
    int64_t cumulative = 0;
    for (size_t i = 0; i < cycles.counts.size(); ++i) {
      cumulative += cycles.counts[i];
      prometheus::ClientMetric::Bucket bucket;
      bucket.cumulative_count = static_cast<std::uint64_t>(cumulative);
      bucket.upper_bound = i < CycleHistogram::kBounds.size()
                               ? CycleHistogram::kBounds[i]
                               : std::numeric_limits<double>::infinity();
      histogram.histogram.bucket.push_back(bucket);
    }
    histogram.histogram.sample_count = static_cast<std::uint64_t>(cycles.count);
    histogram.histogram.sample_sum = cycles.sum;
    families.push_back(Family("pathd_control_cycle_seconds",
                              "Control cycles of control sessions: from a state's arrival to "
                              "its command being queued.",
                              prometheus::MetricType::Histogram, {histogram}));
    std::vector<prometheus::ClientMetric> robots;
    for (const auto& [map, count] :
         s_.sessions->robots().Counts(std::chrono::steady_clock::now())) {
      if (robots.size() >= kMaxMapSeries) break;
      robots.push_back(Value(prometheus::MetricType::Gauge, static_cast<double>(count),
                             {{"map", map}}));
    }
    families.push_back(Family("pathd_control_robots",
                              "Robots of control sessions per map that still count as "
                              "obstacles (fresh or stale, not forgotten).",
                              prometheus::MetricType::Gauge, std::move(robots)));
  }

  // One series per cache: the two incremental caches, the inflation cache
  // (which has no byte budget and evicts by entry count, so it has neither
  // budget nor evictions; its advances from an older version's shaped grid
  // count as repairs, its full shapings as rebuilds) and the derived cache.
  void AddCaches(std::vector<prometheus::MetricFamily>& families) const {
    using prometheus::MetricType;
    struct Row {
      std::string name;
      IncrementalCache::Stats stats;
      // Has a byte budget and evictions beyond it.
      bool budgeted;
    };
    std::vector<Row> rows;
    for (const IncrementalCache::Kind kind :
         {IncrementalCache::Kind::kSpm, IncrementalCache::Kind::kDStarLite}) {
      rows.push_back({std::string(IncrementalCache::KindName(kind)),
                      s_.cache->stats(kind), true});
    }
    const InflationCache::Stats inflation = s_.inflation->stats();
    IncrementalCache::Stats as_incremental;
    as_incremental.entries = static_cast<int64_t>(inflation.entries);
    as_incremental.bytes = static_cast<int64_t>(inflation.bytes);
    as_incremental.hits = inflation.hits;
    as_incremental.misses = inflation.misses;
    as_incremental.repairs = inflation.advances;
    as_incremental.rebuilds = inflation.builds;
    rows.push_back({"inflation", as_incremental, false});
    if (s_.derived != nullptr) {
      // Structures derived from map versions: a miss is a build or an
      // advance; an advance counts as a repair, a build as a rebuild.
      const DerivedCache::Stats derived = s_.derived->stats();
      IncrementalCache::Stats d;
      d.entries = static_cast<int64_t>(derived.entries);
      d.bytes = static_cast<int64_t>(derived.bytes);
      d.budget_bytes = static_cast<int64_t>(derived.budget_bytes);
      d.hits = derived.hits;
      d.misses = derived.builds + derived.advances;
      d.evictions = derived.evictions;
      d.repairs = derived.advances;
      d.rebuilds = derived.builds;
      rows.push_back({"derived", d, true});
    }

    struct Column {
      const char* name;
      const char* help;
      MetricType type;
      int64_t IncrementalCache::Stats::*field;
      bool budgeted_only;
    };
    static constexpr Column kColumns[] = {
        {"pathd_cache_entries", "Entries in the cache.", MetricType::Gauge,
         &IncrementalCache::Stats::entries, false},
        {"pathd_cache_bytes", "Bytes held by the cache.", MetricType::Gauge,
         &IncrementalCache::Stats::bytes, false},
        {"pathd_cache_budget_bytes", "Byte budget of the cache (--cache_bytes / 2).",
         MetricType::Gauge, &IncrementalCache::Stats::budget_bytes, true},
        {"pathd_cache_hits_total", "Requests answered from an existing entry.",
         MetricType::Counter, &IncrementalCache::Stats::hits, false},
        {"pathd_cache_misses_total", "Requests that had to build an entry.",
         MetricType::Counter, &IncrementalCache::Stats::misses, false},
        {"pathd_cache_evictions_total", "Entries evicted beyond the budget.",
         MetricType::Counter, &IncrementalCache::Stats::evictions, true},
        {"pathd_cache_repairs_total",
         "Entries repaired for a new map version (inflation, derived: advanced "
         "from an older version's entry).",
         MetricType::Counter, &IncrementalCache::Stats::repairs, false},
        {"pathd_cache_rebuilds_total",
         "Entries rebuilt because a map changed too much to repair (inflation, "
         "derived: every entry made from scratch).",
         MetricType::Counter, &IncrementalCache::Stats::rebuilds, false},
    };
    for (const Column& column : kColumns) {
      std::vector<prometheus::ClientMetric> metrics;
      for (const Row& row : rows) {
        if (column.budgeted_only && !row.budgeted) continue;
        metrics.push_back(Value(column.type, static_cast<double>(row.stats.*column.field),
                                {{"cache", row.name}}));
      }
      families.push_back(Family(column.name, column.help, column.type, std::move(metrics)));
    }
  }

  void AddMemoryBudget(std::vector<prometheus::MetricFamily>& families) const {
    using prometheus::MetricType;
    const MemoryBudget& b = *s_.budget;
    families.push_back(Family(
        "pathd_memory_reserved_bytes",
        "Bytes held against the memory budget (--memory_budget_bytes), by part.",
        MetricType::Gauge,
        {Value(MetricType::Gauge,
               static_cast<double>(b.reserved(MemoryBudget::Part::kSessions)),
               {{"part", "sessions"}}),
         Value(MetricType::Gauge,
               static_cast<double>(b.reserved(MemoryBudget::Part::kWatchers)),
               {{"part", "watchers"}}),
         Value(MetricType::Gauge, static_cast<double>(b.cache_bytes()),
               {{"part", "caches"}})}));
    families.push_back(Family(
        "pathd_memory_budget_bytes",
        "Limits of the memory budget: total (--memory_budget_bytes) and "
        "sessions (--session_memory_bytes); 0 = unbounded.",
        MetricType::Gauge,
        {Value(MetricType::Gauge, static_cast<double>(b.options().total_bytes),
               {{"part", "total"}}),
         Value(MetricType::Gauge, static_cast<double>(b.options().session_bytes),
               {{"part", "sessions"}})}));
    families.push_back(Single(
        "pathd_memory_refusals_total",
        "Sessions and WatchMap streams refused (RESOURCE_EXHAUSTED) by the "
        "memory budget or --max_watchers.",
        MetricType::Counter, static_cast<double>(b.refusals())));
    families.push_back(Single(
        "pathd_memory_trims_total",
        "Times freed memory was handed back to the system (malloc_trim).",
        MetricType::Counter, static_cast<double>(b.trims())));
  }

  const MetricsSources s_;
};

ServerMetrics::ServerMetrics(MetricsSources sources)
    : registry_(std::make_shared<prometheus::Registry>()),
      requests_(prometheus::BuildCounter()
                    .Name("pathd_requests_total")
                    .Help("Answered RPCs by method and gRPC status code.")
                    .Register(*registry_)),
      request_seconds_(prometheus::BuildHistogram()
                           .Name("pathd_request_duration_seconds")
                           .Help("Time from receiving an RPC to answering it (a "
                                 "stream: to its end), by method.")
                           .Register(*registry_)),
      plan_seconds_(prometheus::BuildHistogram()
                        .Name("pathd_plan_duration_seconds")
                        .Help("Time from receiving a plan request to answering "
                              "it (queue wait included), by planner.")
                        .Register(*registry_)),
      slow_requests_(prometheus::BuildCounter()
                         .Name("pathd_slow_requests_total")
                         .Help("Requests at or over --slow_request_threshold, by "
                               "method.")
                         .Register(*registry_)),
      state_(std::make_shared<StateCollectable>(sources)) {}

ServerMetrics::~ServerMetrics() {
  if (exposer_ == nullptr) return;
  // civetweb's listener polls with a 2 s timeout and sees the stop request
  // only when the poll returns, which would add up to 2 s to every shutdown;
  // connecting once the stop has been requested wakes it at once. The wakes
  // repeat because the first may land before the stop flag is set.
  std::atomic<bool> stopped{false};
  std::thread waker([this, &stopped] {
    while (!stopped.load()) {
      PokeListener();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  exposer_.reset();
  stopped.store(true);
  waker.join();
}

void ServerMetrics::PokeListener() const {
  sockaddr_storage address{};
  socklen_t length = 0;
  if (host_.find(':') != std::string::npos) {
    auto* in6 = reinterpret_cast<sockaddr_in6*>(&address);
    in6->sin6_family = AF_INET6;
    in6->sin6_port = htons(static_cast<uint16_t>(port_));
    // "::" (every interface) is reachable as the loopback address.
    if (host_ == "::" || inet_pton(AF_INET6, host_.c_str(), &in6->sin6_addr) != 1) {
      in6->sin6_addr = in6addr_loopback;
    }
    length = sizeof(sockaddr_in6);
  } else {
    auto* in4 = reinterpret_cast<sockaddr_in*>(&address);
    in4->sin_family = AF_INET;
    in4->sin_port = htons(static_cast<uint16_t>(port_));
    if (host_ == "0.0.0.0" || inet_pton(AF_INET, host_.c_str(), &in4->sin_addr) != 1) {
      in4->sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    }
    length = sizeof(sockaddr_in);
  }
  const int fd = socket(address.ss_family, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd < 0) return;
  // Non-blocking: the SYN is all it takes; the answer does not matter.
  connect(fd, reinterpret_cast<const sockaddr*>(&address), length);
  close(fd);
}

absl::Status ServerMetrics::Listen(const std::string& address) {
  try {
    // civetweb gives each connection a thread until its request is read, and
    // by default waits 30 s for it: with prometheus-cpp's 2 threads, two
    // sockets that send half a request blinded every scrape. More threads
    // than a scraper or two ever needs, and a request timeout well under a
    // Prometheus scrape timeout, so stalled sockets cost a thread each only
    // briefly and never all of them.
    exposer_ = std::make_unique<prometheus::Exposer>(std::vector<std::string>{
        "listening_ports", address, "num_threads",
        std::to_string(kHttpThreads), "request_timeout_ms",
        std::to_string(absl::ToInt64Milliseconds(kHttpRequestTimeout))});
  } catch (const std::exception& e) {
    // civetweb reports a bad address or a port in use by throwing.
    return absl::UnavailableError(
        absl::StrFormat("cannot serve metrics on %s: %s", address, e.what()));
  }
  const std::vector<int> ports = exposer_->GetListeningPorts();
  if (ports.empty() || ports[0] == 0) {
    exposer_.reset();
    return absl::UnavailableError(
        absl::StrFormat("cannot serve metrics on %s: no port bound", address));
  }
  port_ = ports[0];
  // The IP part of "IP:PORT" or "[IPv6]:PORT", for PokeListener.
  host_ = address.substr(0, address.rfind(':'));
  if (host_.size() >= 2 && host_.front() == '[' && host_.back() == ']') {
    host_ = host_.substr(1, host_.size() - 2);
  }
  exposer_->RegisterCollectable(registry_);
  exposer_->RegisterCollectable(state_);
  return absl::OkStatus();
}

void ServerMetrics::Observe(const RequestRecord& record) {
  const std::string rpc(record.rpc);
  requests_.Add({{"rpc", rpc}, {"code", absl::StatusCodeToString(record.code)}})
      .Increment();
  const double seconds = absl::ToDoubleSeconds(record.elapsed);
  request_seconds_.Add({{"rpc", rpc}}, LatencyBuckets()).Observe(seconds);
  if (!record.planner.empty()) {
    plan_seconds_.Add({{"planner", std::string(record.planner)}}, LatencyBuckets())
        .Observe(seconds);
  }
  if (record.slow) slow_requests_.Add({{"rpc", rpc}}).Increment();
}

}  // namespace pathd::server
