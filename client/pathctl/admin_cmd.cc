// pathctl cache-stats, sessions, health and metrics: GetCacheStats,
// ListSessions, the gRPC health
// check, and an HTTP GET of pathd's Prometheus endpoint (libcurl).
#include "client/pathctl/admin_cmd.h"

#include <memory>

#include <curl/curl.h>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/pathctl/command.h"

namespace pathd::pathctl {
namespace {

// --- cache-stats -------------------------------------------------------------

int CacheStats(CommandEnv& env, Args args) {
  if (!args.empty()) return env.Usage("cache-stats takes no arguments");
  absl::StatusOr<v1::GetCacheStatsResponse> response =
      env.client().GetCacheStats();
  if (!response.ok()) return env.Fail(response.status());
  if (env.json()) return env.PrintJson(*response);
  const bool csv = env.csv();
  Table table(csv ? std::vector<std::string>{"cache", "entries", "bytes",
                                             "budget_bytes", "hits", "misses",
                                             "evictions", "repairs", "rebuilds"}
                  : std::vector<std::string>{"CACHE", "ENTRIES", "BYTES", "BUDGET",
                                             "HITS", "MISSES", "EVICTIONS",
                                             "REPAIRS", "REBUILDS"});
  for (const v1::CacheStats& c : response->caches()) {
    table.AddRow({c.name(), absl::StrCat(c.entries()), absl::StrCat(c.bytes()),
                  absl::StrCat(c.budget_bytes()), absl::StrCat(c.hits()),
                  absl::StrCat(c.misses()), absl::StrCat(c.evictions()),
                  absl::StrCat(c.repairs()), absl::StrCat(c.rebuilds())});
  }
  if (csv) {
    // Navigate sessions' D* Lite state is memory like a cache's: one more
    // row, so the CSV carries everything the table shows.
    table.AddRow({"navigate_sessions", absl::StrCat(response->sessions()),
                  absl::StrCat(response->session_bytes())});
    return env.PrintCsv(table);
  }
  env.out() << table.Aligned();
  env.out() << absl::StrFormat("sessions:    %d open, %d bytes of D* Lite state\n",
                               response->sessions(), response->session_bytes());
  return kExitOk;
}

// --- sessions ----------------------------------------------------------------

int Sessions(CommandEnv& env, Args args) {
  if (args.size() > 1) return env.Usage("sessions takes at most one map NAME");
  absl::StatusOr<v1::ListSessionsResponse> response =
      env.client().ListSessions(args.empty() ? "" : args[0]);
  if (!response.ok()) return env.Fail(response.status());
  if (env.json()) return env.PrintJson(*response);
  Table table(env.csv() ? std::vector<std::string>{"session", "map", "robot_x", "robot_y",
                                                   "goal_x", "goal_y", "path_cells",
                                                   "length_m", "age_s", "idle_s"}
                        : std::vector<std::string>{"SESSION", "MAP", "ROBOT", "GOAL",
                                                   "PATH", "LENGTH_M", "AGE_S", "IDLE_S"});
  for (const v1::SessionInfo& s : response->sessions()) {
    const v1::PlanResponse& plan = s.last().plan();
    // The robot is where its latest path starts (kinematic sessions: the
    // pose the answer planned from).
    std::string x = "-", y = "-";
    if (s.last().has_robot_pose()) {
      x = absl::StrFormat("%.2f", s.last().robot_pose().x());
      y = absl::StrFormat("%.2f", s.last().robot_pose().y());
    } else if (plan.path_size() > 0) {
      x = absl::StrCat(plan.path(0).x());
      y = absl::StrCat(plan.path(0).y());
    }
    const std::string gx = s.last().has_plan() ? absl::StrCat(plan.goal().x()) : "-";
    const std::string gy = s.last().has_plan() ? absl::StrCat(plan.goal().y()) : "-";
    const std::string length = plan.found() ? absl::StrFormat("%.2f", plan.length_m()) : "-";
    const std::string age = absl::StrFormat("%.1f", s.age_seconds());
    const std::string idle = absl::StrFormat("%.1f", s.idle_seconds());
    if (env.csv()) {
      table.AddRow({absl::StrCat(s.session_id()), s.map(), x, y, gx, gy,
                    absl::StrCat(plan.path_size()), length, age, idle});
    } else {
      table.AddRow({absl::StrCat(s.session_id()), s.map(), absl::StrCat("(", x, ", ", y, ")"),
                    absl::StrCat("(", gx, ", ", gy, ")"), absl::StrCat(plan.path_size()),
                    length, age, idle});
    }
  }
  if (env.csv()) return env.PrintCsv(table);
  env.out() << table.Aligned();
  return kExitOk;
}

// --- health ------------------------------------------------------------------

int Health(CommandEnv& env, Args args) {
  if (args.size() > 1) return env.Usage("health takes at most one SERVICE");
  const std::string service = args.empty() ? "" : args[0];
  absl::StatusOr<grpc::health::v1::HealthCheckResponse> response =
      env.client().CheckHealth(service);
  if (!response.ok()) return env.Fail(response.status());
  using grpc::health::v1::HealthCheckResponse;
  if (env.json()) {
    if (const int code = env.PrintJson(*response); code != kExitOk) return code;
  } else if (env.csv()) {
    Table table({"service", "status"});
    table.AddRow({service, HealthCheckResponse::ServingStatus_Name(response->status())});
    env.PrintCsv(table);
  } else {
    env.out() << HealthCheckResponse::ServingStatus_Name(response->status())
              << "\n";
  }
  // Probes (scripts, container health checks) read the exit code.
  return response->status() == HealthCheckResponse::SERVING ? kExitOk
                                                            : kExitError;
}

// --- metrics -----------------------------------------------------------------

// Appends what libcurl receives to a std::string.
size_t AppendToString(char* data, size_t size, size_t count, void* out) {
  static_cast<std::string*>(out)->append(data, size * count);
  return size * count;
}

// GET http://`address`/metrics; UNAVAILABLE when it cannot be fetched or the
// answer is not 200.
absl::StatusOr<std::string> FetchMetrics(const std::string& address,
                                         absl::Duration timeout) {
  const std::string url = absl::StrCat("http://", address, "/metrics");
  std::unique_ptr<CURL, decltype(&curl_easy_cleanup)> curl(curl_easy_init(),
                                                           &curl_easy_cleanup);
  if (curl == nullptr) return absl::InternalError("cannot initialise libcurl");
  std::string body;
  char curl_error[CURL_ERROR_SIZE] = {};
  curl_easy_setopt(curl.get(), CURLOPT_URL, url.c_str());
  curl_easy_setopt(curl.get(), CURLOPT_WRITEFUNCTION, &AppendToString);
  curl_easy_setopt(curl.get(), CURLOPT_WRITEDATA, &body);
  curl_easy_setopt(curl.get(), CURLOPT_ERRORBUFFER, curl_error);
  curl_easy_setopt(curl.get(), CURLOPT_TIMEOUT_MS,
                   static_cast<long>(absl::ToInt64Milliseconds(timeout)));
  // The endpoint may gzip the text when asked; "" accepts what libcurl can
  // decode.
  curl_easy_setopt(curl.get(), CURLOPT_ACCEPT_ENCODING, "");
  curl_easy_setopt(curl.get(), CURLOPT_NOSIGNAL, 1L);
  if (const CURLcode code = curl_easy_perform(curl.get()); code != CURLE_OK) {
    return absl::UnavailableError(absl::StrCat(
        "cannot fetch ", url, ": ",
        curl_error[0] != '\0' ? curl_error : curl_easy_strerror(code),
        " (is pathd running with --metrics_address=", address, "?)"));
  }
  long http_status = 0;
  curl_easy_getinfo(curl.get(), CURLINFO_RESPONSE_CODE, &http_status);
  if (http_status != 200) {
    return absl::UnavailableError(
        absl::StrCat("GET ", url, " answered HTTP ", http_status));
  }
  return body;
}

int Metrics(CommandEnv& env, Args args) {
  if (env.global().output != OutputFormat::kTable) {
    return env.Unsupported("metrics",
                           "it prints pathd's Prometheus text exposition, "
                           "which Prometheus tools read; use --output table");
  }
  absl::StatusOr<std::string> text =
      FetchMetrics(env.options().metrics.metrics_address, env.global().timeout);
  if (!text.ok()) return env.Fail(text.status());
  env.out() << FilterMetricsText(*text, std::vector<std::string>(args.begin(), args.end()));
  return kExitOk;
}

}  // namespace

std::string FilterMetricsText(absl::string_view text,
                              const std::vector<std::string>& prefixes) {
  if (prefixes.empty()) return std::string(text);
  std::string filtered;
  for (absl::string_view line : absl::StrSplit(text, '\n', absl::SkipEmpty())) {
    // "# HELP name ...", "# TYPE name ..." or "name{labels} value".
    absl::string_view name = line;
    if (absl::ConsumePrefix(&name, "# HELP ") || absl::ConsumePrefix(&name, "# TYPE ")) {
      name = name.substr(0, name.find(' '));
    } else {
      name = name.substr(0, name.find_first_of("{ "));
    }
    for (const std::string& prefix : prefixes) {
      if (absl::StartsWith(name, prefix)) {
        absl::StrAppend(&filtered, line, "\n");
        break;
      }
    }
  }
  return filtered;
}

namespace {

constexpr absl::string_view kMetricsFlags[] = {"metrics_address"};

}  // namespace

const Command kCacheStatsCommand = {
    .name = "cache-stats",
    .synopsis = "",
    .help = "Prints the server's caches (cost-to-go fields, D* Lite state, inflated\n"
            "maps, ...): entries, bytes of their budget, hits, misses, evictions,\n"
            "repairs and rebuilds, and the open Navigate sessions.",
    .flags = {},
    .run = CacheStats,
};

const Command kSessionsCommand = {
    .name = "sessions",
    .synopsis = "[NAME]",
    .help = "Lists the open Navigate sessions (of map NAME, or of every map): where\n"
            "each robot is, its goal, its current path's cells and length, and how\n"
            "long since it opened and since its last message (ListSessions).",
    .flags = {},
    .run = Sessions,
};

const Command kHealthCommand = {
    .name = "health",
    .synopsis = "[SERVICE]",
    .help = "Asks the gRPC health service whether SERVICE (default: the whole\n"
            "server) is SERVING; exit code 1 when it is not.",
    .flags = {},
    .run = Health,
};

const Command kMetricsCommand = {
    .name = "metrics",
    .synopsis = "[PREFIX ...] [--metrics_address HOST:PORT]",
    .help = "Prints pathd's Prometheus text (GET http://HOST:PORT/metrics, the\n"
            "daemon's --metrics_address; default 127.0.0.1:9464); with PREFIX\n"
            "arguments only the metrics whose name starts with one of them. Plain\n"
            "HTTP: no TLS, no token.",
    .flags = kMetricsFlags,
    .run = Metrics,
    .connects = false,
};

}  // namespace pathd::pathctl
