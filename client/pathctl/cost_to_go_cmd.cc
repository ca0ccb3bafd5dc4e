// pathctl cost-to-go: CostToGo's field for a goal, printed as a table of
// numbers, long-form CSV, JSON, or written to a CSV file.
#include "client/pathctl/cost_to_go_cmd.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <fstream>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "client/pathctl/command.h"
#include "client/pathctl/files.h"

namespace pathd::pathctl {
namespace {

// Largest window printed as a table; bigger ones go to --cost_to_go_file.
constexpr int32_t kMaxTableColumns = 16;
constexpr int32_t kMaxTableRows = 64;

// "X,Y,W,H" as a CellWindow.
absl::StatusOr<v1::CellWindow> ParseWindow(absl::string_view text) {
  const std::vector<std::string> parts = absl::StrSplit(text, ',');
  static constexpr const char* kNames[] = {"--window X", "--window Y",
                                           "--window W", "--window H"};
  if (parts.size() != 4) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--window takes X,Y,W,H (first column, first row, width, height), not '",
        text, "'"));
  }
  absl::StatusOr<std::vector<int32_t>> v = ParseInts(parts, kNames);
  if (!v.ok()) return v.status();
  if ((*v)[2] <= 0 || (*v)[3] <= 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--window width and height must be positive, not ", (*v)[2], "x", (*v)[3]));
  }
  v1::CellWindow window;
  window.set_x((*v)[0]);
  window.set_y((*v)[1]);
  window.set_width((*v)[2]);
  window.set_height((*v)[3]);
  return window;
}

// The field as rows of numbers with column and row labels, "inf" where the
// goal cannot be reached.
std::string FormatCostTable(const v1::CostToGoResponse& response) {
  const v1::CellWindow& w = response.window();
  std::string text = "  y\\x";
  for (int32_t x = 0; x < w.width(); ++x) {
    absl::StrAppendFormat(&text, " %7d", w.x() + x);
  }
  text.push_back('\n');
  for (int32_t y = 0; y < w.height(); ++y) {
    absl::StrAppendFormat(&text, "%5d", w.y() + y);
    for (int32_t x = 0; x < w.width(); ++x) {
      const float v = response.cost(y * w.width() + x);
      absl::StrAppend(&text, std::isfinite(v) ? absl::StrFormat(" %7.2f", v)
                                              : std::string("     inf"));
    }
    text.push_back('\n');
  }
  return text;
}

int CostToGo(CommandEnv& env, Args args) {
  const CostToGoOptions& options = env.options().cost_to_go;
  if (args.size() != 3) return env.Usage("cost-to-go takes NAME GX GY");
  v1::CostToGoRequest request;
  request.set_map(args[0]);
  static constexpr const char* kNames[] = {"GX", "GY"};
  if (options.world) {
    absl::StatusOr<std::vector<double>> g = ParseDoubles(args.subspan(1), kNames);
    if (!g.ok()) return env.Usage(g.status().message());
    request.mutable_goal()->mutable_world()->set_x((*g)[0]);
    request.mutable_goal()->mutable_world()->set_y((*g)[1]);
  } else {
    absl::StatusOr<std::vector<int32_t>> g = ParseInts(args.subspan(1), kNames);
    if (!g.ok()) {
      return env.Usage(absl::StrCat(g.status().message(),
                                    " (use --world for coordinates in metres)"));
    }
    request.mutable_goal()->mutable_cell()->set_x((*g)[0]);
    request.mutable_goal()->mutable_cell()->set_y((*g)[1]);
  }
  if (absl::Status s = SetCostOptions(env.options().cost, request.mutable_options());
      !s.ok()) {
    return env.Usage(s.message());
  }
  if (!options.window.empty()) {
    absl::StatusOr<v1::CellWindow> window = ParseWindow(options.window);
    if (!window.ok()) return env.Usage(window.status().message());
    *request.mutable_window() = *window;
  }
  absl::StatusOr<v1::CostToGoResponse> response = env.client().CostToGo(request);
  if (!response.ok()) return env.Fail(response.status());
  const v1::CellWindow& w = response->window();
  if (int64_t{w.width()} * w.height() != response->cost_size()) {
    return env.Fail(absl::InternalError(absl::StrFormat(
        "server sent %d costs for a %dx%d window", response->cost_size(),
        w.width(), w.height())));
  }
  if (!options.cost_to_go_file.empty()) {
    if (absl::Status s =
            WriteCostToGoCsv(options.cost_to_go_file, w.width(), response->cost());
        !s.ok()) {
      return env.Fail(s);
    }
  }
  if (env.json()) return env.PrintJson(*response);
  if (env.csv()) {
    // Long form, one row per cell: what plotting and data-frame tools read.
    Table table({"x", "y", "cost"});
    for (int32_t y = 0; y < w.height(); ++y) {
      for (int32_t x = 0; x < w.width(); ++x) {
        table.AddRow({absl::StrCat(w.x() + x), absl::StrCat(w.y() + y),
                      FormatNumber(response->cost(y * w.width() + x))});
      }
    }
    return env.PrintCsv(table);
  }
  const int64_t reachable =
      std::count_if(response->cost().begin(), response->cost().end(),
                    [](float v) { return std::isfinite(v); });
  std::ostream& out = env.out();
  out << absl::StrFormat(
      "map version: %d\n"
      "goal:        %s\n"
      "window:      x %d..%d, y %d..%d (%dx%d cells)\n"
      "reachable:   %d of %d cells\n"
      "cache hit:   %s\n"
      "expansions:  %d\n",
      response->map_version(), FormatCell(response->goal()), w.x(),
      w.x() + w.width() - 1, w.y(), w.y() + w.height() - 1, w.width(),
      w.height(), reachable, response->cost_size(),
      response->cache_hit() ? "yes" : "no", response->expansions());
  if (!options.cost_to_go_file.empty()) {
    out << "cost-to-go:  " << response->cost_size() << " cells written to "
        << options.cost_to_go_file << "\n";
  } else if (w.width() <= kMaxTableColumns && w.height() <= kMaxTableRows) {
    out << "\n" << FormatCostTable(*response);
  } else {
    out << absl::StrFormat(
        "(tables go up to %dx%d cells: give --cost_to_go_file F for the CSV, "
        "or a smaller --window)\n",
        kMaxTableColumns, kMaxTableRows);
  }
  return kExitOk;
}

