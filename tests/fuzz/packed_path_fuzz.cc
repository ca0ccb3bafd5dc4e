// Fuzz target: the packed path decoder (proto/path_codec.h), which reads
// PlanResponse.packed_path from the wire. Besides "no crash, no UB, no
// allocation beyond what the bytes can hold" (run_fuzzers.sh's
// -malloc_limit_mb), bytes that decode must survive a round trip: the
// cells encoded again decode to the same cells.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "proto/path_codec.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const absl::StatusOr<std::vector<pathd::PackedCell>> cells =
      pathd::DecodePackedPath(bytes);
  if (!cells.ok()) {
    PATHD_FUZZ_CHECK(
        cells.status().code() == absl::StatusCode::kInvalidArgument,
        "bad bytes are INVALID_ARGUMENT");
    return 0;
  }
  const std::string again = pathd::EncodePackedPath(*cells);
  const absl::StatusOr<std::vector<pathd::PackedCell>> round =
      pathd::DecodePackedPath(again);
  PATHD_FUZZ_CHECK(round.ok() && *round == *cells, "decoded cells round-trip");
  return 0;
}
