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

#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
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

// How each planner is run in CI. The visibility graph connects every pair
// of mutually visible convex corners: its build is quadratic-ish in corners
// and dropped on the maps below (measured build times in the comment);
// euclidean_spm builds one shortest path map per goal (a sweep of the whole
// map), so it sees every `stride`-th sampled scenario. PATHD_GEOMETRIC_FULL
// runs everything.
struct PlannerPlan {
  const char* name;
  int stride;
  // Maps (relative paths) where CI skips the planner.
  std::vector<std::string> skipped_maps;
};

const std::vector<PlannerPlan>& Plans() {
  static const auto* plans = new std::vector<PlannerPlan>{
      {"visibility_graph", 1, {}},
      {"minimal_construct", 1, {}},
      {"navmesh", 1, {}},
      {"euclidean_spm", 10, {}},
  };
  return *plans;
}

struct Tally {
  const Planner* planner = nullptr;
  int stride = 1;
  int checked = 0;
  // Time of the first query (which builds the structure) and of the rest.
  absl::Duration first;
  absl::Duration rest;
  double ratio_sum = 0.0;
  std::unique_ptr<AdvancingStore> store;
};

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
  for (const PlannerPlan& plan : Plans()) {
    const Planner* p = PlannerRegistry::Default().Get(plan.name);
    if (p == nullptr) {
      missing.push_back(plan.name);
      continue;
    }
    if (!Full() && std::find(plan.skipped_maps.begin(), plan.skipped_maps.end(),
                             GetParam()) != plan.skipped_maps.end()) {
      dropped.push_back(plan.name);
      continue;
    }
    Tally t;
    t.planner = p;
    t.stride = Full() ? 1 : plan.stride;
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
  const std::vector<size_t> sample =
      SpreadSample(file->scenarios.size(), Full() ? file->scenarios.size() : ScenarioCount());
  for (size_t k = 0; k < sample.size(); ++k) {
    const Scenario& s = file->scenarios[sample[k]];
    const double tolerance = ScenarioTolerance(s, file->version);
    const double straight =
        std::hypot(static_cast<double>(s.goal.x - s.start.x),
                   static_cast<double>(s.goal.y - s.start.y));
    CostParams cost;
    cost.cost_weight = 0.0;
    double first_length = -1.0;
    std::string first_name;
    for (Tally& t : tallies) {
      if (k % static_cast<size_t>(t.stride) != 0) continue;
      PlanRequest request = PlanRequest::Between(s.start, s.goal, cost);
      request.derived = t.store.get();
      const absl::Time started = absl::Now();
      auto r = t.planner->Plan(*grid, request, StopCondition::None(), scratch);
      (t.checked == 0 ? t.first : t.rest) += absl::Now() - started;
      ++t.checked;
      const std::string where = absl::StrFormat(
          "%s on %s, scenario %d (line %d) (%d, %d) -> (%d, %d), optimal %.8f",
          t.planner->name(), GetParam(), sample[k], s.line, s.start.x, s.start.y, s.goal.x,
          s.goal.y, s.optimal_length);
      ASSERT_TRUE(r.ok()) << where << ": " << r.status();
      ASSERT_TRUE(r->found()) << where << ": " << PlanOutcomeName(r->outcome);
      ASSERT_GE(r->polyline.size(), 1u) << where;
      ASSERT_EQ(r->polyline.front().x, s.start.x + 0.5) << where;
      ASSERT_EQ(r->polyline.front().y, s.start.y + 0.5) << where;
      ASSERT_EQ(r->polyline.back().x, s.goal.x + 0.5) << where;
      ASSERT_EQ(r->polyline.back().y, s.goal.y + 0.5) << where;
      const auto defect = polylines.FirstDefect(r->polyline);
      ASSERT_FALSE(defect.has_value()) << where << ": " << defect->ToString();
      const double measured = testing::LatticePolylineLength(r->polyline);
      ASSERT_NEAR(r->length, measured, 1e-9 * (1 + measured))
          << where << ": reported length vs its polyline's";
      ASSERT_LE(r->length, s.optimal_length + tolerance)
          << where << ": length " << r->length << " above the grid optimum";
      ASSERT_GE(r->length, straight - 1e-9)
          << where << ": length " << r->length << " below the straight line " << straight;
      if (first_length < 0) {
        first_length = r->length;
        first_name = std::string(t.planner->name());
      } else {
        ASSERT_NEAR(r->length, first_length, 1e-6 * first_length)
            << where << ": length " << r->length << " vs " << first_name << "'s "
            << first_length;
      }
      t.ratio_sum += s.optimal_length > 0 ? r->length / s.optimal_length : 1.0;
    }
  }
  std::printf("%s: %zu of %zu scenarios\n", GetParam().c_str(), sample.size(),
              file->scenarios.size());
  for (const Tally& t : tallies) {
    std::printf(
        "  %-18s every %2d: %4d checked, mean length/grid optimum %.4f, first query "
        "(build) %.2f s, the rest %.2f s\n",
        std::string(t.planner->name()).c_str(), t.stride, t.checked,
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
