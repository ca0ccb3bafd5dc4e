// Dijkstra benchmark: our Dijkstra and our cost-to-go build (the backward
// sweep of core/planners/cost_to_go.h) on the binary-heap OpenList (old) and
// on the radix-heap MonotoneOpenList (new), against a textbook Dijkstra
// written apart here (std::priority_queue discipline on a reused vector,
// (cost, index) pairs, lazy deletion, the same octile moves without corner
// cutting and the same step costs), in one run on Moving AI maps. Point to
// point: scenarios spread over each whole file; fields: full-map builds from
// the goals of scenarios spread over the file, each handed out as a vector
// of its own (the textbook allocates its distances per build and hands them
// out, as ours does). The three variants of one
// query run back to back in a rotating order, each timed in the thread's CPU
// time; a variant's figure is its mean per query, the minimum over --rounds.
// Costs are compared bit for bit (old vs new, new vs textbook). Fields are
// also timed as the shortest path map cache builds them (ShortestPathMap::
// Build: the incremental engine from its initial state, 4-byte floats,
// the fleet Table's fields), a fourth variant in the rotation.
//
//   build/tests/bench/dijkstra_bench
//   --movingai_dir=../shared/benchmarks/movingai
//       --sample=100 --fields=12 --rounds=3
#include <malloc.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_format.h"
#include "core/incremental/incremental_search.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "core/planners/cost_to_go.h"
#include "core/search/best_first.h"
#include "core/search/open_list.h"
#include "core/search/radix_heap.h"
#include "core/search/search_scratch.h"
#include "tests/bench/movingai_maps.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder of the Moving AI maps");
ABSL_FLAG(std::string, maps,
          "dao/den520d.map,dao/brc202d.map,bg512/AR0011SR.map,street/"
          "Berlin_0_512.map,"
          "room/8room_000.map,random/random512-25-0.map,maze/maze512-4-0.map",
          "comma-separated maps under --movingai_dir (empty: every map)");
ABSL_FLAG(int, sample, 100,
          "point-to-point scenarios per map, spread over the file");
ABSL_FLAG(int, fields, 12,
          "full-map cost-to-go builds per map, goals spread over the file (a "
          "multiple of 4: "
          "each variant then runs as often in each place of the rotation)");
ABSL_FLAG(int, rounds, 3, "rounds; each variant's figure is its best round");
ABSL_FLAG(bool, keep_freed_memory, true,
          "keep freed memory mapped (glibc mallopt), so no variant's field "
          "pays page faults "
          "that another's free caused");
ABSL_FLAG(bool, textbook_fresh_fields, true,
          "the textbook allocates each field (as ours must, to hand it out); "
          "false: it "
          "reuses one array, which shows what allocating costs");

namespace pathd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double CpuNow() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) +
         1e-9 * static_cast<double>(ts.tv_nsec);
}

// The textbook Dijkstra over the 8-connected grid: a binary heap of (cost,
// index) pairs with lazy deletion (a pair whose cost is above the cell's is
// skipped). Memory is kept between queries, as any repeated use would.
class Textbook {
 public:
  Textbook(const Grid& grid, const CostParams& cost)
      : w_(grid.width()),
        h_(grid.height()),
        open_(grid.size()),
        factor_(grid.size()),
        dist_(grid.size()) {
    for (int32_t y = 0; y < h_; ++y) {
      for (int32_t x = 0; x < w_; ++x) {
        const size_t i = grid.Index(x, y);
        open_[i] = Traversable(grid.cost(x, y), cost.unknown_is_free);
        factor_[i] = CellFactor(grid.cost(x, y), cost.cost_weight);
      }
    }
  }

