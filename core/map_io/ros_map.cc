// ROS map_server maps: the YAML metadata (https://wiki.ros.org/map_server) and
// the PGM image it names (netpbm P2 plain or P5 raw, 8- or 16-bit). yaml-cpp
// reports errors by throwing; every exception is caught here and turned into
// an absl::Status so none crosses out of core.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "core/status_macros.h"
#include "core/map_io/text_util.h"

namespace pathd {
namespace {

using internal::Quote;
using internal::ToAbsl;

// ---------------------------------------------------------------- YAML ----

// Plausible ranges of the metadata. Finite is not enough: a resolution of
// 1e-320 (a denormal) or an origin of 1e308 metres passes isfinite but makes
// every world coordinate overflow, underflow or lose all precision. A
// micrometre to a thousand kilometres per cell and an origin within a million
// kilometres cover every robot map with room to spare.
constexpr double kMinResolution = 1e-6;
constexpr double kMaxResolution = 1e6;
constexpr double kMaxOriginMetres = 1e9;
// Yaw in radians; map_server only ever writes 0, but a few turns either way
// is still meaningful.
constexpr double kMaxYawRadians = 100.0;

// Empty when `value` is in range for `field` ("resolution", "origin" x/y or
// "origin yaw"), else the problem, for both the YAML and the request paths.
std::string RangeProblem(absl::string_view field, double value) {
  if (field == "resolution") {
    if (value < kMinResolution || value > kMaxResolution) {
      return absl::StrCat("must be between ", kMinResolution, " and ",
                          kMaxResolution, " metres per cell, got ", value);
    }
  } else if (field == "origin") {
    if (std::fabs(value) > kMaxOriginMetres) {
      return absl::StrCat("must be within +/-", kMaxOriginMetres,
                          " metres, got ", value);
    }
  } else if (std::fabs(value) > kMaxYawRadians) {
    return absl::StrCat("yaw must be within +/-", kMaxYawRadians,
                        " radians, got ", value);
  }
  return "";
}

// "<source>:<line>" for a node yaml-cpp knows the position of, else "<source>".
std::string Where(absl::string_view source, const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.is_null() || mark.line < 0) return std::string(source);
  return absl::StrCat(source, ":", mark.line + 1);
}

absl::Status KeyError(absl::string_view source, const YAML::Node& node,
                      absl::string_view key, absl::string_view problem) {
  return absl::InvalidArgumentError(
      absl::StrCat(Where(source, node), ": '", key, "' ", problem));
}

// A finite number from a scalar node. absl::SimpleAtod rather than
// node.as<double>() so YAML spellings like ".inf" cannot slip through.
absl::StatusOr<double> NumberValue(absl::string_view source,
                                   const YAML::Node& node,
                                   absl::string_view key) {
  double value = 0.0;
  if (!node.IsScalar() || !absl::SimpleAtod(node.Scalar(), &value) ||
      !std::isfinite(value)) {
    return KeyError(
        source, node, key,
        absl::StrCat("must be a finite number",
                     node.IsScalar()
                         ? absl::StrCat(", got ", Quote(node.Scalar()))
                         : ""));
  }
  return value;
}

absl::StatusOr<RosMapMetadata> ParseRosMapYamlOrThrow(
    absl::string_view yaml, absl::string_view source) {
  const YAML::Node root = YAML::Load(std::string(yaml));
  if (!root.IsMap()) {
    return absl::InvalidArgumentError(
        absl::StrCat(source,
                     ": expected a YAML mapping with image, resolution "
                     "and origin"));
  }
  RosMapMetadata metadata;

  const YAML::Node image = root["image"];
  if (!image.IsDefined() || image.IsNull()) {
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": missing required key 'image'"));
  }
  if (!image.IsScalar() || image.Scalar().empty()) {
    return KeyError(source, image, "image", "must be a non-empty file name");
  }
  metadata.image = image.Scalar();

  const YAML::Node resolution = root["resolution"];
  if (!resolution.IsDefined() || resolution.IsNull()) {
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": missing required key 'resolution'"));
  }
  PATHD_ASSIGN_OR_RETURN(metadata.resolution,
                         NumberValue(source, resolution, "resolution"));
  if (metadata.resolution <= 0.0) {
    return KeyError(
        source, resolution, "resolution",
        absl::StrCat("must be positive, got ", metadata.resolution));
  }
  if (std::string problem = RangeProblem("resolution", metadata.resolution);
      !problem.empty()) {
    return KeyError(source, resolution, "resolution", problem);
  }

  const YAML::Node origin = root["origin"];
  if (!origin.IsDefined() || origin.IsNull()) {
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": missing required key 'origin'"));
  }
  if (!origin.IsSequence() || origin.size() != 3) {
    return KeyError(
        source, origin, "origin",
        absl::StrCat("must be a list of 3 numbers [x, y, yaw]",
                     origin.IsSequence()
                         ? absl::StrCat(", got ", origin.size(), " elements")
                         : ""));
  }
  PATHD_ASSIGN_OR_RETURN(metadata.origin.x,
                         NumberValue(source, origin[0], "origin"));
  PATHD_ASSIGN_OR_RETURN(metadata.origin.y,
                         NumberValue(source, origin[1], "origin"));
  PATHD_ASSIGN_OR_RETURN(metadata.origin.yaw,
                         NumberValue(source, origin[2], "origin"));
  for (const auto& [index, field, value] :
       {std::tuple{0, "origin", metadata.origin.x},
        std::tuple{1, "origin", metadata.origin.y},
        std::tuple{2, "origin yaw", metadata.origin.yaw}}) {
    if (std::string problem = RangeProblem(field, value); !problem.empty()) {
      return KeyError(source, origin[index], "origin", problem);
    }
  }

  if (const YAML::Node negate = root["negate"];
      negate.IsDefined() && !negate.IsNull()) {
    // map_server writes 0/1; people write true/false. Accept both, nothing
    // else, so "negate: 2" is not quietly read as true.
    bool value = false;
    if (negate.IsScalar() && negate.Scalar() == "0") {
      value = false;
    } else if (negate.IsScalar() && negate.Scalar() == "1") {
      value = true;
    } else if (!negate.IsScalar() ||
               !YAML::convert<bool>::decode(negate, value)) {
      return KeyError(source, negate, "negate", "must be 0, 1, true or false");
    }
    metadata.negate = value;
  }
  for (const auto& [key, field] :
       {std::pair{"occupied_thresh", &metadata.occupied_thresh},
        std::pair{"free_thresh", &metadata.free_thresh}}) {
    const YAML::Node node = root[key];
    if (!node.IsDefined() || node.IsNull()) continue;
    PATHD_ASSIGN_OR_RETURN(*field, NumberValue(source, node, key));
    if (*field < 0.0 || *field > 1.0) {
      return KeyError(source, node, key,
                      absl::StrCat("must be in 0..1, got ", *field));
    }
  }
  if (const YAML::Node mode = root["mode"];
      mode.IsDefined() && !mode.IsNull()) {
    const std::string value = mode.IsScalar() ? mode.Scalar() : "";
    if (value == "trinary") {
      metadata.mode = RosMapMetadata::Mode::kTrinary;
    } else if (value == "scale") {
      metadata.mode = RosMapMetadata::Mode::kScale;
    } else if (value == "raw") {
      metadata.mode = RosMapMetadata::Mode::kRaw;
    } else {
      return KeyError(
          source, mode, "mode",
          absl::StrCat("must be trinary, scale or raw, got ", Quote(value)));
    }
  }
  if (!(metadata.free_thresh < metadata.occupied_thresh)) {
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": 'free_thresh' (", metadata.free_thresh,
                     ") must be less than 'occupied_thresh' (",
                     metadata.occupied_thresh, ")"));
  }
  return metadata;
}

