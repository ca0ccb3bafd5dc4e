// Fuzz target: the ROS map_server reader (core/map_io/map_io.h ParseRosMapYaml and
// ParseRosMap). The input is "<yaml>\0<pgm>"; without a NUL byte the whole
// input is offered to both parsers. When the YAML half does not parse, the
// image is still read with default metadata (the mode picked by the input's
// length) so mutations of the YAML never starve the PGM parser. A grid that
// parses must have the metadata's pose and only the costs its mode can
// produce. As in movingai_fuzz.cc, the default cell limit and
// run_fuzzers.sh's -malloc_limit_mb=64 catch allocations sized by a header
// rather than by the input.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "tests/fuzz/fuzz_check.h"

namespace pathd {
namespace {


bool CostPossible(RosMapMetadata::Mode mode, uint8_t cost) {
  switch (mode) {
    case RosMapMetadata::Mode::kTrinary:
      return cost == kFreeCost || cost == kLethalCost || cost == kUnknownCost;
    case RosMapMetadata::Mode::kScale:
      return cost <= kMaxTraversableCost || cost == kLethalCost;
    case RosMapMetadata::Mode::kRaw:
      return true;
  }
  return false;
}

void Check(std::string_view input) {
  const size_t nul = input.find('\0');
  const std::string_view yaml = input.substr(0, nul);
  const std::string_view pgm =
      nul == std::string_view::npos ? input : input.substr(nul + 1);

  absl::StatusOr<RosMapMetadata> parsed = ParseRosMapYaml(yaml, "fuzz.yaml");
  RosMapMetadata metadata;
  if (parsed.ok()) {
    PATHD_FUZZ_CHECK(!parsed->image.empty(), "image named");
    PATHD_FUZZ_CHECK(parsed->resolution > 0, "resolution");
    PATHD_FUZZ_CHECK(parsed->free_thresh >= 0 &&
                         parsed->free_thresh < parsed->occupied_thresh &&
                         parsed->occupied_thresh <= 1,
                     "thresholds");
    metadata = *parsed;
  } else {
    PATHD_FUZZ_CHECK(parsed.status().code() == absl::StatusCode::kInvalidArgument,
                     "reader errors are INVALID_ARGUMENT");
    metadata.image = "fuzz.pgm";
    metadata.resolution = 0.05;
    metadata.mode = static_cast<RosMapMetadata::Mode>(input.size() % 3);
  }

  absl::StatusOr<Grid> grid = ParseRosMap(metadata, pgm, "fuzz.pgm", kDefaultMaxReaderCells);
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
  PATHD_FUZZ_CHECK(grid->resolution() == metadata.resolution, "resolution");
  PATHD_FUZZ_CHECK(grid->origin().x == metadata.origin.x &&
                       grid->origin().y == metadata.origin.y &&
                       grid->origin().yaw == metadata.origin.yaw,
                   "origin");
  for (uint8_t cost : grid->cells()) {
    PATHD_FUZZ_CHECK(CostPossible(metadata.mode, cost), "cost of the mode");
  }
}

}  // namespace
}  // namespace pathd

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  pathd::Check(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
