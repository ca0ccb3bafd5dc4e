// Implementation of pathctl's shared text helpers.
#include "client/pathctl/text.h"

#include <cmath>
#include <utility>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/strip.h"

namespace pathd::pathctl {

absl::Status BadArg(absl::string_view what, absl::string_view text,
                    absl::string_view expected) {
  return absl::InvalidArgumentError(
      absl::StrCat(what, ": '", text, "' is not ", expected));
}

absl::StatusOr<std::vector<int32_t>> ParseInts(Args args,
                                               std::span<const char* const> names) {
  std::vector<int32_t> values;
  for (size_t i = 0; i < args.size(); ++i) {
    int32_t value = 0;
    if (!absl::SimpleAtoi(args[i], &value)) {
      return BadArg(names[i], args[i], "an integer");
    }
    values.push_back(value);
  }
  return values;
}

absl::StatusOr<std::vector<double>> ParseDoubles(Args args,
                                                 std::span<const char* const> names) {
  std::vector<double> values;
  for (size_t i = 0; i < args.size(); ++i) {
    double value = 0;
    if (!absl::SimpleAtod(args[i], &value) || !std::isfinite(value)) {
      return BadArg(names[i], args[i], "a finite number");
    }
    values.push_back(value);
  }
  return values;
}

absl::StatusOr<uint32_t> ParseCost(absl::string_view text) {
  static constexpr std::pair<absl::string_view, uint32_t> kNamed[] = {
      {"free", 0}, {"inscribed", 253}, {"lethal", 254}, {"unknown", 255}};
  for (const auto& [name, cost] : kNamed) {
    if (text == name) return cost;
  }
  uint32_t cost = 0;
  if (!absl::SimpleAtoi(text, &cost) || cost > 255) {
    return BadArg("COST", text, "0..255, free, inscribed, lethal or unknown");
  }
  return cost;
}

std::string FormatCell(const v1::Cell& cell) {
  return absl::StrFormat("(%d,%d)", cell.x(), cell.y());
}

std::string FormatPath(const google::protobuf::RepeatedPtrField<v1::Cell>& cells) {
  std::vector<std::string> parts;
  parts.reserve(cells.size());
  for (const v1::Cell& cell : cells) parts.push_back(FormatCell(cell));
  return absl::StrJoin(parts, " ");
}

std::string OutcomeName(v1::PlanOutcome outcome) {
  absl::string_view name = v1::PlanOutcome_Name(outcome);
  absl::ConsumePrefix(&name, "PLAN_OUTCOME_");
  return std::string(name);
}

char CellGlyph(uint8_t cost) {
  if (cost == 0) return '.';
  if (cost <= 252) return static_cast<char>('1' + (cost - 1) / 28);
  if (cost == 255) return '?';
  return '#';
}

std::string RenderCells(int32_t width, int32_t height, absl::string_view cells) {
  std::string text;
  text.reserve(static_cast<size_t>(width + 1) * static_cast<size_t>(height));
  for (int32_t y = 0; y < height; ++y) {
    for (int32_t x = 0; x < width; ++x) {
      text.push_back(CellGlyph(static_cast<uint8_t>(
          cells[static_cast<size_t>(y) * static_cast<size_t>(width) +
                static_cast<size_t>(x)])));
    }
    text.push_back('\n');
  }
  return text;
}

}  // namespace pathd::pathctl
