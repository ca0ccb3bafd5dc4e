// geometric_bench: the geometric planners against the grid ones on the
// Moving AI maps, printed as markdown tables (figures, not assertions;
// docs/performance.md records them with the command that produced them):
//  1. per map and planner, on a sample of scenarios spread over the whole
//     scenario file: queries, paths found, mean and p95 microseconds per
//     query with the planner's structure already built (each planner gets
//     an AdvancingStore per map, as the server's cache would be; the first
//     query, which builds it, is timed apart), mean length over the grid
//     optimum stored in the .scen file;
//  2. per map, every structure kind DescribeStructure knows
//     (core/geometry/structure.h): its counts, memory and build time;
//  3. on a map scaled to --advance_size cells square, each geometric
//     planner's derived structures rebuilt against advanced (through the
//     planner's own recipe, tests/testing/advancing_store.h) after 1, 10 and
//     100 random changed cells.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/match.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "core/geometry/structure.h"
#include "core/map_io/map_io.h"
#include "core/planners/hierarchical/hpa_graph.h"
#include "core/planners/hierarchical/hpa_star.h"
#include "core/planners/hierarchical/quadtree.h"
#include "core/postprocess/path_simplify.h"
#include "core/search/planner.h"
#include "core/search/registry.h"
#include "tests/bench/movingai_maps.h"
#include "tests/testing/advancing_store.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map and <map>.map.scen files");
ABSL_FLAG(std::string, maps, "",
          "comma-separated map paths relative to --movingai_dir; empty = every map");
ABSL_FLAG(std::string, planners,
          "astar,theta_star,navmesh,minimal_construct,visibility_graph",
          "comma-separated planner names for the query table; NAME/nostore "
          "runs NAME without a derived store (each query builds what it "
          "needs, as a robot linking core would), so a planner's shared "
          "per-version structure can be compared with none in one run");
ABSL_FLAG(int, sample, 1000,
          "scenarios per map, spread evenly over the whole scenario file");
ABSL_FLAG(double, query_budget_s, 30.0,
          "stop a planner's queries on a map after this many seconds (the row "
          "then says how many ran)");
ABSL_FLAG(std::string, skip, "",
          "comma-separated planner@map pairs to leave out (structures too slow to "
          "build), e.g. visibility_graph@maze/maze512-1-0.map");
ABSL_FLAG(bool, structures, true, "print the structure table (section 2)");
ABSL_FLAG(std::string, advance_map, "street/Berlin_0_512.map",
          "map for section 3, scaled up (each cell repeated) to --advance_size; "
          "empty = skip section 3");
ABSL_FLAG(int, advance_size, 1024, "side of the section-3 map, cells");
// euclidean_spm is left out by default: its per-goal map has no advance and
// takes over a minute to build on a 1024 x 1024 map (84 s measured), so its
// row costs 10 such builds; its visibility graph is visibility_graph's.
ABSL_FLAG(std::string, advance_planners,
          "navmesh,minimal_construct,visibility_graph,trapezoidal,voronoi",
          "planners whose structures section 3 advances (euclidean_spm: see the comment)");
ABSL_FLAG(int, advance_repeats, 5, "advances measured per changed-cell count (median)");
ABSL_FLAG(std::string, tile_map, "",
          "section 4 (huge maps): a map tiled to --tile_sizes cells square by "
          "MirrorTile; empty = skip section 4");
ABSL_FLAG(std::string, tile_sizes, "4096,8192", "sides of the section-4 maps, cells");
ABSL_FLAG(std::string, tile_planners, "astar,jps,hpa_star,quadtree",
          "section-4 planners; the first is the baseline the others are compared with");
ABSL_FLAG(int, tile_queries, 20,
          "section-4 queries per map: random pairs of free cells at least a quarter "
          "of the side apart that hpa_star (complete) connects");
ABSL_FLAG(int, tile_repairs, 5, "section-4 map updates timed per kind (median)");

namespace fs = std::filesystem;

