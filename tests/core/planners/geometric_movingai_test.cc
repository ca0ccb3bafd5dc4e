// The exact geometric planners (visibility_graph, minimal_construct, navmesh,
// euclidean_spm) on the shared Moving AI maps: on a sample of scenarios
// spread over each whole .scen file, every planner finds a path, its length
// is never above the scenario's stored grid optimum (an 8-connected path is
// one polyline among many) nor below the straight line, its polyline runs
// from the start centre to the goal centre and every segment is clear under
// the independent checker (tests/testing/segment_checker.h), and the
// planners agree with each other to 1e-6 relative.
//
// One ctest entry per map (tests/core/CMakeLists.txt), like
// movingai_conformance; skipped, saying so, when the benchmark folder is
// absent. Each planner's structure is built once per map (through an
// AdvancingStore that sees one grid) and reused by every query, as the
// server's cache would.
//
// Environment:
//   PATHD_MOVINGAI_DIR=DIR        the benchmark folder (default
//                                 ../shared/benchmarks/movingai)
//   PATHD_GEOMETRIC_SCENARIOS=N   scenarios per map (default kScenarios)
//   PATHD_GEOMETRIC_PLANNERS=a,b  only these planners (default: all four)
//   PATHD_GEOMETRIC_FULL=1        every scenario, every planner on every map
//                                 (also the visibility graph where CI drops
//                                 it, and euclidean_spm on every scenario)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "core/map_io/map_io.h"
#include "core/search/planner.h"
#include "core/search/registry.h"
#include "gtest/gtest.h"
#include "tests/testing/advancing_store.h"
#include "tests/testing/segment_checker.h"

