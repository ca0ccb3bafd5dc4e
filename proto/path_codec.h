// The packed path encoding of PlanResponse.packed_path (issue 19): a plan's
// cells as one `bytes` field, written by the server and read by the C++
// client and pathctl (the Python client has its twin in values.py). The byte
// format is documented on PlanResponse.packed_path and in docs/service.md.
#ifndef PATHD_PROTO_PATH_CODEC_H_
#define PATHD_PROTO_PATH_CODEC_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/functional/function_ref.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd {

// A cell as the codec sees it (core's Cell without core).
struct PackedCell {
  int32_t x = 0;
  int32_t y = 0;
  friend bool operator==(const PackedCell&, const PackedCell&) = default;
};

// The format byte that opens a non-empty packed path.
inline constexpr uint8_t kPackedPathMoves = 0x01;
inline constexpr uint8_t kPackedPathDeltas = 0x02;

// The packed bytes of `count` cells, cell(i) giving the i-th: empty for no
// cells, MOVES when every step is one 8-connected move, DELTAS otherwise.
// Lossless for any int32 coordinates.
std::string EncodePackedPath(int64_t count,
                             absl::FunctionRef<PackedCell(int64_t)> cell);
std::string EncodePackedPath(absl::Span<const PackedCell> cells);

// The cells of packed bytes (none for empty bytes). INVALID_ARGUMENT naming
// packed_path and the byte or cell for truncated bytes, an unknown format
// byte, an invalid move code or padding nibble, a coordinate outside int32
// or bytes after the last cell. Never reads past `bytes`, and allocates
// no more than the bytes can hold.
absl::StatusOr<std::vector<PackedCell>> DecodePackedPath(
    std::string_view bytes);

// The world point of cell (x, y)'s centre under `frame`: the server's
// Grid::CellCenter, operation for operation, so equal to the readable
// world_path bit for bit.
v1::WorldPoint PathFrameCellCenter(const v1::PathFrame& frame, int32_t x,
                                   int32_t y);

// A packed-only response made readable: when packed_path is set and path is
// empty, fills path and world_path from packed_path and path_frame and
// clears both, so callers see the response as READABLE would have answered
// it. Anything else (readable, BOTH, no path) is left as it is. Errors as
// DecodePackedPath; the response is unchanged on error.
absl::Status UnpackPlanPath(v1::PlanResponse* response);

}  // namespace pathd

#endif  // PATHD_PROTO_PATH_CODEC_H_
