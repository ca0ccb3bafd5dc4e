// Fuzz target: the Moving AI readers (core/map_io/map_io.h). Every input is parsed
// both as a .map and as a .map.scen file. Besides "no crash, no UB", a map
// that parses must survive a round trip: written back as '.'/'@' text it
// parses to the same grid, and scenarios that parse keep the promises
// ParseMovingAiScenarioFile makes about their fields. The reader runs with
// its default cell limit (2^28); run_fuzzers.sh's -malloc_limit_mb=64 then
// reports a header that makes it allocate more than the input could fill.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "tests/fuzz/fuzz_check.h"

namespace pathd {
namespace {


std::string ToMovingAiText(const Grid& grid) {
  std::string text = "type octile\nheight " + std::to_string(grid.height()) +
                     "\nwidth " + std::to_string(grid.width()) + "\nmap\n";
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      text += grid.cost(x, y) == kFreeCost ? '.' : '@';
    }
    text += '\n';
  }
  return text;
}

void CheckMap(std::string_view text) {
  absl::StatusOr<Grid> grid = ParseMovingAiMap(text, "fuzz.map", kDefaultMaxReaderCells);
  if (!grid.ok()) {
    PATHD_FUZZ_CHECK(grid.status().code() == absl::StatusCode::kInvalidArgument ||
                         grid.status().code() == absl::StatusCode::kResourceExhausted,
                     "reader errors are INVALID_ARGUMENT (RESOURCE_EXHAUSTED over max_cells)");
    return;
  }
  PATHD_FUZZ_CHECK(grid->width() >= 1 && grid->height() >= 1, "dimensions");
  PATHD_FUZZ_CHECK(grid->size() == static_cast<size_t>(grid->width()) *
                                       static_cast<size_t>(grid->height()),
                   "cell count");
  PATHD_FUZZ_CHECK(static_cast<int64_t>(grid->size()) <= kDefaultMaxReaderCells, "max_cells");
  for (uint8_t cost : grid->cells()) {
    PATHD_FUZZ_CHECK(cost == kFreeCost || cost == kLethalCost, "cell cost");
  }
  absl::StatusOr<Grid> again =
      ParseMovingAiMap(ToMovingAiText(*grid), "roundtrip.map", kDefaultMaxReaderCells);
  PATHD_FUZZ_CHECK(again.ok(), "round trip parses");
  PATHD_FUZZ_CHECK(again->width() == grid->width() &&
                       again->height() == grid->height() &&
                       again->cells() == grid->cells(),
                   "round trip equals");
}

void CheckScenarios(std::string_view text) {
  absl::StatusOr<ScenarioFile> file = ParseMovingAiScenarioFile(text, "fuzz.scen");
  if (!file.ok()) {
    PATHD_FUZZ_CHECK(file.status().code() == absl::StatusCode::kInvalidArgument,
                     "reader errors are INVALID_ARGUMENT");
    return;
  }
  PATHD_FUZZ_CHECK(file->version == "1" || file->version == "1.0", "version");
  int previous_line = 1;
  for (const Scenario& s : file->scenarios) {
    PATHD_FUZZ_CHECK(s.line > previous_line, "lines increase");
    previous_line = s.line;
    PATHD_FUZZ_CHECK(s.map_width >= 1 && s.map_width <= kMaxGridDimension &&
                         s.map_height >= 1 && s.map_height <= kMaxGridDimension,
                     "map size");
    for (const Cell c : {s.start, s.goal}) {
      PATHD_FUZZ_CHECK(c.x >= 0 && c.y >= 0 && c.x < s.map_width &&
                           c.y < s.map_height,
                       "endpoint on the map");
    }
    PATHD_FUZZ_CHECK(std::isfinite(s.optimal_length) && s.optimal_length >= 0,
                     "optimal length");
    const double tolerance = ScenarioTolerance(s, file->version);
    PATHD_FUZZ_CHECK(std::isfinite(tolerance) && tolerance > 0, "tolerance");
  }
}

}  // namespace
}  // namespace pathd

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  pathd::CheckMap(text);
  pathd::CheckScenarios(text);
  return 0;
}
