// Prometheus metrics of a PathdServer, served as text on their own HTTP port
// (--metrics_address) by prometheus-cpp's exposer. Requests are counted and
// timed when they answer (as a RequestObserver fed by LogRequest); everything
// else is read from the server's parts when Prometheus scrapes.
#ifndef PATHD_SERVER_METRICS_H_
#define PATHD_SERVER_METRICS_H_

#include <cstddef>
#include <memory>
#include <string>

#include "absl/status/status.h"
#include "absl/time/time.h"
#include "prometheus/counter.h"
#include "prometheus/exposer.h"
#include "prometheus/family.h"
#include "prometheus/histogram.h"
#include "prometheus/registry.h"
#include "server/incremental_cache.h"
#include "server/derived_cache.h"
#include "server/inflation_cache.h"
#include "server/map_store.h"
#include "server/memory_budget.h"
#include "server/rpc/watch_map.h"
#include "server/rpc/navigate.h"
#include "server/request_log.h"
#include "server/worker_pool.h"

namespace pathd::server {

// The parts a scrape reads; all must outlive the ServerMetrics.
struct MetricsSources {
  const MapStore* store = nullptr;
  const WorkerPool* pool = nullptr;
  const InflationCache* inflation = nullptr;
  const IncrementalCache* cache = nullptr;
  // Null = no "derived" cache series.
  const DerivedCache* derived = nullptr;
  const NavigationSessions* sessions = nullptr;
  const MapWatchers* watchers = nullptr;
  // Null = no memory budget series.
  const MemoryBudget* budget = nullptr;
};

// Thread-safe. The metric names and labels are listed in docs/service.md ("Metrics
// and logs").
class ServerMetrics final : public RequestObserver {
 public:
  // Maps named by pathd_map_version series, the first in name order. Map
  // names are chosen by clients, so one series per map would let them grow
  // Prometheus's series count without bound; pathd_maps still counts all.
  static constexpr size_t kMaxMapSeries = 100;
  // The HTTP server's threads (one per connection being served) and how long
  // it waits for a connection's request or for its reader before closing it.
  static constexpr int kHttpThreads = 16;
  static constexpr absl::Duration kHttpRequestTimeout = absl::Seconds(5);

  explicit ServerMetrics(MetricsSources sources);
  // Stops the HTTP server (letting a scrape in progress finish) first.
  ~ServerMetrics() override;
  ServerMetrics(const ServerMetrics&) = delete;
  ServerMetrics& operator=(const ServerMetrics&) = delete;

  // Serves GET /metrics on `address` ("IP:PORT", port 0 picks a free one).
  // UNAVAILABLE naming the address when it cannot be bound. Call once.
  absl::Status Listen(const std::string& address);
  // The bound port; 0 before Listen.
  int port() const { return port_; }

  // Counts and times one request: pathd_requests_total,
  // pathd_request_duration_seconds, pathd_plan_duration_seconds (when it
  // names a planner) and pathd_slow_requests_total (when it was logged slow).
  void Observe(const RequestRecord& record) override;

 private:
  class StateCollectable;

  // Opens (and drops) a connection to the metrics port, to wake civetweb's
  // listener while it stops.
  void PokeListener() const;

  std::shared_ptr<prometheus::Registry> registry_;
  prometheus::Family<prometheus::Counter>& requests_;
  prometheus::Family<prometheus::Histogram>& request_seconds_;
  prometheus::Family<prometheus::Histogram>& plan_seconds_;
  prometheus::Family<prometheus::Counter>& slow_requests_;
  std::shared_ptr<StateCollectable> state_;
  // The bound IP (without brackets) and port; set by Listen.
  std::string host_;
  int port_ = 0;
  // Last: destroyed first, so no scrape runs while the rest goes away.
  std::unique_ptr<prometheus::Exposer> exposer_;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_METRICS_H_
