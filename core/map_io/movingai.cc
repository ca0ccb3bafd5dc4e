// Moving AI benchmark readers: .map grids and .map.scen scenario lists
// (https://movingai.com/benchmarks/formats.html). Strict about structure so a
// damaged or mislabelled file fails loudly instead of loading as another map;
// lenient only where the published files themselves vary (CRLF, trailing
// whitespace in the header, a missing final newline, blank trailing lines).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "core/status_macros.h"
#include "core/map_io/text_util.h"

namespace pathd {
namespace {

using internal::Quote;
using internal::ToAbsl;

// Yields the lines of a text one at a time, dropping one trailing '\r' per
// line so CRLF files (the street maps) read like LF ones. A missing final
// newline still yields the last line; a final newline yields no extra line.
class LineReader {
 public:
  explicit LineReader(absl::string_view text) : rest_(text) {}

  // Sets `line` to the next line; false at the end of the text.
  bool Next(absl::string_view& line) {
    if (rest_.empty()) return false;
    const size_t newline = rest_.find('\n');
    if (newline == absl::string_view::npos) {
      line = rest_;
      rest_ = {};
    } else {
      line = rest_.substr(0, newline);
      rest_.remove_prefix(newline + 1);
    }
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    ++line_number_;
    return true;
  }

  // 1-based number of the line last returned by Next().
  int64_t line_number() const { return line_number_; }