  // From `source` until `target` is settled (-1: every cell). A move pays
  // its length times the factor of the cell it enters; `backward` searches
  // against the moves (the cost of reaching `source` from each cell), so
  // there that is the settled cell. Returns the cells settled. `fresh`: the
  // distances go to a new vector (a field to hand out, TakeField()), else
  // the last one is reused.
  int64_t Run(int32_t source, int32_t target, bool backward,
              bool fresh = false) {
    if (fresh) {
      dist_ = std::vector<double>(open_.size(), kInf);
    } else {
      std::fill(dist_.begin(), dist_.end(), kInf);
    }
    heap_.clear();
    dist_[source] = 0.0;
    Push(0.0, source);
    int64_t settled = 0;
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), std::greater<>());
      const auto [d, v] = heap_.back();
      heap_.pop_back();
      if (d > dist_[v]) continue;
      ++settled;
      if (v == target) break;
      const int32_t x = v % w_, y = v / w_;
      const bool left = x > 0 && open_[v - 1],
                 right = x + 1 < w_ && open_[v + 1];
      const bool up = y > 0 && open_[v - w_],
                 down = y + 1 < h_ && open_[v + w_];
      const double entered = factor_[v];
      auto relax = [&](int32_t u, double length) {
        const double du = d + length * (backward ? entered : factor_[u]);
        if (du < dist_[u]) {
          dist_[u] = du;
          Push(du, u);
        }
      };
      if (left) relax(v - 1, 1.0);
      if (right) relax(v + 1, 1.0);
      if (up) relax(v - w_, 1.0);
      if (down) relax(v + w_, 1.0);
      if (left && up && open_[v - w_ - 1]) relax(v - w_ - 1, kSqrt2);
      if (right && up && open_[v - w_ + 1]) relax(v - w_ + 1, kSqrt2);
      if (left && down && open_[v + w_ - 1]) relax(v + w_ - 1, kSqrt2);
      if (right && down && open_[v + w_ + 1]) relax(v + w_ + 1, kSqrt2);
    }
    return settled;
  }
  double dist(int32_t i) const { return dist_[i]; }
  std::vector<double> TakeField() { return std::move(dist_); }
  const std::vector<double>& field() const { return dist_; }

 private:
  void Push(double d, int32_t v) {
    heap_.emplace_back(d, v);
    std::push_heap(heap_.begin(), heap_.end(), std::greater<>());
  }

  int32_t w_, h_;
  std::vector<bool> open_;
  std::vector<double> factor_;
  std::vector<double> dist_;
  std::vector<std::pair<double, int32_t>> heap_;
};

struct Figures {
  // textbook, old, new; fields also the incremental engine's build
  double seconds[4] = {0, 0, 0, 0};
  int64_t expansions[4] = {0, 0, 0, 0};
  int64_t old_new_mismatch = 0;   // costs (or field cells) not bit-identical
  int64_t textbook_mismatch = 0;  // new vs textbook
};

bool Same(double a, double b) {
  return std::bit_cast<uint64_t>(a) == std::bit_cast<uint64_t>(b);
}

std::vector<Scenario> Spread(const std::vector<Scenario>& all, int n) {
  if (n <= 0 || static_cast<int>(all.size()) <= n) return all;
  std::vector<Scenario> picked;
  const double stride = static_cast<double>(all.size()) / n;
  for (int i = 0; i < n; ++i)
    picked.push_back(all[static_cast<size_t>(i * stride + stride / 2)]);
  return picked;
}

// One round of point-to-point queries.
Figures PointToPoint(const Grid& grid, const std::vector<Scenario>& scenarios,
                     SearchScratch& scratch) {
  const CostParams cost;
  Textbook textbook(grid, cost);
  const internal::AStarPriority<internal::ZeroHeuristic> dijkstra{};
  Figures f;
  for (size_t q = 0; q < scenarios.size(); ++q) {
    const Scenario& s = scenarios[q];
    const PlanRequest request = PlanRequest::Between(s.start, s.goal, cost);
    double costs[3] = {kInf, kInf, kInf};
    for (int k = 0; k < 3; ++k) {
      const int variant = static_cast<int>((q + k) % 3);
      const double t0 = CpuNow();
      if (variant == 0) {
        f.expansions[0] += textbook.Run(
            static_cast<int32_t>(grid.Index(s.start.x, s.start.y)),
            static_cast<int32_t>(grid.Index(s.goal.x, s.goal.y)), false);
        costs[0] =
            textbook.dist(static_cast<int32_t>(grid.Index(s.goal.x, s.goal.y)));
      } else {
        const PlanResult r =
            variant == 1
                ? internal::GridBestFirstSearch<internal::OpenList>(
                      grid, request, StopCondition::None(), scratch, dijkstra)
                : internal::GridBestFirstSearch<internal::MonotoneOpenList>(
                      grid, request, StopCondition::None(), scratch, dijkstra);
        f.expansions[variant] += r.expansions;
        costs[variant] = r.found() ? r.cost : kInf;
      }
      f.seconds[variant] += CpuNow() - t0;
    }
    f.old_new_mismatch += !Same(costs[1], costs[2]);
    f.textbook_mismatch += !Same(costs[0], costs[2]);
  }
  return f;
}