namespace {

using pathd::testing::AdvancingStore;


// A registered planner, or `hpa_star:N` / `hpa_star:N:edges`: HPA* with
// N x N clusters, refined in the corridor or edge by edge (made here, kept
// for the run), so sizes and refinements can be compared in one run.
const pathd::Planner* PlannerByName(const std::string& name) {
  static std::map<std::string, std::unique_ptr<pathd::Planner>>* made =
      new std::map<std::string, std::unique_ptr<pathd::Planner>>();
  const std::vector<std::string> parts = absl::StrSplit(name, ':');
  int size = 0;
  if (parts.size() >= 2 && parts[0] == "hpa_star" && absl::SimpleAtoi(parts[1], &size) &&
      size >= 2 && (parts.size() == 2 || (parts.size() == 3 && parts[2] == "edges"))) {
    auto& planner = (*made)[name];
    if (planner == nullptr) {
      planner = pathd::MakeHpaStarPlanner(size, parts.size() == 3
                                                    ? pathd::HpaRefinement::kPerEdge
                                                    : pathd::HpaRefinement::kCorridor);
    }
    return planner.get();
  }
  return pathd::PlannerRegistry::Default().Get(name);
}

// A store holding one value made beforehand, for timing queries apart from
// the build of what they use.
class FixedStore : public pathd::DerivedStore {
 public:
  explicit FixedStore(std::shared_ptr<const void> value) : value_(std::move(value)) {}
  std::shared_ptr<const void> Get(const std::string&, const pathd::DerivedRecipe&,
                                  pathd::DerivedStop&) override {
    return value_;
  }