// Checks what ParseRosMap relies on, for metadata that did not come from
// ParseRosMapYaml (e.g. built by the server from a request).
absl::Status ValidateMetadata(const RosMapMetadata& m,
                              absl::string_view source) {
  const auto bad = [&](absl::string_view problem) {
    return absl::InvalidArgumentError(absl::StrCat(source, ": ", problem));
  };
  if (!std::isfinite(m.resolution) || m.resolution <= 0.0) {
    return bad(absl::StrCat(
        "'resolution' must be a positive finite number, got ", m.resolution));
  }
  if (!std::isfinite(m.origin.x) || !std::isfinite(m.origin.y) ||
      !std::isfinite(m.origin.yaw)) {
    return bad("'origin' must be finite");
  }
  for (const auto& [field, value] :
       {std::pair{"resolution", m.resolution}, std::pair{"origin", m.origin.x},
        std::pair{"origin", m.origin.y}, std::pair{"origin yaw", m.origin.yaw}}) {
    if (std::string problem = RangeProblem(field, value); !problem.empty()) {
      const absl::string_view key =
          absl::string_view(field) == "resolution" ? "resolution" : "origin";
      return bad(absl::StrCat("'", key, "' ", problem));
    }
  }
  if (!(m.free_thresh >= 0.0 && m.occupied_thresh <= 1.0 &&
        m.free_thresh < m.occupied_thresh)) {
    return bad(
        absl::StrCat("need 0 <= free_thresh < occupied_thresh <= 1, got ",
                     m.free_thresh, " and ", m.occupied_thresh));
  }
  return absl::OkStatus();
}

