// pathctl bench: a closed-loop load of Plan calls (load_generator.h) on a
// map's random free-cell pairs or a Moving AI scenario file, reported as
// attempts, goodput, latency percentiles and errors by code.
#include <algorithm>
#include <filesystem>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "client/pathctl/map_source.h"
#include "client/pathctl/command.h"
#include "client/pathctl/files.h"
#include "client/pathctl/load_generator.h"
#include "client/pathctl/map_name.h"
#include "client/pathctl/progress.h"
#include "core/map_io/map_io.h"
#include "core/status_macros.h"
#include "google/protobuf/struct.pb.h"

namespace pathd::pathctl {
namespace {

// Distinct random queries when a map has no scenario file; the load cycles
// through them.
constexpr int kRandomQueries = 1000;

// Where the benchmark's queries come from, for the report.
struct BenchQueries {
  std::vector<v1::PlanRequest> requests;
  std::string source;
};

// `count` start/goal pairs drawn uniformly (fixed seed) from the cells a
// robot centre may occupy on `map`; pairs in different components make
// NO_PATH answers, which the report counts.
absl::StatusOr<std::vector<std::pair<v1::Cell, v1::Cell>>> RandomEndpoints(
    const v1::GetMapResponse& map, bool unknown_is_free, uint64_t seed, int count) {
  std::vector<int64_t> free_cells;
  const std::string& cells = map.cells();
  for (size_t i = 0; i < cells.size(); ++i) {
    const auto cost = static_cast<uint8_t>(cells[i]);
    if (cost < 253 || (cost == 255 && unknown_is_free)) {
      free_cells.push_back(static_cast<int64_t>(i));
    }
  }
  if (free_cells.empty()) {
    return absl::FailedPreconditionError(
        absl::StrCat("map ", map.info().name(), " has no free cell to plan between"));
  }
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<size_t> pick(0, free_cells.size() - 1);
  const int64_t width = map.info().width();
  auto cell = [&] {
    const int64_t i = free_cells[pick(rng)];
    v1::Cell c;
    c.set_x(static_cast<int32_t>(i % width));
    c.set_y(static_cast<int32_t>(i / width));
    return c;
  };
  std::vector<std::pair<v1::Cell, v1::Cell>> pairs;
  for (int q = 0; q < count; ++q) {
    v1::Cell start = cell();
    pairs.emplace_back(std::move(start), cell());
  }
  return pairs;
}

v1::Cell ToProtoCell(const Cell& cell) {
  v1::Cell c;
  c.set_x(cell.x);
  c.set_y(cell.y);
  return c;
}

// Loads --movingai into the server as `name` (replacing it) and returns its
// scenario file's pairs, or, when the map has none, random ones.
absl::StatusOr<std::vector<std::pair<v1::Cell, v1::Cell>>> MovingAiEndpoints(
    CommandEnv& env, const std::string& name, std::string* source) {
  const BenchOptions& options = env.options().bench;
  v1::CreateMapRequest create;
  create.set_name(name);
  create.set_replace(true);
  PATHD_RETURN_IF_ERROR(SetMapSourceFromFile(options.movingai, &create));
  PATHD_RETURN_IF_ERROR(env.client().CreateMap(create).status());
  const std::string scen = options.movingai + ".scen";
  absl::StatusOr<std::string> text = ReadTextFile(scen);
  if (!text.ok()) {
    PATHD_ASSIGN_OR_RETURN(v1::GetMapResponse map, env.client().DownloadMap(name));
    *source = absl::StrCat(kRandomQueries, " random pairs of free cells (no ", scen, ")");
    return RandomEndpoints(map, env.options().cost.unknown_is_free, options.seed, kRandomQueries);
  }
  PATHD_ASSIGN_OR_RETURN(std::vector<Scenario> scenarios,
                         ParseMovingAiScenarios(*text, scen));
  if (scenarios.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(scen, " has no scenarios"));
  }
  std::vector<std::pair<v1::Cell, v1::Cell>> pairs;
  for (const Scenario& s : scenarios) {
    pairs.emplace_back(ToProtoCell(s.start), ToProtoCell(s.goal));
  }
  *source = absl::StrCat(scenarios.size(), " scenarios of ", scen);
  return pairs;
}

// The request every benchmark query shares: map, planner and cost options.
// INVALID_ARGUMENT (a usage error) for a bad planner or option.
absl::StatusOr<v1::PlanRequest> BenchBaseRequest(const PlanFlags& options,
                                                 const CostOptions& cost,
                                                 const std::string& name) {
  v1::PlanRequest base;
  base.set_map(name);
  if (!options.planner.empty()) {
    PATHD_ASSIGN_OR_RETURN(v1::Planner planner, PlannerFromName(options.planner));
    base.set_planner(planner);
  }
  PATHD_RETURN_IF_ERROR(SetCostOptions(cost, base.mutable_options()));
  PATHD_RETURN_IF_ERROR(SetPathEncoding(options.path_encoding, base.mutable_options()));
  base.mutable_options()->set_max_expansions(options.max_expansions);
  if (options.heuristic_weight.has_value()) {
    base.mutable_options()->set_heuristic_weight(*options.heuristic_weight);
  }
  return base;
}

// The plan requests of a benchmark: `base` between each pair, shuffled with
// --seed so a time-bounded run samples the whole list (scenario files are
// sorted by length).
absl::StatusOr<BenchQueries> MakeBenchQueries(CommandEnv& env, const v1::PlanRequest& base) {
  const BenchOptions& options = env.options().bench;
  const std::string& name = base.map();
  BenchQueries queries;
  std::vector<std::pair<v1::Cell, v1::Cell>> pairs;
  if (!options.movingai.empty()) {
    PATHD_ASSIGN_OR_RETURN(pairs, MovingAiEndpoints(env, name, &queries.source));
  } else {
    // Through the stream, so a map of any size can be benchmarked.
    PATHD_ASSIGN_OR_RETURN(v1::GetMapResponse map, env.client().DownloadMap(name));
    PATHD_ASSIGN_OR_RETURN(pairs, RandomEndpoints(map, env.options().cost.unknown_is_free,
                                                  options.seed, kRandomQueries));
    queries.source = absl::StrCat(kRandomQueries, " random pairs of free cells");
  }
  std::mt19937_64 rng(options.seed);
  std::shuffle(pairs.begin(), pairs.end(), rng);
  for (auto& [start, goal] : pairs) {
    v1::PlanRequest& request = queries.requests.emplace_back(base);
    *request.mutable_start()->mutable_cell() = std::move(start);
    *request.mutable_goal()->mutable_cell() = std::move(goal);
  }
  return queries;
}

// The progress bar of a benchmark, fed by RunPlanLoad about once a second:
// elapsed of --warmup, then elapsed of --duration (requests of --requests
// when the run is bounded by a count only), with the requests, the current
// rate and the errors as its detail.
class BenchProgress {
 public:
  explicit BenchProgress(CommandEnv& env) : env_(env) {}