// Plan returns doubles, CostToGo the 4-byte floats the server stores.
template <typename T>
absl::Status WriteCsv(const std::string& path, int32_t width,
                      const google::protobuf::RepeatedField<T>& field) {
  if (width <= 0 || field.size() % width != 0) {
    return absl::DataLossError(absl::StrCat("cost-to-go field of ", field.size(),
                                            " values does not fill rows of ", width));
  }
  errno = 0;
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) return CannotWrite(path);
  std::string line;
  for (int i = 0; i < field.size(); ++i) {
    const double v = static_cast<double>(field.Get(i));
    if (i % width != 0) line.push_back(',');
    absl::StrAppend(&line, std::isfinite(v) ? absl::StrFormat("%.6f", v) : "inf");
    if (i % width == width - 1) {
      line.push_back('\n');
      file << line;
      line.clear();
    }
  }
  file << line;
  file.flush();
  if (!file) return absl::DataLossError(absl::StrCat("error writing ", path));
  return absl::OkStatus();
}

}  // namespace

absl::Status WriteCostToGoCsv(const std::string& path, int32_t width,
                              const google::protobuf::RepeatedField<double>& field) {
  return WriteCsv(path, width, field);
}

absl::Status WriteCostToGoCsv(const std::string& path, int32_t width,
                              const google::protobuf::RepeatedField<float>& field) {
  return WriteCsv(path, width, field);
}

namespace {

constexpr absl::string_view kCostToGoFlags[] = {
    "world", "window", "cost_to_go_file", "connectivity", "cost_weight",
    "unknown_is_free", "robot_radius", "robot_radius_cells", "min_clearance",
    "min_clearance_cells", "inflation_radius",
    "inflation_radius_cells", "cost_scaling_factor"};

}  // namespace

const Command kCostToGoCommand = {
    .name = "cost-to-go",
    .synopsis = "NAME GX GY [--window X,Y,W,H]\n"
                " [--cost_to_go_file F] [--world] [cost options]",
    .help = "Prints the cost-to-go field of goal (GX, GY) on map NAME: every cell's\n"
            "cost of the cheapest path to the goal (inf: unreachable), from the\n"
            "server's cache when it has it. --window limits it to columns X..X+W-1\n"
            "and rows Y..Y+H-1; --cost_to_go_file writes it as CSV instead of a\n"
            "table (tables go up to 16x64 cells).",
    .flags = kCostToGoFlags,
    .run = CostToGo,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
