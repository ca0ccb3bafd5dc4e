#include "proto/path_codec.h"

#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "absl/strings/str_format.h"

namespace pathd {
namespace {

// Direction codes of MOVES as (dx, dy), counter-clockwise from +x; the
// index is the code.
constexpr std::array<std::pair<int, int>, 8> kMoves = {
    {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}}};

// The code of a step, or -1 when it is not one 8-connected move.
int MoveCode(int64_t dx, int64_t dy) {
  for (int code = 0; code < 8; ++code) {
    if (kMoves[code].first == dx && kMoves[code].second == dy) return code;
  }
  return -1;
}

uint64_t ZigZag(int64_t v) {
  return (static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63);
}

int64_t UnZigZag(uint64_t v) {
  return static_cast<int64_t>(v >> 1) ^ -static_cast<int64_t>(v & 1);
}

void PutVarint(uint64_t v, std::string* out) {
  while (v >= 0x80) {
    out->push_back(static_cast<char>((v & 0x7f) | 0x80));
    v >>= 7;
  }
  out->push_back(static_cast<char>(v));
}

absl::Status Invalid(const absl::FormatSpec<size_t>& what, size_t at) {
  return absl::InvalidArgumentError(absl::StrFormat(what, at));
}

// Reads packed bytes front to back; every read is bounds-checked.
class Reader {
 public:
  explicit Reader(std::string_view bytes) : bytes_(bytes) {}

  size_t pos() const { return pos_; }
  size_t remaining() const { return bytes_.size() - pos_; }

  absl::StatusOr<uint8_t> Byte() {
    if (pos_ >= bytes_.size()) {
      return Invalid("packed_path: truncated at byte %d", pos_);
    }
    return static_cast<uint8_t>(bytes_[pos_++]);
  }

  absl::StatusOr<uint64_t> Varint() {
    const size_t start = pos_;
    uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      if (pos_ >= bytes_.size()) {
        return Invalid("packed_path: truncated varint at byte %d", start);
      }
      const auto b = static_cast<uint8_t>(bytes_[pos_++]);
      // The tenth byte holds bit 63 only.
      if (shift == 63 && b > 1) break;
      v |= static_cast<uint64_t>(b & 0x7f) << shift;
      if ((b & 0x80) == 0) return v;
    }
    return Invalid("packed_path: varint at byte %d is longer than 64 bits",
                   start);
  }

 private:
  std::string_view bytes_;
  size_t pos_ = 0;
};

// `base + delta` as an int32 coordinate, or an error naming the cell.
absl::StatusOr<int32_t> Coordinate(int64_t base, int64_t delta, size_t cell,
                                   char axis) {
  // |base| < 2^31 and |delta| < 2^63: the sum cannot overflow unless delta
  // is beyond int32's span anyway, which is checked first.
  constexpr int64_t kSpan = int64_t{1} << 32;
  if (delta > kSpan || delta < -kSpan) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "packed_path: cell %d: %c outside the int32 range", cell, axis));
  }
  const int64_t v = base + delta;
  if (v < std::numeric_limits<int32_t>::min() ||
      v > std::numeric_limits<int32_t>::max()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "packed_path: cell %d: %c outside the int32 range", cell, axis));
  }
  return static_cast<int32_t>(v);
}

}  // namespace

std::string EncodePackedPath(int64_t count,
                             absl::FunctionRef<PackedCell(int64_t)> cell) {
  std::string out;
  if (count <= 0) return out;
  bool moves = true;
  PackedCell prev = cell(0);
  for (int64_t i = 1; i < count && moves; ++i) {
    const PackedCell c = cell(i);
    moves = MoveCode(int64_t{c.x} - prev.x, int64_t{c.y} - prev.y) >= 0;
    prev = c;
  }
  // Header at most 1 + 10 + 2 * 5 bytes; MOVES half a byte a step, DELTAS
  // usually two.
  out.reserve(21 + static_cast<size_t>(moves ? count / 2 + 1 : 2 * count));
  out.push_back(
      static_cast<char>(moves ? kPackedPathMoves : kPackedPathDeltas));
  PutVarint(static_cast<uint64_t>(count), &out);
  prev = cell(0);
  PutVarint(ZigZag(prev.x), &out);
  PutVarint(ZigZag(prev.y), &out);
  uint8_t pending = 0;
  for (int64_t i = 1; i < count; ++i) {
    const PackedCell c = cell(i);
    const int64_t dx = int64_t{c.x} - prev.x;
    const int64_t dy = int64_t{c.y} - prev.y;
    prev = c;
    if (!moves) {
      PutVarint(ZigZag(dx), &out);
      PutVarint(ZigZag(dy), &out);
    } else if (i % 2 == 1) {
      pending = static_cast<uint8_t>(MoveCode(dx, dy));
    } else {
      out.push_back(static_cast<char>(pending | (MoveCode(dx, dy) << 4)));
    }
  }
  // An odd number of moves leaves its last one in a low nibble.
  if (moves && count % 2 == 0) out.push_back(static_cast<char>(pending));
  return out;
}

std::string EncodePackedPath(absl::Span<const PackedCell> cells) {
  return EncodePackedPath(static_cast<int64_t>(cells.size()),
                          [cells](int64_t i) { return cells[i]; });
}