// One round of full-map cost-to-go builds.
Figures Fields(const Grid& grid, const std::vector<Scenario>& goals,
               SearchScratch& scratch) {
  const CostParams cost;
  Textbook textbook(grid, cost);
  const auto shared = std::make_shared<const Grid>(grid);
  const bool fresh = absl::GetFlag(FLAGS_textbook_fresh_fields);
  Figures f;
  for (size_t q = 0; q < goals.size(); ++q) {
    const Cell goal = goals[q].goal;
    CostToGoField fields[3];
    std::vector<double> textbook_field;
    for (int k = 0; k < 4; ++k) {
      const int variant = static_cast<int>((q + k) % 4);
      const double t0 = CpuNow();
      if (variant == 3) {
        // The shortest path map cache's build (the fleet Table's fields).
        auto spm =
            ShortestPathMap::Build(shared, goal, cost, StopCondition::None());
        if (spm.ok()) f.expansions[3] += (*spm)->last_stats().expansions;
      } else if (variant == 0) {
        f.expansions[0] += textbook.Run(
            static_cast<int32_t>(grid.Index(goal.x, goal.y)), -1, true, fresh);
        if (fresh) textbook_field = textbook.TakeField();
      } else if (variant == 1) {
        fields[1] = internal::DijkstraCostToGoOn<internal::OpenList>(
            grid, goal, cost, StopCondition::None(), scratch);
      } else {
        fields[2] = internal::DijkstraCostToGoOn<internal::MonotoneOpenList>(
            grid, goal, cost, StopCondition::None(), scratch);
      }
      f.seconds[variant] += CpuNow() - t0;
    }
    const std::vector<double>& textbook_values =
        fresh ? textbook_field : textbook.field();
    f.expansions[1] += fields[1].expansions;
    f.expansions[2] += fields[2].expansions;
    for (size_t i = 0; i < grid.size(); ++i) {
      f.old_new_mismatch += !Same(fields[1].values[i], fields[2].values[i]);
      f.textbook_mismatch += !Same(textbook_values[i], fields[2].values[i]);
    }
  }
  return f;
}

// The best round of each variant.
Figures Best(const std::vector<Figures>& rounds) {
  Figures best = rounds.front();
  for (const Figures& r : rounds) {
    for (int v = 0; v < 4; ++v)
      best.seconds[v] = std::min(best.seconds[v], r.seconds[v]);
  }
  return best;
}

void PrintRow(const std::string& map, const char* kind, size_t queries,
              const Figures& f) {
  const double n = static_cast<double>(queries);
  const double us[4] = {1e6 * f.seconds[0] / n, 1e6 * f.seconds[1] / n,
                        1e6 * f.seconds[2] / n, 1e6 * f.seconds[3] / n};
  const std::string spm =
      us[3] > 0 ? absl::StrFormat("%.0f (%.2fx)", us[3], us[3] / us[0])
                : std::string("-");
  std::printf(
      "| %s | %s | %zu | %.0f | %.0f | %.0f | %.3f | %.3f | %.3f | %s | %.0f / "
      "%.0f | %lld | "
      "%lld |\n",
      map.c_str(), kind, queries, us[0], us[1], us[2], us[1] / us[0],
      us[2] / us[0], us[2] / us[1], spm.c_str(),
      static_cast<double>(f.expansions[0]) / n,
      static_cast<double>(f.expansions[2]) / n,
      static_cast<long long>(f.old_new_mismatch),
      static_cast<long long>(f.textbook_mismatch));
  std::fflush(stdout);
}

