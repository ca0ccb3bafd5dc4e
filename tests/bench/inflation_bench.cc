// inflation_bench: times InflateObstacles on Moving AI maps for a few robot
// radii and prints, per map and radius, the mean and p95 milliseconds per call
// and the share of cells the inflation blocked. Figures, not assertions.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/map/grid.h"
#include "core/map/inflation.h"
#include "core/map_io/map_io.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map files");
ABSL_FLAG(std::string, maps,
          "random/random512-25-0.map,bg512/AR0011SR.map,dao/brc202d.map,"
          "street/Berlin_0_512.map",
          "comma-separated map paths relative to --movingai_dir");
ABSL_FLAG(std::string, radii, "1.5,5,20", "comma-separated radii, cells");
ABSL_FLAG(int, runs, 200, "timed calls per map and radius (after one warm-up)");

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "inflation_bench [--movingai_dir DIR] [--maps a.map,...] [--radii 5,20] "
      "[--runs N]\nPrints mean/p95 ms per InflateObstacles call.");
  absl::ParseCommandLine(argc, argv);
  std::vector<double> radii;
  for (absl::string_view r :
       absl::StrSplit(absl::GetFlag(FLAGS_radii), ',', absl::SkipEmpty())) {
    double value = 0;
    if (!absl::SimpleAtod(r, &value)) {
      std::fprintf(stderr, "bad radius '%s'\n", std::string(r).c_str());
      return 2;
    }
    radii.push_back(value);
  }
  const int runs = std::max(1, absl::GetFlag(FLAGS_runs));
  const fs::path root = absl::GetFlag(FLAGS_movingai_dir);

  std::printf("%-28s %11s %7s %6s %9s %9s %9s\n", "map", "size", "radius",
              "runs", "mean_ms", "p95_ms", "blocked");
  for (absl::string_view name :
       absl::StrSplit(absl::GetFlag(FLAGS_maps), ',', absl::SkipEmpty())) {
    const fs::path path = root / std::string(name);
    const absl::StatusOr<pathd::Grid> grid =
        pathd::ReadMovingAiMapFile(path.string());
    if (!grid.ok()) {
      std::fprintf(stderr, "%s\n",
                   std::string(grid.status().message()).c_str());
      return 1;
    }
    for (double radius : radii) {
      // The warm-up call also gives the blocked share.
      const absl::StatusOr<pathd::Grid> inflated =
          pathd::InflateObstacles(*grid, radius);
      if (!inflated.ok()) {
        std::fprintf(stderr, "%s\n",
                     std::string(inflated.status().message()).c_str());
        return 1;
      }
      std::vector<double> ms;
      ms.reserve(runs);
      for (int i = 0; i < runs; ++i) {
        const absl::Time t0 = absl::Now();
        const absl::StatusOr<pathd::Grid> out =
            pathd::InflateObstacles(*grid, radius);
        ms.push_back(absl::ToDoubleMilliseconds(absl::Now() - t0));
        if (!out.ok()) return 1;
      }
      double total = 0;
      for (double m : ms) total += m;
      std::sort(ms.begin(), ms.end());
      const double p95 = ms[std::min(ms.size() - 1, ms.size() * 95 / 100)];
      const std::string size =
          std::to_string(grid->width()) + "x" + std::to_string(grid->height());
      std::printf("%-28s %11s %7.2f %6d %9.3f %9.3f %8.1f%%\n",
                  std::string(name).c_str(), size.c_str(), radius, runs,
                  total / runs, p95,
                  100.0 * static_cast<double>(inflated->CountBlocked()) /
                      static_cast<double>(grid->size()));
      std::fflush(stdout);
    }
  }
  return 0;
}