  void Update(const client::LoadProgress& p) {
    const BenchOptions& options = env_.options().bench;
    const bool by_count = !p.warming_up && options.duration == absl::ZeroDuration();
    if (bar_ == nullptr || p.warming_up != warming_up_) {
      if (bar_ != nullptr) bar_->Finish();
      warming_up_ = p.warming_up;
      last_requests_ = 0;
      last_elapsed_ = absl::ZeroDuration();
      const double total =
          p.warming_up ? absl::ToDoubleSeconds(options.warmup)
          : by_count   ? static_cast<double>(options.requests)
                       : absl::ToDoubleSeconds(options.duration);
      // The phase began p.elapsed ago, so the bar shows at once and its own
      // rate (for --requests) counts from the phase's start.
      bar_ = std::make_unique<ProgressBar>(
          env_.err(), p.warming_up ? "warm-up" : "bench  ", total,
          by_count ? ProgressBar::Unit::kCount : ProgressBar::Unit::kSeconds,
          true, &absl::Now, absl::Now() - p.elapsed);
    }
    const double seconds = absl::ToDoubleSeconds(p.elapsed - last_elapsed_);
    const double rate =
        seconds > 0 ? static_cast<double>(p.requests - last_requests_) / seconds : 0;
    last_requests_ = p.requests;
    last_elapsed_ = p.elapsed;
    bar_->Update(by_count ? static_cast<double>(p.requests)
                          : absl::ToDoubleSeconds(p.elapsed),
                 absl::StrFormat("%d requests  %.0f req/s now  %d errors",
                                 p.requests, rate, p.errors));
  }

