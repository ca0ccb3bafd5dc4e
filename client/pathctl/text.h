// Small text helpers every pathctl command and its lower layers share:
// parsing positional numbers and cost bytes, and printing cells, paths,
// outcomes and map cells as glyphs. Nothing here talks to a server.
#ifndef PATHD_CLIENT_PATHCTL_TEXT_H_
#define PATHD_CLIENT_PATHCTL_TEXT_H_

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::pathctl {

// Positional arguments of a command, after its name.
using Args = std::span<const std::string>;

// INVALID_ARGUMENT "WHAT: 'TEXT' is not EXPECTED".
absl::Status BadArg(absl::string_view what, absl::string_view text,
                    absl::string_view expected);

// Parses args[i] as the integer (or finite number) named names[i];
// INVALID_ARGUMENT naming the first bad one. names.size() >= args.size().
absl::StatusOr<std::vector<int32_t>> ParseInts(Args args,
                                               std::span<const char* const> names);
absl::StatusOr<std::vector<double>> ParseDoubles(Args args,
                                                 std::span<const char* const> names);

// A cost byte as a number 0..255 or the Nav2 name of a special value (free,
// inscribed, lethal, unknown); INVALID_ARGUMENT "COST: ..." otherwise.
absl::StatusOr<uint32_t> ParseCost(absl::string_view text);

// "(x,y)".
std::string FormatCell(const v1::Cell& cell);
// Cells as "(x,y) (x,y) ...".
std::string FormatPath(const google::protobuf::RepeatedPtrField<v1::Cell>& cells);
// "GOAL_OCCUPIED" for PLAN_OUTCOME_GOAL_OCCUPIED.
std::string OutcomeName(v1::PlanOutcome outcome);

// One character per cell: '.' free (0); '1'..'9' weighted 1..252, digit d
// covering costs 28(d-1)+1 .. 28d; '#' inscribed or lethal (253, 254); '?'
// unknown (255).
char CellGlyph(uint8_t cost);
// Renders row-major cells as `height` lines of `width` glyphs, row 0 first.
// Precondition: cells.size() == width * height.
std::string RenderCells(int32_t width, int32_t height, absl::string_view cells);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_TEXT_H_