// ----------------------------------------------------------------- PGM ----

bool IsPgmSpace(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' ||
         c == '\f';
}

// Cursor over the text part of a PGM (header, and the raster of P2).
class PgmCursor {
 public:
  PgmCursor(absl::string_view data, absl::string_view source)
      : data_(data), source_(source) {}

  size_t pos() const { return pos_; }
  void set_pos(size_t pos) { pos_ = pos; }
  bool AtEnd() const { return pos_ >= data_.size(); }
  char Peek() const { return data_[pos_]; }

  // Skips whitespace and '#' comments (which run to the end of the line).
  void SkipSpaceAndComments() {
    while (pos_ < data_.size()) {
      if (IsPgmSpace(data_[pos_])) {
        ++pos_;
      } else if (data_[pos_] == '#') {
        while (pos_ < data_.size() && data_[pos_] != '\n' &&
               data_[pos_] != '\r')
          ++pos_;
      } else {
        break;
      }
    }
  }

  // The next run of non-space characters; empty at the end of the data.
  absl::string_view Token() {
    SkipSpaceAndComments();
    const size_t start = pos_;
    while (pos_ < data_.size() && !IsPgmSpace(data_[pos_]) &&
           data_[pos_] != '#')
      ++pos_;
    return data_.substr(start, pos_ - start);
  }

  // 1-based line of the current position. Linear, so only for errors.
  int64_t Line() const {
    int64_t line = 1;
    for (size_t i = 0; i < pos_ && i < data_.size(); ++i)
      line += data_[i] == '\n';
    return line;
  }

  absl::Status Error(absl::string_view problem) const {
    return absl::InvalidArgumentError(
        absl::StrCat(source_, ":", Line(), ": ", problem));
  }

  // A decimal header field in 1..max.
  absl::StatusOr<int32_t> HeaderNumber(absl::string_view name, int32_t max) {
    const absl::string_view token = Token();
    if (token.empty()) {
      return Error(absl::StrCat("truncated PGM header: missing ", name));
    }
    if (!std::all_of(token.begin(), token.end(), absl::ascii_isdigit)) {
      return Error(
          absl::StrCat("PGM ", name, " ", Quote(token), " is not a number"));
    }
    int64_t value = 0;
    if (token.size() > 12 || !absl::SimpleAtoi(token, &value) || value < 1 ||
        value > max) {
      return Error(absl::StrCat("PGM ", name, " ", Quote(token),
                                " is out of range 1..", max));
    }
    return static_cast<int32_t>(value);
  }

 private:
  absl::string_view data_;
  absl::string_view source_;
  size_t pos_ = 0;
};

// Cost for every sample value 0..maxval under the metadata's rules. A table
// keeps the per-pixel work trivial and the mapping identical for every pixel.
std::vector<uint8_t> MakeCostTable(const RosMapMetadata& m, int32_t maxval) {
  std::vector<uint8_t> table(static_cast<size_t>(maxval) + 1);
  for (int32_t v = 0; v <= maxval; ++v) {
    uint8_t cost;
    if (m.mode == RosMapMetadata::Mode::kRaw) {
      // Raw stores the sample itself (Nav2 ignores negate here too).
      cost = static_cast<uint8_t>(std::min(v, 255));
    } else {
      const double p = m.negate ? static_cast<double>(v) / maxval
                                : static_cast<double>(maxval - v) / maxval;
      if (p > m.occupied_thresh) {
        cost = kLethalCost;
      } else if (p < m.free_thresh) {
        cost = kFreeCost;
      } else if (m.mode == RosMapMetadata::Mode::kTrinary) {
        cost = kUnknownCost;
      } else {
        const double t =
            (p - m.free_thresh) / (m.occupied_thresh - m.free_thresh);
        const long scaled = 1 + std::lround(t * (kMaxTraversableCost - 1));
        cost = static_cast<uint8_t>(
            std::clamp<long>(scaled, 1, kMaxTraversableCost));
      }
    }
    table[static_cast<size_t>(v)] = cost;
  }
  return table;
}

}  // namespace