  // Ends the bar's line so the report starts on a fresh one; a completed
  // run's bar shows its final figures rather than the last second's.
  void Close(const absl::StatusOr<client::LoadReport>& report) {
    if (bar_ == nullptr) return;
    if (report.ok() && !warming_up_) {
      const bool by_count = env_.options().bench.duration == absl::ZeroDuration();
      bar_->Update(by_count ? static_cast<double>(report->requests)
                            : absl::ToDoubleSeconds(report->elapsed),
                   absl::StrFormat("%d requests  %.0f req/s  %d errors",
                                   report->requests, report->requests_per_second,
                                   report->errors()));
    }
    bar_->Finish();
  }

 private:
  CommandEnv& env_;
  std::unique_ptr<ProgressBar> bar_;
  bool warming_up_ = false;
  int64_t last_requests_ = 0;
  absl::Duration last_elapsed_;
};

double Micros(absl::Duration d) { return absl::ToDoubleMicroseconds(d); }

int PrintBenchJson(CommandEnv& env, const std::string& name, const std::string& source,
                   const client::LoadReport& report) {
  const BenchOptions& options = env.options().bench;
  google::protobuf::Struct json;
  auto& fields = *json.mutable_fields();
  fields["map"].set_string_value(name);
  const std::string& planner = env.options().plan.planner;
  fields["planner"].set_string_value(planner.empty() ? "default" : planner);
  fields["queries"].set_string_value(source);
  fields["concurrency"].set_number_value(options.concurrency);
  fields["channels"].set_number_value(options.channels);
  fields["elapsed_s"].set_number_value(absl::ToDoubleSeconds(report.elapsed));
  fields["requests"].set_number_value(static_cast<double>(report.requests));
  fields["ok"].set_number_value(static_cast<double>(report.ok));
  fields["no_path"].set_number_value(static_cast<double>(report.no_path));
  fields["errors"].set_number_value(static_cast<double>(report.errors()));
  auto& by_code = *fields["errors_by_code"].mutable_struct_value()->mutable_fields();
  for (size_t c = 0; c < report.errors_by_code.size(); ++c) {
    if (report.errors_by_code[c] == 0) continue;
    by_code[absl::StatusCodeToString(static_cast<absl::StatusCode>(c))]
        .set_number_value(static_cast<double>(report.errors_by_code[c]));
  }
  fields["requests_per_second"].set_number_value(report.requests_per_second);
  fields["goodput_per_second"].set_number_value(report.goodput_per_second);
  fields["backoff_waits"].set_number_value(static_cast<double>(report.backoff_waits));
  fields["backoff_s"].set_number_value(absl::ToDoubleSeconds(report.backoff_time));
  auto& latency = *fields["latency_us"].mutable_struct_value()->mutable_fields();
  latency["min"].set_number_value(Micros(report.latency.min));
  latency["mean"].set_number_value(Micros(report.latency.mean));
  latency["p50"].set_number_value(Micros(report.latency.p50));
  latency["p95"].set_number_value(Micros(report.latency.p95));
  latency["p99"].set_number_value(Micros(report.latency.p99));
  latency["max"].set_number_value(Micros(report.latency.max));
  return env.PrintJson(json);
}

// "CODE N" for every status code the load saw errors of.
std::vector<std::string> ErrorsByCode(const client::LoadReport& report) {
  std::vector<std::string> errors;
  for (size_t c = 0; c < report.errors_by_code.size(); ++c) {
    if (report.errors_by_code[c] == 0) continue;
    errors.push_back(absl::StrCat(
        absl::StatusCodeToString(static_cast<absl::StatusCode>(c)), " ",
        report.errors_by_code[c]));
  }
  return errors;
}

// One row of figures, the same as --json's (latencies in microseconds, of
// the OK answers); errors by code as "CODE N" pairs separated by spaces.
int PrintBenchCsv(CommandEnv& env, const std::string& name, const std::string& source,
                  const client::LoadReport& report) {
  const BenchOptions& options = env.options().bench;
  const std::vector<std::string> errors = ErrorsByCode(report);
  const client::LatencySummary& l = report.latency;
  Table table({"map", "planner", "queries", "concurrency", "channels", "elapsed_s",
               "requests", "ok", "no_path", "errors", "errors_by_code",
               "requests_per_second", "latency_min_us", "latency_mean_us",
               "latency_p50_us", "latency_p95_us", "latency_p99_us",
               "latency_max_us", "goodput_per_second", "backoff_waits",
               "backoff_s"});
  const std::string& planner = env.options().plan.planner;
  table.AddRow({name, planner.empty() ? "default" : planner, source,
                absl::StrCat(options.concurrency), absl::StrCat(options.channels),
                FormatNumber(absl::ToDoubleSeconds(report.elapsed)),
                absl::StrCat(report.requests), absl::StrCat(report.ok),
                absl::StrCat(report.no_path), absl::StrCat(report.errors()),
                absl::StrJoin(errors, " "), FormatNumber(report.requests_per_second),
                FormatNumber(Micros(l.min)), FormatNumber(Micros(l.mean)),
                FormatNumber(Micros(l.p50)), FormatNumber(Micros(l.p95)),
                FormatNumber(Micros(l.p99)), FormatNumber(Micros(l.max)),
                FormatNumber(report.goodput_per_second),
                absl::StrCat(report.backoff_waits),
                FormatNumber(absl::ToDoubleSeconds(report.backoff_time))});
  return env.PrintCsv(table);
}

void PrintBenchText(CommandEnv& env, const std::string& name, const std::string& source,
                    const client::LoadReport& report) {
  const BenchOptions& options = env.options().bench;
  const std::vector<std::string> errors = ErrorsByCode(report);
  const client::LatencySummary& l = report.latency;
  env.out() << absl::StrFormat(
      "map:         %s\n"
      "planner:     %s\n"
      "queries:     %s\n"
      "load:        %d concurrent requests over %d channel(s), %.2f s measured\n"
      "requests:    %d (%d ok, %d of them without a path; %d errors)\n"
      "throughput:  %.1f requests/s attempted, goodput %.1f ok answers/s\n"
      "latency us:  p50 %.0f  p95 %.0f  p99 %.0f  max %.0f  (min %.0f, mean %.0f; "
      "ok answers)\n"
      "errors:      %s\n"
      "back-off:    %s\n",
      name,
      env.options().plan.planner.empty() ? "the server's default"
                                         : env.options().plan.planner,
      source, options.concurrency, options.channels,
      absl::ToDoubleSeconds(report.elapsed), report.requests, report.ok,
      report.no_path, report.errors(), report.requests_per_second,
      report.goodput_per_second, Micros(l.p50), Micros(l.p95), Micros(l.p99),
      Micros(l.max), Micros(l.min), Micros(l.mean),
      errors.empty() ? "none" : absl::StrJoin(errors, ", "),
      report.backoff_waits == 0
          ? std::string("none")
          : absl::StrFormat("%d waits, %.2f s in all (retry-after-ms hints of "
                            "RESOURCE_EXHAUSTED, exponential on UNAVAILABLE)",
                            report.backoff_waits,
                            absl::ToDoubleSeconds(report.backoff_time)));
}

int Bench(CommandEnv& env, Args args) {
  const BenchOptions& options = env.options().bench;
  std::string name;
  if (!options.movingai.empty()) {
    if (args.size() > 1) return env.Usage("bench --movingai FILE takes at most one NAME");
    if (DetectMapFileKind(options.movingai) != MapFileKind::kMovingAi) {
      return env.Usage(absl::StrCat("--movingai ", options.movingai,
                                    ": expected a Moving AI .map file"));
    }
    name = args.empty() ? std::filesystem::path(options.movingai).stem().string()
                        : args[0];
  } else {
    if (args.size() != 1) return env.Usage("bench takes NAME (or --movingai FILE)");
    name = args[0];
  }
  if (options.concurrency < 1) return env.Usage("--concurrency must be at least 1");
  if (options.channels < 1) return env.Usage("--channels must be at least 1");
  if (options.requests < 0) return env.Usage("--requests must not be negative");
  if (options.duration < absl::ZeroDuration() || options.warmup < absl::ZeroDuration()) {
    return env.Usage("--duration and --warmup must not be negative");
  }
  if (options.duration == absl::ZeroDuration() && options.requests == 0) {
    return env.Usage("--duration 0 needs --requests N, or the load never ends");
  }
  if (absl::Status s = ValidateMapName(name); !s.ok()) return env.Fail(s);
  absl::StatusOr<v1::PlanRequest> base = BenchBaseRequest(env.options().plan, env.options().cost, name);
  if (!base.ok()) return env.Usage(base.status().message());
  absl::StatusOr<BenchQueries> queries = MakeBenchQueries(env, *base);
  if (!queries.ok()) return env.Fail(queries.status());

  client::LoadOptions load;
  load.concurrency = options.concurrency;
  load.duration = options.duration;
  load.max_requests = options.requests;
  load.warmup = options.warmup;
  BenchProgress bar(env);
  std::function<void(const client::LoadProgress&)> progress;
  if (env.global().progress_bars) {
    progress = [&bar](const client::LoadProgress& p) { bar.Update(p); };
  }
  absl::StatusOr<client::LoadReport> report =
      client::RunPlanLoad(env.global().server, env.credentials(), options.channels,
                          env.global().timeout, queries->requests, load, progress);
  bar.Close(report);
  if (!report.ok()) return env.Fail(report.status());
  if (env.json()) return PrintBenchJson(env, name, queries->source, *report);
  if (env.csv()) return PrintBenchCsv(env, name, queries->source, *report);
  PrintBenchText(env, name, queries->source, *report);
  return kExitOk;
}

constexpr absl::string_view kBenchFlags[] = {
    "concurrency", "duration", "warmup", "requests", "channels", "movingai", "seed",
    "planner", "max_expansions", "heuristic_weight", "connectivity", "cost_weight",
    "unknown_is_free", "robot_radius", "robot_radius_cells", "min_clearance",
    "min_clearance_cells", "inflation_radius",
    "inflation_radius_cells", "cost_scaling_factor", "path_encoding"};

}  // namespace

const Command kBenchCommand = {
    .name = "bench",
    .synopsis = "NAME [--concurrency N] [--duration T] [--warmup T]\n"
                " [--requests N] [--channels K] [--seed S]\n"
                " [--planner P] [cost options]\n"
                "[NAME] --movingai FILE.map [...]",
    .help = "Runs a closed-loop load of Plan calls: --concurrency workers, each\n"
            "sending its next request when the previous answer arrived. The queries\n"
            "are --movingai's scenarios or 1000 random pairs of free cells of NAME.\n"
            "A refused call (RESOURCE_EXHAUSTED) waits the server's retry-after-ms\n"
            "hint and an unreachable server (UNAVAILABLE) an exponential back-off\n"
            "with jitter. Prints attempts and goodput (OK answers/s) apart, latency\n"
            "percentiles of the OK answers, errors by code and the back-off waits.",
    .flags = kBenchFlags,
    .run = Bench,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