 private:
  std::shared_ptr<const void> value_;
};

struct QueryFigures {
  int queries = 0;
  int found = 0;
  double mean_us = 0;
  double p95_us = 0;
  double length_ratio = 0;
  double max_ratio = 0;
  // After SimplifyPath (core/postprocess), outside the timed part.
  double smoothed_ratio = 0;
  double smoothed_max = 0;
  double first_ms = 0;
  bool budget_hit = false;
};

pathd::PlanRequest GeometricRequest(pathd::Cell s, pathd::Cell g) {
  pathd::CostParams cost;
  cost.cost_weight = 0.0;  // the geometric planners' uniform cost
  return pathd::PlanRequest::Between(s, g, cost);
}

QueryFigures RunQueries(const pathd::Planner& planner, const pathd::Grid& grid,
                        const std::vector<pathd::Scenario>& scenarios, bool use_store,
                        pathd::SearchScratch& scratch) {
  QueryFigures f;
  AdvancingStore store;
  store.SetGrid(grid);
  pathd::DerivedStore* const derived = use_store ? &store : nullptr;
  // The first query builds the structure.
  {
    pathd::PlanRequest request = GeometricRequest(scenarios[0].start, scenarios[0].goal);
    request.derived = derived;
    const absl::Time t0 = absl::Now();
    auto r = planner.Plan(grid, request, pathd::StopCondition::None(), scratch);
    f.first_ms = absl::ToDoubleMilliseconds(absl::Now() - t0);
    if (!r.ok()) {
      std::fprintf(stderr, "%s: %s\n", std::string(planner.name()).c_str(),
                   std::string(r.status().message()).c_str());
      return QueryFigures{};
    }
  }
  const absl::Duration budget = absl::Seconds(absl::GetFlag(FLAGS_query_budget_s));
  std::vector<double> micros;
  double ratio = 0, smoothed = 0;
  const absl::Time started = absl::Now();
  for (const pathd::Scenario& s : scenarios) {
    if (absl::Now() - started > budget) {
      f.budget_hit = true;
      break;
    }
    pathd::PlanRequest request = GeometricRequest(s.start, s.goal);
    request.derived = derived;
    const absl::Time t0 = absl::Now();
    auto r = planner.Plan(grid, request, pathd::StopCondition::None(), scratch);
    micros.push_back(absl::ToDoubleMicroseconds(absl::Now() - t0));
    if (r.ok() && r->found()) {
      ++f.found;
      const double opt = s.optimal_length > 0 ? s.optimal_length : 1.0;
      const double q = s.optimal_length > 0 ? r->length / opt : 1.0;
      ratio += q;
      f.max_ratio = std::max(f.max_ratio, q);
      pathd::PlanResult copy = *std::move(r);
      pathd::SimplifyPath(grid, request.cost, &copy);
      const double sq = s.optimal_length > 0 ? copy.length / opt : 1.0;
      smoothed += sq;
      f.smoothed_max = std::max(f.smoothed_max, sq);
    }
  }
  f.queries = static_cast<int>(micros.size());
  if (micros.empty()) return f;
  double sum = 0;
  for (double m : micros) sum += m;
  f.mean_us = sum / micros.size();
  std::sort(micros.begin(), micros.end());
  f.p95_us = micros[std::min(micros.size() - 1, micros.size() * 95 / 100)];
  f.length_ratio = f.found > 0 ? ratio / f.found : 0;
  f.smoothed_ratio = f.found > 0 ? smoothed / f.found : 0;
  return f;
}

std::vector<pathd::Scenario> Spread(const std::vector<pathd::Scenario>& all, int n) {
  if (n <= 0 || static_cast<int>(all.size()) <= n) return all;
  std::vector<pathd::Scenario> out;
  const double stride = static_cast<double>(all.size()) / n;
  for (int i = 0; i < n; ++i) out.push_back(all[static_cast<size_t>(i * stride + stride / 2)]);
  return out;
}

// Each cell repeated k x k, k = size / max(width, height) (at least 1).
pathd::Grid ScaleUp(const pathd::Grid& grid, int size) {
  const int k = std::max(1, size / std::max(grid.width(), grid.height()));
  pathd::Grid out = *pathd::Grid::Create(grid.width() * k, grid.height() * k);
  for (int y = 0; y < out.height(); ++y) {
    for (int x = 0; x < out.width(); ++x) out.set_cost(x, y, grid.cost(x / k, y / k));
  }
  return out;
}

double Median(std::vector<double> v) {
  if (v.empty()) return -1;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

std::string Ms(double ms) {
  if (ms < 0) return "-";
  if (ms < 10) return absl::StrFormat("%.3f", ms);
  return absl::StrFormat("%.1f", ms);
}

// Section 3 for one planner: builds on `base`, then chains
// advance_repeats updates of n random changed cells for n = 1, 10, 100
// (never the query's endpoints), timing every structure the planner asks
// for. Prints one row per structure key.
void AdvanceRows(const pathd::Planner& planner, const pathd::Grid& base, pathd::Cell start,
                 pathd::Cell goal, pathd::SearchScratch& scratch) {
  AdvancingStore store;
  pathd::Grid grid = base;
  store.SetGrid(grid);
  pathd::PlanRequest request = GeometricRequest(start, goal);
  request.derived = &store;
  auto r = planner.Plan(grid, request, pathd::StopCondition::None(), scratch);
  if (!r.ok()) {
    std::printf("| %s | - | %s | | | | | |\n", std::string(planner.name()).c_str(),
                std::string(r.status().message()).c_str());
    return;
  }
  struct Row {
    double build_ms = -1;
    size_t bytes = 0;
    std::map<int, std::vector<double>> advance_ms;
    std::map<int, int> declined;
  };
  std::map<std::string, Row> rows;
  std::vector<std::string> order;
  size_t seen = 0;
  auto collect = [&](int n) {
    const std::vector<AdvancingStore::Event> events = store.events();
    for (; seen < events.size(); ++seen) {
      const AdvancingStore::Event& e = events[seen];
      if (!rows.contains(e.key)) order.push_back(e.key);
      Row& row = rows[e.key];
      const double ms = absl::ToDoubleMilliseconds(e.time);
      if (n == 0) {
        row.build_ms = ms;
        row.bytes = e.bytes;
      } else {
        row.advance_ms[n].push_back(ms);
        if (!e.advanced) row.declined[n]++;
      }
    }
  };
  collect(0);
  std::mt19937_64 rng(42);
  const int repeats = std::max(1, absl::GetFlag(FLAGS_advance_repeats));
  for (int n : {1, 10, 100}) {
    for (int rep = 0; rep < repeats; ++rep) {
      for (int k = 0; k < n; ++k) {
        pathd::Cell c{static_cast<int32_t>(rng() % grid.width()),
                      static_cast<int32_t>(rng() % grid.height())};
        if (c == start || c == goal) continue;
        grid.set_cost(c, grid.cost(c) == pathd::kFreeCost ? pathd::kLethalCost
                                                          : pathd::kFreeCost);
      }
      store.SetGrid(grid);
      auto again = planner.Plan(grid, request, pathd::StopCondition::None(), scratch);
      if (!again.ok()) {
        std::fprintf(stderr, "%s: %s\n", std::string(planner.name()).c_str(),
                     std::string(again.status().message()).c_str());
      }
      collect(n);
    }
  }
  if (order.empty()) {
    std::printf("| %s | (asks for no derived structure) | | | | | |\n",
                std::string(planner.name()).c_str());
  }
  for (const std::string& key : order) {
    const Row& row = rows[key];
    std::string cells[3];
    int i = 0;
    for (int n : {1, 10, 100}) {
      auto it = row.advance_ms.find(n);
      std::string text = it == row.advance_ms.end() ? "-" : Ms(Median(it->second));
      if (row.declined.contains(n)) {
        text += absl::StrFormat(" (rebuilt %d/%d)", row.declined.at(n),
                                static_cast<int>(it->second.size()));
      }
      cells[i++] = text;
    }
    std::printf("| %s | `%s` | %.1f | %s | %s | %s | %s |\n",
                std::string(planner.name()).c_str(), key.c_str(),
                static_cast<double>(row.bytes) / (1 << 20), Ms(row.build_ms).c_str(),
                cells[0].c_str(), cells[1].c_str(), cells[2].c_str());
    std::fflush(stdout);
  }
}


// The huge-map generator of section 4: `grid` repeated k x k times, k =
// size / max(width, height), every other copy mirrored (in x for odd tile
// columns, in y for odd tile rows) so each copy's edge meets its own mirror
// image and open edges join the copies (a plain repeat would put the
// map's right edge against its left one). The result is `size` square when
// the map is square and divides it.
pathd::Grid MirrorTile(const pathd::Grid& grid, int size) {
  const int k = std::max(1, size / std::max(grid.width(), grid.height()));
  const int w = grid.width(), h = grid.height();
  pathd::Grid out = *pathd::Grid::Create(w * k, h * k);
  for (int y = 0; y < out.height(); ++y) {
    const int ty = y / h;
    const int sy = ty % 2 == 0 ? y % h : h - 1 - y % h;
    for (int x = 0; x < out.width(); ++x) {
      const int tx = x / w;
      const int sx = tx % 2 == 0 ? x % w : w - 1 - x % w;
      out.set_cost(x, y, grid.cost(sx, sy));
    }
  }
  return out;
}

// Section 4 on one tiled map: the planners on the same long queries, the
// first as the baseline; hpa_star's graph build, memory and repairs.
void TiledRows(const std::string& map_name, const pathd::Grid& grid) {
  const std::vector<std::string> names =
      absl::StrSplit(absl::GetFlag(FLAGS_tile_planners), ',', absl::SkipEmpty());
  pathd::CostParams cost;
  cost.cost_weight = 0.0;
  // hpa_star's graph, built here to time it; its queries get it from a
  // FixedStore.
  const pathd::HpaParams params{pathd::kHpaDefaultClusterSize, cost};
  pathd::DerivedStop never;
  absl::Time t0 = absl::Now();
  std::shared_ptr<const pathd::HpaGraph> graph = pathd::HpaGraph::Build(grid, params, never);
  const double hpa_build_ms = absl::ToDoubleMilliseconds(absl::Now() - t0);
  FixedStore hpa_store(graph);
  const pathd::Planner* hpa = PlannerByName("hpa_star");
  // Queries hpa_star connects (it is complete: found <=> reachable), so the
  // baseline never searches a whole component in vain.
  pathd::SearchScratch scratch;
  std::mt19937_64 rng(20261202);
  std::vector<std::pair<pathd::Cell, pathd::Cell>> queries;
  const int want = absl::GetFlag(FLAGS_tile_queries);
  for (int tries = 0; static_cast<int>(queries.size()) < want && tries < 100 * want; ++tries) {
    const pathd::Cell s{static_cast<int32_t>(rng() % grid.width()),
                        static_cast<int32_t>(rng() % grid.height())};
    const pathd::Cell g{static_cast<int32_t>(rng() % grid.width()),
                        static_cast<int32_t>(rng() % grid.height())};
    if (grid.cost(s) != pathd::kFreeCost || grid.cost(g) != pathd::kFreeCost) continue;
    if (pathd::OctileDistance(s, g) < grid.width() / 4) continue;
    pathd::PlanRequest request = pathd::PlanRequest::Between(s, g, cost);
    request.derived = &hpa_store;
    auto r = hpa->Plan(grid, request, pathd::StopCondition::None(), scratch);
    if (r.ok() && r->found()) queries.emplace_back(s, g);
  }
  struct Answer {
    double us = 0;
    double cost = 0;
    double smoothed = 0;
  };
  std::vector<std::vector<Answer>> answers(names.size());
  for (size_t p = 0; p < names.size(); ++p) {
    const pathd::Planner* planner = PlannerByName(names[p]);
    if (planner == nullptr) continue;
    AdvancingStore store;
    store.SetGrid(grid);
    for (const auto& [s, g] : queries) {
      pathd::PlanRequest request = pathd::PlanRequest::Between(s, g, cost);
      // Every HPA* of the default cluster size shares the graph built above.
      const bool default_hpa = names[p] == "hpa_star" ||
                               absl::StartsWith(names[p], absl::StrFormat(
                                   "hpa_star:%d:", pathd::kHpaDefaultClusterSize)) ||
                               names[p] == absl::StrFormat("hpa_star:%d",
                                                           pathd::kHpaDefaultClusterSize);
      request.derived =
          default_hpa ? static_cast<pathd::DerivedStore*>(&hpa_store) : &store;
      const absl::Time t0 = absl::Now();
      auto r = planner->Plan(grid, request, pathd::StopCondition::None(), scratch);
      const double us = absl::ToDoubleMicroseconds(absl::Now() - t0);
      if (!r.ok() || !r->found()) {
        answers[p].push_back({us, -1, -1});
        continue;
      }
      const double c = r->cost;
      pathd::PlanResult copy = *std::move(r);
      pathd::SimplifyPath(grid, cost, &copy);
      answers[p].push_back({us, c, copy.length});
    }
    // The first query of a planner with a derived structure built it: its
    // time is in the build column, not the query columns.
    if (!answers[p].empty() && !store.events().empty()) {
      answers[p][0].us = -1;
    }
  }
  for (size_t p = 0; p < names.size(); ++p) {
    std::vector<double> us;
    double ratio = 0, worst = 0, sm = 0, sm_worst = 0;
    int n = 0;
    for (size_t q = 0; q < answers[p].size(); ++q) {
      const Answer& a = answers[p][q];
      const Answer& base = answers[0][q];
      if (a.us >= 0) us.push_back(a.us);
      if (a.cost < 0 || base.cost <= 0) continue;
      ratio += a.cost / base.cost;
      worst = std::max(worst, a.cost / base.cost);
      sm += a.smoothed / base.cost;
      sm_worst = std::max(sm_worst, a.smoothed / base.cost);
      ++n;
    }
    std::vector<double> base_us;
    for (const Answer& a : answers[0]) {
      if (a.us >= 0) base_us.push_back(a.us);
    }
    auto mean = [](const std::vector<double>& v) {
      double t = 0;
      for (double x : v) t += x;
      return v.empty() ? 0.0 : t / v.size();
    };
    std::sort(us.begin(), us.end());
    const double p95 = us.empty() ? 0 : us[std::min(us.size() - 1, us.size() * 95 / 100)];
    std::printf("| %s %dx%d | %s | %zu | %.2f | %.2f | %.1f | %.4f / %.4f | %.4f / %.4f |\n",
                map_name.c_str(), grid.width(), grid.height(), names[p].c_str(), us.size(),
                mean(us) / 1000, p95 / 1000, mean(us) > 0 ? mean(base_us) / mean(us) : 0.0,
                n > 0 ? ratio / n : 0.0, worst, n > 0 ? sm / n : 0.0, sm_worst);
    std::fflush(stdout);
  }
  // Repairs (Advance timed alone, with the changed cells a map store
  // records): a 10 x 10 block of cells toggled (100 cells), then 100 cells
  // scattered over the map, each on the last version; the same sequence
  // for hpa_star's graph and the quadtree.
  const int repeats = std::max(1, absl::GetFlag(FLAGS_tile_repairs));
  std::vector<pathd::Grid> versions;
  std::vector<std::vector<pathd::Cell>> updates;
  pathd::Grid live = grid;
  for (int i = 0; i < 2 * repeats; ++i) {
    std::vector<pathd::Cell> changed;
    if (i < repeats) {
      const int x0 = static_cast<int>(rng() % (live.width() - 10));
      const int y0 = static_cast<int>(rng() % (live.height() - 10));
      for (int y = y0; y < y0 + 10; ++y) {
        for (int x = x0; x < x0 + 10; ++x) changed.push_back({x, y});
      }
    } else {
      for (int k = 0; k < 100; ++k) {
        changed.push_back({static_cast<int32_t>(rng() % live.width()),
                           static_cast<int32_t>(rng() % live.height())});
      }
    }
    for (const pathd::Cell c : changed) {
      live.set_cost(c, live.cost(c) == pathd::kFreeCost ? pathd::kLethalCost
                                                        : pathd::kFreeCost);
    }
    versions.push_back(live);
    updates.push_back(std::move(changed));
  }
  std::vector<double> block_ms, scattered_ms;
  for (size_t i = 0; i < versions.size(); ++i) {
    t0 = absl::Now();
    std::shared_ptr<const pathd::HpaGraph> next = graph->Advance(versions[i], updates[i], never);
    (static_cast<int>(i) < repeats ? block_ms : scattered_ms)
        .push_back(absl::ToDoubleMilliseconds(absl::Now() - t0));
    graph = std::move(next);
  }
  const size_t hpa_bytes = graph->MemoryBytes();
  std::printf("| %s %dx%d | hpa_star graph | build %.0f ms | %.1f MiB (%.2f bytes/cell), "
              "%zu nodes | repair 10x10 block %s ms | repair 100 scattered cells %s ms | | |\n",
              map_name.c_str(), grid.width(), grid.height(), hpa_build_ms,
              static_cast<double>(hpa_bytes) / (1 << 20),
              static_cast<double>(hpa_bytes) / static_cast<double>(grid.size()),
              graph->node_count(), Ms(Median(block_ms)).c_str(), Ms(Median(scattered_ms)).c_str());
  if (std::find(names.begin(), names.end(), "quadtree") != names.end()) {
    t0 = absl::Now();
    std::shared_ptr<const pathd::Quadtree> tree = pathd::Quadtree::Build(grid, false, never);
    const double build_ms = absl::ToDoubleMilliseconds(absl::Now() - t0);
    block_ms.clear();
    scattered_ms.clear();
    for (size_t i = 0; i < versions.size(); ++i) {
      t0 = absl::Now();
      std::shared_ptr<const pathd::Quadtree> next = tree->Advance(versions[i], updates[i]);
      (static_cast<int>(i) < repeats ? block_ms : scattered_ms)
          .push_back(absl::ToDoubleMilliseconds(absl::Now() - t0));
      tree = std::move(next);
    }
    std::printf("| %s %dx%d | quadtree | build %.0f ms | %.1f MiB (%.2f bytes/cell), "
                "%zu leaves | repair 10x10 block %s ms | repair 100 scattered cells %s ms | | |\n",
                map_name.c_str(), grid.width(), grid.height(), build_ms,
                static_cast<double>(tree->MemoryBytes()) / (1 << 20),
                static_cast<double>(tree->MemoryBytes()) / static_cast<double>(grid.size()),
                tree->leaf_count(), Ms(Median(block_ms)).c_str(),
                Ms(Median(scattered_ms)).c_str());
  }
  std::fflush(stdout);
}
}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "geometric_bench [--movingai_dir DIR] [--maps a.map,...] [--planners ...] "
      "[--sample N] [--query_budget_s S] [--skip planner@map,...] [--structures] "
      "[--advance_map MAP] [--advance_size N] [--advance_planners ...] "
      "[--tile_map MAP --tile_sizes 4096,8192 --tile_planners astar,jps,hpa_star]\n"
      "Prints markdown tables: geometric vs grid planners per Moving AI map, "
      "structure sizes and build times, advance vs rebuild.");
  absl::ParseCommandLine(argc, argv);
  const fs::path root = absl::GetFlag(FLAGS_movingai_dir);
  if (!fs::is_directory(root)) {
    std::printf("Moving AI benchmarks not found at %s; nothing to measure\n", root.c_str());
    return 0;
  }
  const pathd::PlannerRegistry& registry = pathd::PlannerRegistry::Default();
  const std::vector<std::string> maps =
      pathd::bench::MovingAiMaps(root, absl::GetFlag(FLAGS_maps));
  std::vector<std::string> planners;
  const std::vector<std::string> listed =
      absl::StrSplit(absl::GetFlag(FLAGS_planners), ',', absl::SkipEmpty());
  for (const std::string& name : listed) {
    if (PlannerByName(std::string(absl::StripSuffix(name, "/nostore"))) == nullptr) {
      std::printf("(planner %s is not registered; left out)\n", name.c_str());
    } else {
      planners.push_back(name);
    }
  }
  const std::vector<std::string> skip =
      absl::StrSplit(absl::GetFlag(FLAGS_skip), ',', absl::SkipEmpty());
  std::printf("geometric_bench: %u hardware threads, single-threaded queries, sample %d, "
              "query budget %.0f s per planner and map\n\n",
              std::thread::hardware_concurrency(), absl::GetFlag(FLAGS_sample),
              absl::GetFlag(FLAGS_query_budget_s));

  std::vector<std::pair<std::string, pathd::Grid>> grids;
  std::printf("### Queries (structure built by the first query, timed apart)\n\n");
  std::printf("| map | planner | queries | found | mean µs | p95 µs | length / grid optimum "
              "| first query (build) ms | max length / optimum | simplified: mean / max |\n");
  std::printf("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  pathd::SearchScratch scratch;
  for (const std::string& name : maps) {
    const fs::path map_path = root / name;
    auto grid = pathd::ReadMovingAiMapFile(map_path.string());
    auto file = pathd::ReadMovingAiScenarioFileWithVersion(map_path.string() + ".scen");
    if (!grid.ok() || !file.ok()) {
      std::fprintf(stderr, "%s: cannot read the map or its scenarios\n", name.c_str());
      return 1;
    }
    const std::vector<pathd::Scenario> scenarios =
        Spread(file->scenarios, absl::GetFlag(FLAGS_sample));
    for (const std::string& planner_name : planners) {
      if (std::find(skip.begin(), skip.end(), planner_name + "@" + name) != skip.end()) {
        std::printf("| %s | %s | skipped (--skip) | | | | | |\n", name.c_str(),
                    planner_name.c_str());
        continue;
      }
      const bool use_store = !absl::EndsWith(planner_name, "/nostore");
      const QueryFigures f =
          RunQueries(*PlannerByName(std::string(absl::StripSuffix(planner_name, "/nostore"))),
                     *grid, scenarios, use_store, scratch);
      std::printf("| %s | %s | %d%s | %d | %.1f | %.1f | %.4f | %s | %.4f | %.4f / %.4f |\n",
                  name.c_str(), planner_name.c_str(), f.queries,
                  f.budget_hit ? " (budget)" : "", f.found, f.mean_us, f.p95_us,
                  f.length_ratio, Ms(f.first_ms).c_str(), f.max_ratio, f.smoothed_ratio,
                  f.smoothed_max);
      std::fflush(stdout);
    }
    grids.emplace_back(name, *std::move(grid));
  }

  if (absl::GetFlag(FLAGS_structures)) {
    std::printf("\n### Structures (DescribeStructure, unknown blocked)\n\n");
    std::printf("| map | kind | counts | MiB | build ms |\n| --- | --- | --- | ---: | ---: |\n");
    for (const auto& [name, grid] : grids) {
      for (std::string_view kind : pathd::StructureKinds()) {
        const std::string kind_name(kind);
        if (std::find(skip.begin(), skip.end(), kind_name + "@" + name) != skip.end()) {
          std::printf("| %s | %s | skipped (--skip) | | |\n", name.c_str(), kind_name.c_str());
          continue;
        }
        auto s = pathd::DescribeStructure(kind, grid, false);
        if (!s.ok()) continue;
        std::vector<std::string> counts;
        for (const auto& [what, n] : s->counts) {
          counts.push_back(absl::StrFormat("%d %s", n, what));
        }
        std::printf("| %s | %s | %s | %.2f | %s |\n", name.c_str(), kind_name.c_str(),
                    absl::StrJoin(counts, ", ").c_str(),
                    static_cast<double>(s->bytes) / (1 << 20),
                    Ms(absl::ToDoubleMilliseconds(s->build_time)).c_str());
        std::fflush(stdout);
      }
    }
  }

  const std::string advance_map = absl::GetFlag(FLAGS_advance_map);
  if (!advance_map.empty()) {
    auto small = pathd::ReadMovingAiMapFile((root / advance_map).string());
    if (!small.ok()) {
      std::fprintf(stderr, "%s: %s\n", advance_map.c_str(),
                   std::string(small.status().message()).c_str());
      return 1;
    }
    const pathd::Grid big = ScaleUp(*small, absl::GetFlag(FLAGS_advance_size));
    // Two far-apart free cells as the query (the structures do not depend
    // on it, except euclidean_spm's, which is per goal).
    std::optional<pathd::Cell> start, goal;
    for (int y = 0; y < big.height() && !start; ++y) {
      for (int x = 0; x < big.width() && !start; ++x) {
        if (big.cost(x, y) == pathd::kFreeCost) start = pathd::Cell{x, y};
      }
    }
    for (int y = big.height() - 1; y >= 0 && !goal; --y) {
      for (int x = big.width() - 1; x >= 0 && !goal; --x) {
        if (big.cost(x, y) == pathd::kFreeCost) goal = pathd::Cell{x, y};
      }
    }
    std::printf("\n### Advance vs rebuild: %s scaled to %d x %d, random changed cells "
                "(median of %d)\n\n",
                advance_map.c_str(), big.width(), big.height(),
                absl::GetFlag(FLAGS_advance_repeats));
    std::printf("| planner | structure key | MiB | build ms | advance 1 cell ms | "
                "advance 10 ms | advance 100 ms |\n");
    std::printf("| --- | --- | ---: | ---: | ---: | ---: | ---: |\n");
    const std::vector<std::string> advanced =
        absl::StrSplit(absl::GetFlag(FLAGS_advance_planners), ',', absl::SkipEmpty());
    for (const std::string& name : advanced) {
      const pathd::Planner* planner = PlannerByName(name);
      if (planner == nullptr) {
        std::printf("| %s | not registered | | | | | |\n", name.c_str());
        continue;
      }
      AdvanceRows(*planner, big, *start, *goal, scratch);
    }
  }

  const std::string tile_map = absl::GetFlag(FLAGS_tile_map);
  if (!tile_map.empty()) {
    auto small = pathd::ReadMovingAiMapFile((root / tile_map).string());
    if (!small.ok()) {
      std::fprintf(stderr, "%s: %s\n", tile_map.c_str(),
                   std::string(small.status().message()).c_str());
      return 1;
    }
    std::printf("\n### Huge maps: %s mirror-tiled, %d long queries; times in ms, ratios "
                "over the first planner's cost (simplified: SimplifyPath's length)\n\n",
                tile_map.c_str(), absl::GetFlag(FLAGS_tile_queries));
    std::printf("| map | planner | queries timed | mean ms | p95 ms | speed-up | cost ratio "
                "mean / max | simplified ratio mean / max |\n");
    std::printf("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    const std::vector<std::string> sides =
        absl::StrSplit(absl::GetFlag(FLAGS_tile_sizes), ',', absl::SkipEmpty());
    for (const std::string& side : sides) {
      int size = 0;
      if (!absl::SimpleAtoi(side, &size) || size <= 0) continue;
      TiledRows(tile_map, MirrorTile(*small, size));
    }
  }
  return 0;
}