absl::StatusOr<RosMapMetadata> ParseRosMapYaml(std::string_view yaml_in,
                                               std::string_view source_in) {
  const absl::string_view yaml = ToAbsl(yaml_in);
  const absl::string_view source = ToAbsl(source_in);
  try {
    return ParseRosMapYamlOrThrow(yaml, source);
  } catch (const YAML::Exception& e) {
    const bool has_line = !e.mark.is_null() && e.mark.line >= 0;
    return absl::InvalidArgumentError(
        absl::StrCat(source, has_line ? absl::StrCat(":", e.mark.line + 1) : "",
                     ": invalid YAML: ", e.msg));
  } catch (const std::exception& e) {
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": invalid YAML: ", e.what()));
  }
}

absl::StatusOr<Grid> ParseRosMap(const RosMapMetadata& metadata,
                                 std::string_view pgm_in,
                                 std::string_view source_in,
                                 int64_t max_cells) {
  const absl::string_view pgm = ToAbsl(pgm_in);
  const absl::string_view source = ToAbsl(source_in);
  PATHD_RETURN_IF_ERROR(ValidateMetadata(metadata, source));
  PgmCursor cursor(pgm, source);
  if (pgm.size() < 2 || pgm[0] != 'P' || (pgm[1] != '2' && pgm[1] != '5') ||
      (pgm.size() > 2 && !IsPgmSpace(pgm[2]) && pgm[2] != '#')) {
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": not a PGM image: bad magic ",
                     Quote(pgm.substr(0, 2)), ", expected P2 or P5"));
  }
  const bool plain = pgm[1] == '2';
  cursor.set_pos(2);
  PATHD_ASSIGN_OR_RETURN(const int32_t width,
                         cursor.HeaderNumber("width", kMaxGridDimension));
  PATHD_ASSIGN_OR_RETURN(const int32_t height,
                         cursor.HeaderNumber("height", kMaxGridDimension));
  const int64_t cells = int64_t{width} * height;
  if (cells > max_cells) {
    // A size limit, not a syntax error: the caller may allow bigger maps.
    return absl::ResourceExhaustedError(cursor.Error(absl::StrCat(
        "image of ", width, " x ", height, " = ", cells,
        " pixels exceeds the limit of ", max_cells, " cells")).message());
  }
  PATHD_ASSIGN_OR_RETURN(const int32_t maxval,
                         cursor.HeaderNumber("maxval", 65535));

  const std::vector<uint8_t> cost_of = MakeCostTable(metadata, maxval);
  // Allocated only once the pixel data is known to be all there, so a short
  // header ("P5 16384 16384 255") cannot make the reader allocate far more
  // than the input it arrived in.
  std::vector<uint8_t> costs;
  // Image row r (top first) becomes grid row height-1-r: the grid is stored
  // bottom row first, like nav_msgs/OccupancyGrid.
  const auto put = [&](int64_t i, int32_t value) {
    const int64_t row = i / width;
    const int64_t col = i % width;
    costs[static_cast<size_t>((height - 1 - row) * width + col)] =
        cost_of[static_cast<size_t>(value)];
  };

  if (plain) {
    // Each value takes at least two bytes (a digit and a separator), which
    // bounds the reservation by the input.
    std::vector<uint16_t> values;
    values.reserve(static_cast<size_t>(
        std::min(cells, static_cast<int64_t>(pgm.size() / 2 + 1))));
    for (int64_t i = 0; i < cells; ++i) {
      const size_t before = cursor.pos();
      const absl::string_view token = cursor.Token();
      if (token.empty()) {
        // Report the line where the data stops, not the empty line after it.
        cursor.set_pos(before);
        return cursor.Error(absl::StrCat("truncated pixel data: expected ",
                                         cells, " values, found ", i));
      }
      int64_t value = 0;
      if (!std::all_of(token.begin(), token.end(), absl::ascii_isdigit) ||
          token.size() > 12 || !absl::SimpleAtoi(token, &value)) {
        return cursor.Error(
            absl::StrCat("pixel value ", Quote(token), " is not a number"));
      }
      if (value > maxval) {
        return cursor.Error(
            absl::StrCat("pixel value ", value, " exceeds maxval ", maxval));
      }
      values.push_back(static_cast<uint16_t>(value));
    }
    cursor.SkipSpaceAndComments();
    if (!cursor.AtEnd()) {
      // More values than width x height means the header is wrong; loading
      // anyway would shear the map.
      return cursor.Error(absl::StrCat("unexpected data after the ", cells,
                                       " pixel values of a ", width, " x ",
                                       height, " image"));
    }
    costs.resize(static_cast<size_t>(cells));
    for (int64_t i = 0; i < cells; ++i) put(i, values[static_cast<size_t>(i)]);
  } else {
    // Exactly one whitespace character separates maxval from the raster.
    // Some writers put a comment there, which ends at that newline.
    if (!cursor.AtEnd() && cursor.Peek() == '#')
      cursor.SkipSpaceAndComments();
    else if (!cursor.AtEnd())
      cursor.set_pos(cursor.pos() + 1);
    const absl::string_view raster =
        pgm.substr(std::min(cursor.pos(), pgm.size()));
    const int bytes_per_sample = maxval > 255 ? 2 : 1;
    const int64_t needed = cells * bytes_per_sample;
    if (static_cast<int64_t>(raster.size()) < needed) {
      return absl::InvalidArgumentError(
          absl::StrCat(source, ": truncated pixel data: a ", width, " x ",
                       height, " image with maxval ", maxval, " needs ", needed,
                       " bytes, found ", raster.size()));
    }
    // Bytes after the raster are ignored: netpbm allows several images in
    // one file and some writers append a newline.
    const auto* bytes = reinterpret_cast<const unsigned char*>(raster.data());
    costs.resize(static_cast<size_t>(cells));
    // Row by row, without a division per pixel: a 16384² image is 268 M
    // pixels (docs/performance.md, "Huge maps").
    for (int32_t row = 0; row < height; ++row) {
      const int64_t first = int64_t{row} * width;
      uint8_t* out = costs.data() + static_cast<size_t>(height - 1 - row) * width;
      for (int32_t col = 0; col < width; ++col) {
        const int64_t i = first + col;
        const int32_t value =
            bytes_per_sample == 1
                ? bytes[i]
                : (int32_t{bytes[2 * i]} << 8) | bytes[2 * i + 1];  // big-endian
        if (value > maxval) {
          return absl::InvalidArgumentError(
              absl::StrCat(source, ": pixel (", col, ", ", row, ") value ", value,
                           " exceeds maxval ", maxval));
        }
        out[col] = cost_of[static_cast<size_t>(value)];
      }
    }
  }

  PATHD_ASSIGN_OR_RETURN(Grid grid,
                         Grid::FromCells(width, height, std::move(costs)));
  grid.set_resolution(metadata.resolution);
  grid.set_origin(metadata.origin);
  return grid;
}

absl::StatusOr<Grid> ReadRosMapFile(const std::string& yaml_path,
                                    int64_t max_cells) {
  PATHD_ASSIGN_OR_RETURN(const std::string yaml, ReadFileToString(yaml_path));
  PATHD_ASSIGN_OR_RETURN(const RosMapMetadata metadata,
                         ParseRosMapYaml(yaml, yaml_path));
  // map_server resolves a relative image against the YAML's folder, not the
  // process's working directory.
  std::filesystem::path image(metadata.image);
  if (image.is_relative()) {
    image = std::filesystem::path(yaml_path).parent_path() / image;
  }
  const std::string image_path = image.string();
  PATHD_ASSIGN_OR_RETURN(const std::string pgm, ReadFileToString(image_path));
  return ParseRosMap(metadata, std::string_view(pgm), image_path, max_cells);
}

}  // namespace pathd