absl::StatusOr<std::vector<PackedCell>> DecodePackedPath(
    std::string_view bytes) {
  std::vector<PackedCell> cells;
  if (bytes.empty()) return cells;
  Reader in(bytes);
  const uint8_t format = *in.Byte();
  if (format != kPackedPathMoves && format != kPackedPathDeltas) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "packed_path: unknown format byte 0x%02x (0x01 MOVES or 0x02 DELTAS)",
        format));
  }
  absl::StatusOr<uint64_t> count = in.Varint();
  if (!count.ok()) return count.status();
  if (*count == 0) {
    return absl::InvalidArgumentError(
        "packed_path: a cell count of 0 (an empty path is empty bytes)");
  }
  absl::StatusOr<uint64_t> x0 = in.Varint();
  if (!x0.ok()) return x0.status();
  absl::StatusOr<uint64_t> y0 = in.Varint();
  if (!y0.ok()) return y0.status();
  absl::StatusOr<int32_t> x = Coordinate(0, UnZigZag(*x0), 0, 'x');
  if (!x.ok()) return x.status();
  absl::StatusOr<int32_t> y = Coordinate(0, UnZigZag(*y0), 0, 'y');
  if (!y.ok()) return y.status();
  const uint64_t steps = *count - 1;
  // Check the count against the bytes before allocating for it: a MOVES
  // step takes half a byte, a DELTAS step at least two.
  const uint64_t needed =
      format == kPackedPathMoves ? steps / 2 + steps % 2 : steps;
  const uint64_t room =
      format == kPackedPathMoves ? in.remaining() : in.remaining() / 2;
  if (needed > room) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "packed_path: truncated: %d cells need more than the %d bytes after "
        "byte %d",
        *count, in.remaining(), in.pos()));
  }
  cells.reserve(static_cast<size_t>(*count));
  cells.push_back(PackedCell{*x, *y});
  uint8_t byte = 0;
  for (uint64_t i = 0; i < steps; ++i) {
    int64_t dx = 0;
    int64_t dy = 0;
    if (format == kPackedPathMoves) {
      // needed <= remaining: the byte exists.
      if (i % 2 == 0) byte = *in.Byte();
      const int code = i % 2 == 0 ? byte & 0x0f : byte >> 4;
      if (code >= 8) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "packed_path: invalid move code %d at move %d (byte %d)", code, i,
            in.pos() - 1));
      }
      dx = kMoves[code].first;
      dy = kMoves[code].second;
    } else {
      absl::StatusOr<uint64_t> zx = in.Varint();
      if (!zx.ok()) return zx.status();
      absl::StatusOr<uint64_t> zy = in.Varint();
      if (!zy.ok()) return zy.status();
      dx = UnZigZag(*zx);
      dy = UnZigZag(*zy);
    }
    absl::StatusOr<int32_t> cx = Coordinate(cells.back().x, dx, i + 1, 'x');
    if (!cx.ok()) return cx.status();
    absl::StatusOr<int32_t> cy = Coordinate(cells.back().y, dy, i + 1, 'y');
    if (!cy.ok()) return cy.status();
    cells.push_back(PackedCell{*cx, *cy});
  }
  if (format == kPackedPathMoves && steps % 2 == 1 && (byte >> 4) != 0) {
    return Invalid("packed_path: the padding nibble of byte %d is not 0",
                   in.pos() - 1);
  }
  if (in.remaining() != 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("packed_path: %d bytes after the last cell (byte %d)",
                        in.remaining(), in.pos()));
  }
  return cells;
}

namespace {

// Cell centres in the world under one frame, its cosine and sine taken once.
class FrameTransform {
 public:
  explicit FrameTransform(const v1::PathFrame& frame)
      : resolution_(frame.resolution()),
        x_(frame.origin().x()),
        y_(frame.origin().y()),
        cs_(std::cos(frame.origin().yaw())),
        sn_(std::sin(frame.origin().yaw())) {}

  // Grid::CellCenter -> Grid::CellPointToWorld, the same operations in the
  // same order (so the same doubles).
  void CellCenter(int32_t x, int32_t y, v1::WorldPoint* w) const {
    const double lx = (x + 0.5) * resolution_;
    const double ly = (y + 0.5) * resolution_;
    w->set_x(x_ + cs_ * lx - sn_ * ly);
    w->set_y(y_ + sn_ * lx + cs_ * ly);
  }

 private:
  double resolution_, x_, y_, cs_, sn_;
};

}  // namespace

v1::WorldPoint PathFrameCellCenter(const v1::PathFrame& frame, int32_t x,
                                   int32_t y) {
  v1::WorldPoint w;
  FrameTransform(frame).CellCenter(x, y, &w);
  return w;
}

absl::Status UnpackPlanPath(v1::PlanResponse* response) {
  if (response->packed_path().empty() || response->path_size() > 0) {
    return absl::OkStatus();
  }
  absl::StatusOr<std::vector<PackedCell>> cells =
      DecodePackedPath(response->packed_path());
  if (!cells.ok()) return cells.status();
  const v1::PathFrame& frame = response->path_frame();
  if (!(frame.resolution() > 0.0) || !std::isfinite(frame.resolution())) {
    return absl::InvalidArgumentError(
        "path_frame.resolution must be finite and > 0 beside packed_path");
  }
  const int n = static_cast<int>(cells->size());
  response->mutable_path()->Reserve(n);
  response->mutable_world_path()->Reserve(n);
  const FrameTransform transform(frame);
  for (const PackedCell& c : *cells) {
    v1::Cell* cell = response->add_path();
    cell->set_x(c.x);
    cell->set_y(c.y);
    transform.CellCenter(c.x, c.y, response->add_world_path());
  }
  response->clear_packed_path();
  response->clear_path_frame();
  return absl::OkStatus();
}

}  // namespace pathd