 private:
  absl::string_view rest_;
  int64_t line_number_ = 0;
};

absl::Status Error(absl::string_view source, int64_t line,
                   absl::string_view problem) {
  return absl::InvalidArgumentError(
      absl::StrCat(source, ":", line, ": ", problem));
}

std::vector<absl::string_view> SplitFields(absl::string_view line) {
  return absl::StrSplit(line, absl::ByAnyChar(" \t\r\v\f"), absl::SkipEmpty());
}

// Parses the "<key> <N>" header line for a grid dimension.
absl::StatusOr<int32_t> ParseDimension(absl::string_view line,
                                       absl::string_view key,
                                       absl::string_view other_key,
                                       absl::string_view source,
                                       int64_t line_number) {
  const std::vector<absl::string_view> fields = SplitFields(line);
  if (!absl::StartsWith(line, key) || fields.size() != 2 || fields[0] != key) {
    std::string problem =
        absl::StrCat("expected '", key, " <N>', got ", Quote(line));
    // The classic mistake is writing width first; say so instead of
    // silently transposing the map.
    if (!fields.empty() && fields[0] == other_key) {
      absl::StrAppend(&problem, " (height comes before width)");
    }
    return Error(source, line_number, problem);
  }
  const absl::string_view value = fields[1];
  const absl::string_view digits =
      absl::StartsWith(value, "-") ? value.substr(1) : value;
  const bool numeric =
      !digits.empty() &&
      std::all_of(digits.begin(), digits.end(), absl::ascii_isdigit);
  if (!numeric) {
    return Error(source, line_number,
                 absl::StrCat(key, " ", Quote(value), " is not an integer"));
  }
  int64_t n = 0;
  // Longer than any in-range value: reject without risking overflow.
  const bool parsed = digits.size() <= 12 && absl::SimpleAtoi(value, &n);
  if (!parsed || n < 1 || n > kMaxGridDimension) {
    return Error(source, line_number,
                 absl::StrCat(key, " ", Quote(value), " is out of range 1..",
                              kMaxGridDimension));
  }
  return static_cast<int32_t>(n);
}

// Cost for each byte of a map row; -1 marks characters the format does not
// define. Moving AI's terrain classes reduce to passable {. G S} and blocked
// {@ O T W} for ground-based paths (see the benchmark README).
constexpr std::array<int16_t, 256> MakeCharCosts() {
  std::array<int16_t, 256> costs{};
  for (int16_t& c : costs) c = -1;
  for (unsigned char ch : absl::string_view(".GS")) costs[ch] = kFreeCost;
  for (unsigned char ch : absl::string_view("@OTW")) costs[ch] = kLethalCost;
  return costs;
}
constexpr std::array<int16_t, 256> kCharCosts = MakeCharCosts();

absl::StatusOr<Grid> ParseMap(absl::string_view text, absl::string_view source,
                              int64_t max_cells) {
  LineReader reader(text);
  absl::string_view line;

  // Header: four lines, fixed order.
  const auto next_header_line =
      [&](absl::string_view expected) -> absl::Status {
    if (!reader.Next(line)) {
      return Error(source, reader.line_number() + 1,
                   absl::StrCat("truncated header: expected '", expected, "'"));
    }
    line = absl::StripTrailingAsciiWhitespace(line);
    return absl::OkStatus();
  };

  PATHD_RETURN_IF_ERROR(next_header_line("type octile"));
  if (line != "type octile") {
    return Error(source, reader.line_number(),
                 absl::StrCat("expected 'type octile', got ", Quote(line)));
  }
  PATHD_RETURN_IF_ERROR(next_header_line("height <H>"));
  PATHD_ASSIGN_OR_RETURN(
      const int32_t height,
      ParseDimension(line, "height", "width", source, reader.line_number()));
  PATHD_RETURN_IF_ERROR(next_header_line("width <W>"));
  PATHD_ASSIGN_OR_RETURN(
      const int32_t width,
      ParseDimension(line, "width", "height", source, reader.line_number()));
  const int64_t cells = int64_t{width} * height;
  if (cells > max_cells) {
    // A size limit, not a syntax error: the caller may allow bigger maps.
    return absl::ResourceExhaustedError(absl::StrCat(
        source, ":", reader.line_number(), ": map of ", width, " x ", height,
        " = ", cells, " cells exceeds the limit of ", max_cells, " cells"));
  }
  PATHD_RETURN_IF_ERROR(next_header_line("map"));
  if (line != "map") {
    return Error(source, reader.line_number(),
                 absl::StrCat("expected 'map', got ", Quote(line)));
  }

  std::vector<uint8_t> costs;
  // Every row takes `width` bytes of the text, so reserving more than the
  // text's size would only let a short header ("height 16384 / width
  // 16384") allocate far more than the input it arrived in; such a text
  // fails below with the row it ends at.
  costs.reserve(static_cast<size_t>(
      std::min(cells, static_cast<int64_t>(text.size()))));
  for (int32_t y = 0; y < height; ++y) {
    if (!reader.Next(line)) {
      return Error(source, reader.line_number() + 1,
                   absl::StrCat("file ends after ", y, " of ", height,
                                " rows declared by 'height'"));
    }
    // Rows are reported 1-based like the line numbers; cells 0-based.
    if (line.size() != static_cast<size_t>(width)) {
      return Error(source, reader.line_number(),
                   absl::StrCat("row ", y + 1, " has ", line.size(),
                                " characters, expected ", width));
    }
    for (int32_t x = 0; x < width; ++x) {
      const int16_t cost = kCharCosts[static_cast<unsigned char>(line[x])];
      if (cost < 0) {
        return Error(source, reader.line_number(),
                     absl::StrCat("column ", x + 1, ": invalid character ",
                                  Quote(line.substr(x, 1)), " at cell (", x,
                                  ", ", y, "); expected one of . G S @ O T W"));
      }
      costs.push_back(static_cast<uint8_t>(cost));
    }
  }
  while (reader.Next(line)) {
    if (!absl::StripAsciiWhitespace(line).empty()) {
      return Error(source, reader.line_number(),
                   absl::StrCat("unexpected row after the ", height,
                                " rows declared by 'height'"));
    }
  }
  return Grid::FromCells(width, height, std::move(costs));
}

}  // namespace

absl::StatusOr<Grid> ParseMovingAiMap(std::string_view text,
                                      std::string_view source,
                                      int64_t max_cells) {
  return ParseMap(ToAbsl(text), ToAbsl(source), max_cells);
}

absl::StatusOr<Grid> ReadMovingAiMapFile(const std::string& path,
                                         int64_t max_cells) {
  PATHD_ASSIGN_OR_RETURN(const std::string text, ReadFileToString(path));
  return ParseMap(text, path, max_cells);
}

namespace {

absl::StatusOr<ScenarioFile> ParseScenarios(absl::string_view text,
                                            absl::string_view source) {
  LineReader reader(text);
  absl::string_view line;
  ScenarioFile file;
  {
    const bool has_line = reader.Next(line);
    const std::vector<absl::string_view> fields =
        has_line ? SplitFields(line) : std::vector<absl::string_view>{};
    if (fields.size() != 2 || fields[0] != "version" ||
        (fields[1] != "1" && fields[1] != "1.0")) {
      return Error(source, 1,
                   absl::StrCat("expected 'version 1' or 'version 1.0', got ",
                                has_line ? Quote(line) : "end of file"));
    }
    file.version = std::string(fields[1]);
  }

  static constexpr const char* kFieldNames[9] = {
      "bucket",  "map",    "map width", "map height",    "start x",
      "start y", "goal x", "goal y",    "optimal length"};
  while (reader.Next(line)) {
    const std::vector<absl::string_view> fields = SplitFields(line);
    // The published files end with blank lines; anything short is not a
    // scenario.
    if (fields.size() < 9) continue;
    const int64_t line_number = reader.line_number();
    if (fields.size() > 9) {
      return Error(source, line_number,
                   absl::StrCat("expected 9 fields, got ", fields.size()));
    }
    int32_t ints[9] = {};
    for (int i : {0, 2, 3, 4, 5, 6, 7}) {
      if (!absl::SimpleAtoi(fields[i], &ints[i])) {
        return Error(source, line_number,
                     absl::StrCat("field ", i + 1, " (", kFieldNames[i], ") ",
                                  Quote(fields[i]), " is not an integer"));
      }
    }
    Scenario s;
    s.line = static_cast<int>(line_number);
    s.bucket = ints[0];
    s.map = std::string(fields[1]);
    s.map_width = ints[2];
    s.map_height = ints[3];
    s.start = Cell{ints[4], ints[5]};
    s.goal = Cell{ints[6], ints[7]};
    s.optimal_text = std::string(fields[8]);
    if (s.map_width < 1 || s.map_width > kMaxGridDimension ||
        s.map_height < 1 || s.map_height > kMaxGridDimension) {
      return Error(source, line_number,
                   absl::StrCat("map size ", s.map_width, " x ", s.map_height,
                                " is out of range 1..", kMaxGridDimension));
    }
    for (const auto& [name, cell] :
         {std::pair{"start", s.start}, std::pair{"goal", s.goal}}) {
      if (cell.x < 0 || cell.y < 0 || cell.x >= s.map_width ||
          cell.y >= s.map_height) {
        return Error(
            source, line_number,
            absl::StrCat(name, " ", CellToString(cell), " is outside the ",
                         s.map_width, " x ", s.map_height, " map"));
      }
    }
    if (!absl::SimpleAtod(fields[8], &s.optimal_length) ||
        !std::isfinite(s.optimal_length) || s.optimal_length < 0) {
      return Error(source, line_number,
                   absl::StrCat("field 9 (optimal length) ", Quote(fields[8]),
                                " is not a finite non-negative number"));
    }
    file.scenarios.push_back(std::move(s));
  }
  return file;
}

}  // namespace

absl::StatusOr<ScenarioFile> ParseMovingAiScenarioFile(
    std::string_view text, std::string_view source) {
  return ParseScenarios(ToAbsl(text), ToAbsl(source));
}

absl::StatusOr<std::vector<Scenario>> ParseMovingAiScenarios(
    std::string_view text, std::string_view source) {
  PATHD_ASSIGN_OR_RETURN(ScenarioFile file,
                         ParseScenarios(ToAbsl(text), ToAbsl(source)));
  return std::move(file.scenarios);
}

absl::StatusOr<ScenarioFile> ReadMovingAiScenarioFileWithVersion(
    const std::string& path) {
  PATHD_ASSIGN_OR_RETURN(const std::string text, ReadFileToString(path));
  return ParseScenarios(text, path);
}

absl::StatusOr<std::vector<Scenario>> ReadMovingAiScenarioFile(
    const std::string& path) {
  PATHD_ASSIGN_OR_RETURN(ScenarioFile file,
                         ReadMovingAiScenarioFileWithVersion(path));
  return std::move(file.scenarios);
}

}  // namespace pathd