int Main() {
  namespace fs = std::filesystem;
  const fs::path root = absl::GetFlag(FLAGS_movingai_dir);
  if (!fs::exists(root)) {
    std::fprintf(stderr, "no Moving AI maps at %s: nothing to measure\n",
                 root.c_str());
    return 0;
  }
  // A field of a 512 x 512 map is 2 MB: glibc maps such blocks afresh or
  // returns freed heap tops to the system, and the next variant to allocate
  // then pays the page faults (on dao/brc202d, where 43k of 255k cells are
  // reached, they moved a variant's figure by 30-50% from run to run).
  if (absl::GetFlag(FLAGS_keep_freed_memory)) {
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
  }
  const int rounds = std::max(1, absl::GetFlag(FLAGS_rounds));
  std::printf(
      "sample %d, fields %d, rounds %d; mean us per query, best round per "
      "variant\n\n",
      absl::GetFlag(FLAGS_sample), absl::GetFlag(FLAGS_fields), rounds);
  std::printf(
      "| map | kind | queries | textbook us | old us | new us | old/textbook | "
      "new/textbook | new/old | spm build us (/textbook) | settled textbook / "
      "ours | old!=new | "
      "new!=textbook |\n");
  std::printf(
      "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | "
      "---: | ---: | "
      "---: |\n");
  SearchScratch scratch;
  double totals[2][4] = {};
  for (const std::string& name :
       bench::MovingAiMaps(root, absl::GetFlag(FLAGS_maps))) {
    const fs::path path = root / name;
    auto grid = ReadMovingAiMapFile(path.string());
    auto scen = ReadMovingAiScenarioFile(path.string() + ".scen");
    if (!grid.ok() || !scen.ok()) {
      std::fprintf(stderr, "%s: cannot read the map or its scenarios\n",
                   name.c_str());
      return 1;
    }
    const std::vector<Scenario> queries =
        Spread(*scen, absl::GetFlag(FLAGS_sample));
    const std::vector<Scenario> goals =
        Spread(*scen, absl::GetFlag(FLAGS_fields));
    std::vector<Figures> p2p, fields;
    for (int r = 0; r < rounds; ++r) {
      p2p.push_back(PointToPoint(*grid, queries, scratch));
      fields.push_back(Fields(*grid, goals, scratch));
    }
    const Figures a = Best(p2p), b = Best(fields);
    PrintRow(name, "dijkstra", queries.size(), a);
    PrintRow(name, "cost-to-go", goals.size(), b);
    for (int v = 0; v < 4; ++v) {
      totals[0][v] += 1e6 * a.seconds[v] / static_cast<double>(queries.size());
      totals[1][v] += 1e6 * b.seconds[v] / static_cast<double>(goals.size());
    }
  }
  for (int k = 0; k < 2; ++k) {
    std::printf(
        "\n%s, sum of the maps' means: textbook %.0f us, old %.0f us (%.3fx), "
        "new %.0f us "
        "(%.3fx)%s\n",
        k == 0 ? "dijkstra" : "cost-to-go", totals[k][0], totals[k][1],
        totals[k][1] / totals[k][0], totals[k][2], totals[k][2] / totals[k][0],
        k == 0 ? ""
               : absl::StrFormat(", spm build %.0f us (%.3fx)", totals[k][3],
                                 totals[k][3] / totals[k][0])
                     .c_str());
  }
  return 0;
}

}  // namespace
}  // namespace pathd

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "dijkstra_bench [--movingai_dir DIR] [--maps a.map,b.map] [--sample N] "
      "[--fields N] "
      "[--rounds N]");
  absl::ParseCommandLine(argc, argv);
  return pathd::Main();
}