namespace pathd {
namespace {

namespace fs = std::filesystem;
using testing::AdvancingStore;
using testing::PolylineChecker;
using testing::SegmentChecker;

// Scenarios checked per map by default: at least 200, spread evenly over
// the file (every length bucket), never its first N.
constexpr size_t kScenarios = 200;

fs::path BenchmarkDir() {
  if (const char* env = std::getenv("PATHD_MOVINGAI_DIR")) return env;
  return "../shared/benchmarks/movingai";
}

std::vector<std::string> BenchmarkMaps() {
  std::vector<std::string> maps;
  std::error_code ec;
  const fs::path root = BenchmarkDir();
  if (!fs::is_directory(root, ec)) return maps;
  for (const auto& entry : fs::recursive_directory_iterator(root, ec)) {
    const fs::path& p = entry.path();
    if (p.extension() == ".map" && fs::exists(p.string() + ".scen")) {
      maps.push_back(fs::relative(p, root).string());
    }
  }
  std::sort(maps.begin(), maps.end());
  return maps;
}

bool Full() { return std::getenv("PATHD_GEOMETRIC_FULL") != nullptr; }

size_t ScenarioCount() {
  if (const char* env = std::getenv("PATHD_GEOMETRIC_SCENARIOS")) {
    const long n = std::atol(env);
    if (n > 0) return static_cast<size_t>(n);
  }
  return kScenarios;
}

// Indices of `count` scenarios spread evenly over `total` (all when count
// >= total): i * total / count, so the first and the last buckets are in.
std::vector<size_t> SpreadSample(size_t total, size_t count) {
  std::vector<size_t> out;
  if (count >= total) {
    for (size_t i = 0; i < total; ++i) out.push_back(i);
    return out;
  }
  for (size_t i = 0; i < count; ++i) out.push_back(i * total / count + (total / count) / 2);
  return out;
}

// How each planner is run in CI (PATHD_GEOMETRIC_FULL=1 runs every planner
// on every sampled scenario of every map). Measured on the shared 2-core
// machine under load (other builds running), 2026-12-01:
//  - visibility_graph: build 0.01-0.2 s and queries ~1 ms on most maps, but
//    its build is quadratic-ish in convex corners: 9.7 s on maze512-1-0
//    (kept), 48 s on random512-40-0 and over 60 s on random512-10-0 (and
//    random512-25-0 did not finish with the others in 90 s): dropped there.
//  - navmesh: queries 0.5-10 ms, 200 ms on random512-40-0 (every 2nd there).
//  - minimal_construct: 2-10 ms per query on most maps, 360 ms on brc202d
//    (every 16th there), over 6 s on maze512-1-0 (20 queries did not finish
//    in 120 s); every 8th sampled scenario (25 per map), dropped on the
//    mazes with narrow corridors and the random maps (the combined runs
//    timed out).
//  - euclidean_spm: one shortest path map per goal, 0.1-5 s each on the 512
//    maps (84 s on a 1024 x 1024 one): every 100th sampled scenario (2
//    goals per map), dropped where minimal_construct is.
// With these, `ctest -j2 -R geometric_movingai` took about 10 minutes of
// test time (5.5 minutes wall) with every 40th scenario for euclidean_spm
// and every 4th for minimal_construct while another benchmark ran on the
// machine; street/Boston_0_512 was the longest (141 s; with the strides
// above: minimal_construct 0.84 s per query, euclidean_spm 10-20 s per goal,
// so both thinned or dropped there). room/8room_000 ran for over 10 minutes
// with minimal_construct every 4th and euclidean_spm every 40th scenario
// (not yet profiled which): both dropped there until it is.
// With the strides above, `ctest -j2 -R "geometric_movingai|geometric_
// planners_test|segment_checker_test"` takes 1 min 52 s wall (maze512-1-0
// the longest map, 37 s: its visibility graph build).
// A stride of 0 in `per_map` drops the planner on that map.
struct PlannerPlan {
  const char* name;
  int stride;
  std::vector<std::pair<std::string, int>> per_map;
};

const std::vector<PlannerPlan>& Plans() {
  static const auto* plans = new std::vector<PlannerPlan>{
      {"visibility_graph",
       1,
       {{"random/random512-10-0.map", 0},
        {"random/random512-25-0.map", 0},
        {"random/random512-40-0.map", 0}}},
      {"navmesh", 1, {{"random/random512-40-0.map", 2}}},
      {"minimal_construct",
       8,
       {{"dao/brc202d.map", 16},
        {"maze/maze512-1-0.map", 0},
        {"maze/maze512-4-0.map", 0},
        {"random/random512-10-0.map", 0},
        {"random/random512-25-0.map", 0},
        {"random/random512-40-0.map", 0},
        {"room/8room_000.map", 0},
        {"street/Boston_0_512.map", 32}}},
      {"euclidean_spm",
       100,
       {{"maze/maze512-1-0.map", 0},
        {"maze/maze512-4-0.map", 0},
        {"random/random512-10-0.map", 0},
        {"random/random512-25-0.map", 0},
        {"random/random512-40-0.map", 0},
        {"room/8room_000.map", 0},
        {"street/Boston_0_512.map", 0}}},
  };
  return *plans;
}

// The stride of `plan` on `map` in CI (0: dropped).
int StrideOn(const PlannerPlan& plan, const std::string& map) {
  for (const auto& [name, stride] : plan.per_map) {
    if (name == map) return stride;
  }
  return plan.stride;
}

struct Tally {
  const Planner* planner = nullptr;
  int stride = 1;
  int checked = 0;
  int failed = 0;
  // Time of the first query (which builds the structure) and of the rest.
  absl::Duration first;
  absl::Duration rest;
  double ratio_sum = 0.0;
  std::unique_ptr<AdvancingStore> store;
};

// Failures reported per map before the map's test stops.
constexpr int kMaxFailures = 10;

std::string PolylineText(const std::vector<CellPoint>& polyline) {
  std::vector<std::string> parts;
  for (const CellPoint& p : polyline) parts.push_back(absl::StrFormat("(%g, %g)", p.x, p.y));
  return absl::StrJoin(parts, " ");
}

// What is wrong with one answer to scenario `s` ("" when nothing is): not
// found, endpoints, a segment not clear under the checker, a reported length
// that is not its polyline's, above the grid optimum or below the straight
// line.
std::string CheckAnswer(const absl::StatusOr<PlanResult>& r, const Scenario& s,
                        double tolerance, const PolylineChecker& polylines) {
  if (!r.ok()) return r.status().ToString();
  if (!r->found()) return "no path: " + std::string(PlanOutcomeName(r->outcome));
  if (r->polyline.empty()) return "empty polyline";
  const CellPoint a = r->polyline.front(), b = r->polyline.back();
  if (a.x != s.start.x + 0.5 || a.y != s.start.y + 0.5 || b.x != s.goal.x + 0.5 ||
      b.y != s.goal.y + 0.5) {
    return absl::StrFormat("polyline runs (%g, %g) -> (%g, %g), not centre to centre", a.x,
                           a.y, b.x, b.y);
  }
  if (const auto defect = polylines.FirstDefect(r->polyline)) {
    return absl::StrCat(defect->ToString(), "; polyline ", PolylineText(r->polyline));
  }
  const double measured = testing::LatticePolylineLength(r->polyline);
  if (std::abs(r->length - measured) > 1e-9 * (1 + measured)) {
    return absl::StrFormat("reported length %.9f, its polyline's %.9f", r->length, measured);
  }
  if (r->length > s.optimal_length + tolerance) {
    return absl::StrFormat("length %.9f above the grid optimum", r->length);
  }
  const double straight = std::hypot(static_cast<double>(s.goal.x - s.start.x),
                                     static_cast<double>(s.goal.y - s.start.y));
  if (r->length < straight - 1e-9) {
    return absl::StrFormat("length %.9f below the straight line %.9f", r->length, straight);
  }
  return "";
}

class GeometricMovingAi : public ::testing::TestWithParam<std::string> {};

TEST_P(GeometricMovingAi, ExactPlannersOnSpreadScenarios) {
  const fs::path map_path = BenchmarkDir() / GetParam();
  auto grid = ReadMovingAiMapFile(map_path.string());
  ASSERT_TRUE(grid.ok()) << grid.status();
  auto file = ReadMovingAiScenarioFileWithVersion(map_path.string() + ".scen");
  ASSERT_TRUE(file.ok()) << file.status();
  ASSERT_FALSE(file->scenarios.empty());

  std::vector<Tally> tallies;
  std::vector<std::string> missing, dropped;
  std::vector<std::string> only;
  if (const char* env = std::getenv("PATHD_GEOMETRIC_PLANNERS")) {
    only = absl::StrSplit(env, ',', absl::SkipEmpty());
  }
  for (const PlannerPlan& plan : Plans()) {
    if (!only.empty() && std::find(only.begin(), only.end(), plan.name) == only.end()) {
      continue;
    }
    const Planner* p = PlannerRegistry::Default().Get(plan.name);
    if (p == nullptr) {
      missing.push_back(plan.name);
      continue;
    }
    const int stride = Full() ? 1 : StrideOn(plan, GetParam());
    if (stride == 0) {
      dropped.push_back(plan.name);
      continue;
    }
    Tally t;
    t.planner = p;
    t.stride = stride;
    t.store = std::make_unique<AdvancingStore>();
    t.store->SetGrid(*grid);
    tallies.push_back(std::move(t));
  }
  if (tallies.empty()) {
    GTEST_SKIP() << "no exact geometric planner registered (not merged yet): "
                 << absl::StrJoin(missing, ", ");
  }

  const SegmentChecker checker(*grid, false);
  const PolylineChecker polylines(checker);
  SearchScratch scratch;
  int failures = 0;
  const std::vector<size_t> sample =
      SpreadSample(file->scenarios.size(), Full() ? file->scenarios.size() : ScenarioCount());
  for (size_t k = 0; k < sample.size(); ++k) {
    const Scenario& s = file->scenarios[sample[k]];
    const double tolerance = ScenarioTolerance(s, file->version);
    CostParams cost;
    cost.cost_weight = 0.0;
    // The valid answers of this scenario, to compare once all have run.
    struct Answer {
      std::string planner;
      double length;
      std::vector<CellPoint> polyline;
    };
    std::vector<Answer> answers;
    for (Tally& t : tallies) {
      if (k % static_cast<size_t>(t.stride) != 0) continue;
      PlanRequest request = PlanRequest::Between(s.start, s.goal, cost);
      request.derived = t.store.get();
      const absl::Time started = absl::Now();
      auto r = t.planner->Plan(*grid, request, StopCondition::None(), scratch);
      (t.checked == 0 ? t.first : t.rest) += absl::Now() - started;
      ++t.checked;
      const std::string where = absl::StrFormat(
          "%s on %s, scenario %d (line %d) (%d, %d) -> (%d, %d), grid optimum %.8f",
          t.planner->name(), GetParam(), sample[k], s.line, s.start.x, s.start.y, s.goal.x,
          s.goal.y, s.optimal_length);
      const std::string error = CheckAnswer(r, s, tolerance, polylines);
      if (!error.empty()) {
        ADD_FAILURE() << where << ": " << error;
        ++t.failed;
        if (++failures >= kMaxFailures) break;
        continue;
      }
      t.ratio_sum += s.optimal_length > 0 ? r->length / s.optimal_length : 1.0;
      answers.push_back({std::string(t.planner->name()), r->length, r->polyline});
    }
    if (failures >= kMaxFailures) break;
    // Every answer is a valid path, so the shortest of them bounds the
    // optimum: a longer one is not a shortest path.
    auto shortest = std::min_element(answers.begin(), answers.end(),
                                     [](const Answer& a, const Answer& b) {
                                       return a.length < b.length;
                                     });
    for (const Answer& a : answers) {
      if (a.length <= shortest->length * (1 + 1e-6)) continue;
      ADD_FAILURE() << a.planner << " on " << GetParam() << ", scenario " << sample[k]
                    << " (line " << s.line << ") (" << s.start.x << ", " << s.start.y
                    << ") -> (" << s.goal.x << ", " << s.goal.y << "): length "
                    << absl::StrFormat("%.9f", a.length) << " is longer than "
                    << shortest->planner << "'s valid "
                    << absl::StrFormat("%.9f", shortest->length) << "\n  " << a.planner
                    << ": " << PolylineText(a.polyline) << "\n  " << shortest->planner
                    << ": " << PolylineText(shortest->polyline);
      ++failures;
    }
    if (failures >= kMaxFailures) break;
  }
  if (failures >= kMaxFailures) {
    ADD_FAILURE() << "stopped after " << kMaxFailures << " failures on " << GetParam();
  }
  std::printf("%s: %zu of %zu scenarios\n", GetParam().c_str(), sample.size(),
              file->scenarios.size());
  for (const Tally& t : tallies) {
    std::printf(
        "  %-18s every %2d: %4d checked, %d failed, mean length/grid optimum %.4f, "
        "first query (build) %.2f s, the rest %.2f s\n",
        std::string(t.planner->name()).c_str(), t.stride, t.checked, t.failed,
        t.checked > 0 ? t.ratio_sum / t.checked : 0.0, absl::ToDoubleSeconds(t.first),
        absl::ToDoubleSeconds(t.rest));
  }
  if (!dropped.empty()) {
    std::printf("  dropped on this map in CI (PATHD_GEOMETRIC_FULL=1 runs them): %s\n",
                absl::StrJoin(dropped, ", ").c_str());
  }
  if (!missing.empty()) {
    GTEST_SKIP() << "not registered (not merged yet): " << absl::StrJoin(missing, ", ");
  }
}

std::string TestName(const ::testing::TestParamInfo<std::string>& info) {
  std::string name;
  for (char c : info.param) {
    name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Shared, GeometricMovingAi, ::testing::ValuesIn(BenchmarkMaps()),
                         TestName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(GeometricMovingAi);

TEST(GeometricMovingAiBenchmarks, PresentOrSkipped) {
  if (BenchmarkMaps().empty()) {
    GTEST_SKIP() << "Moving AI benchmarks not found at " << BenchmarkDir()
                 << " (expected ../shared/benchmarks/movingai beside the project "
                    "root, or PATHD_MOVINGAI_DIR); geometric checks skipped";
  }
  std::printf("Moving AI benchmarks: %zu maps under %s\n", BenchmarkMaps().size(),
              BenchmarkDir().c_str());
}

// The sample is spread over the whole file.
TEST(GeometricMovingAiSample, SpreadsOverTheWholeFile) {
  const std::vector<size_t> s = SpreadSample(1000, 200);
  ASSERT_EQ(s.size(), 200u);
  EXPECT_LT(s.front(), 5u);
  EXPECT_GE(s.back(), 995u);
  EXPECT_TRUE(std::is_sorted(s.begin(), s.end()));
  EXPECT_EQ(std::adjacent_find(s.begin(), s.end()), s.end());
  EXPECT_EQ(SpreadSample(50, 200).size(), 50u);
}

}  // namespace
}  // namespace pathd
