// The packed path encoding (proto/path_codec.h): round trips of every shape
// of path the server returns (empty, one cell, 8- and 4-connected moves in
// every direction, any-angle jumps, coordinate extremes, random paths),
// the exact bytes of small paths as PlanResponse.packed_path documents
// them, and malformed bytes: a clear INVALID_ARGUMENT, never a crash.
#include "proto/path_codec.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

using ::testing::HasSubstr;
using ::testing::IsEmpty;

std::vector<PackedCell> RoundTrip(const std::vector<PackedCell>& cells) {
  const std::string bytes = EncodePackedPath(cells);
  absl::StatusOr<std::vector<PackedCell>> decoded = DecodePackedPath(bytes);
  EXPECT_TRUE(decoded.ok()) << decoded.status();
  return decoded.ok() ? *decoded : std::vector<PackedCell>{};
}

// The format byte an encoding chose.
uint8_t Format(const std::vector<PackedCell>& cells) {
  return static_cast<uint8_t>(EncodePackedPath(cells).at(0));
}

absl::Status DecodeError(const std::string& bytes) {
  return DecodePackedPath(bytes).status();
}

TEST(PathCodecTest, EmptyPathIsEmptyBytes) {
  EXPECT_THAT(EncodePackedPath(std::vector<PackedCell>{}), IsEmpty());
  EXPECT_THAT(RoundTrip({}), IsEmpty());
}

TEST(PathCodecTest, OneCell) {
  const std::vector<PackedCell> one = {{7, 3}};
  EXPECT_EQ(RoundTrip(one), one);
  // MOVES, 1 cell, zigzag 7 = 14, zigzag 3 = 6.
  EXPECT_EQ(EncodePackedPath(one), std::string("\x01\x01\x0e\x06", 4));
}

TEST(PathCodecTest, EveryDirectionAsDocumented) {
  // (1, 1) then moves with codes 0..7 in turn: two codes a byte, the
  // earlier in the low nibble.
  const std::vector<PackedCell> path = {{1, 1}, {2, 1}, {3, 2}, {3, 3}, {2, 4},
                                        {1, 4}, {0, 3}, {0, 2}, {1, 1}};
  EXPECT_EQ(EncodePackedPath(path),
            std::string("\x01\x09\x02\x02\x10\x32\x54\x76", 8));
  EXPECT_EQ(RoundTrip(path), path);
  // An odd number of moves: the last one alone in a low nibble.
  std::vector<PackedCell> odd(path.begin(), path.end() - 1);
  EXPECT_EQ(EncodePackedPath(odd),
            std::string("\x01\x08\x02\x02\x10\x32\x54\x06", 8));
  EXPECT_EQ(RoundTrip(odd), odd);
}

TEST(PathCodecTest, FourConnectedStaircase) {
  std::vector<PackedCell> path = {{10, 10}};
  for (int i = 0; i < 101; ++i) {
    const PackedCell& c = path.back();
    path.push_back(i % 2 == 0 ? PackedCell{c.x + 1, c.y}
                              : PackedCell{c.x, c.y - 1});
  }
  EXPECT_EQ(Format(path), kPackedPathMoves);
  EXPECT_EQ(RoundTrip(path), path);
  // Header 4 bytes + 101 moves in 51 bytes.
  EXPECT_EQ(EncodePackedPath(path).size(), 4u + 51u);
}

TEST(PathCodecTest, AnyAngleJumpsUseDeltas) {
  const std::vector<PackedCell> path = {{0, 0},     {200, 3},   {198, 65535},
                                        {65535, 0}, {0, 65535}, {1, 65534}};
  EXPECT_EQ(Format(path), kPackedPathDeltas);
  EXPECT_EQ(RoundTrip(path), path);
  // A repeated cell is not a move either: DELTAS keeps it.
  const std::vector<PackedCell> repeat = {{4, 4}, {4, 4}, {5, 5}};
  EXPECT_EQ(Format(repeat), kPackedPathDeltas);
  EXPECT_EQ(RoundTrip(repeat), repeat);
}

TEST(PathCodecTest, CoordinateExtremes) {
  const std::vector<PackedCell> corners = {
      {0, 0}, {65535, 65535}, {0, 65535}, {65535, 0}};
  EXPECT_EQ(RoundTrip(corners), corners);
  const std::vector<PackedCell> edge = {
      {65535, 65534}, {65535, 65535}, {65534, 65535}};
  EXPECT_EQ(Format(edge), kPackedPathMoves);
  EXPECT_EQ(RoundTrip(edge), edge);
  constexpr int32_t kMin = std::numeric_limits<int32_t>::min();
  constexpr int32_t kMax = std::numeric_limits<int32_t>::max();
  const std::vector<PackedCell> int32 = {
      {kMin, kMax}, {kMax, kMin}, {kMax - 1, kMin + 1}};
  EXPECT_EQ(RoundTrip(int32), int32);
}

TEST(PathCodecTest, RandomPaths) {
  std::mt19937 rng(19);
  for (int trial = 0; trial < 300; ++trial) {
    const bool walk = trial % 2 == 0;
    std::uniform_int_distribution<int> step(-1, 1);
    std::uniform_int_distribution<int> coord(0, 65535);
    std::uniform_int_distribution<int> length(1, 400);
    std::vector<PackedCell> path = {{coord(rng), coord(rng)}};
    const int n = length(rng);
    while (static_cast<int>(path.size()) < n) {
      PackedCell c = path.back();
      if (walk) {
        c.x += step(rng);
        c.y += step(rng);
        if (c == path.back()) continue;
      } else {
        c = {coord(rng), coord(rng)};
      }
      path.push_back(c);
    }
    EXPECT_EQ(Format(path),
              walk || n == 1 ? kPackedPathMoves : kPackedPathDeltas);
    ASSERT_EQ(RoundTrip(path), path) << "trial " << trial;
  }
}

TEST(PathCodecTest, MalformedBytesAreClearErrors) {
  const std::string good =
      EncodePackedPath(std::vector<PackedCell>{{1, 1}, {2, 1}, {3, 2}, {3, 3}});
  // Every proper prefix of a valid encoding is truncated.
  for (size_t n = 1; n < good.size(); ++n) {
    const absl::Status s = DecodeError(good.substr(0, n));
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << n;
    EXPECT_THAT(s.message(), HasSubstr("truncated")) << n;
  }
  EXPECT_THAT(DecodeError("\x07\x01\x00\x00").message(),
              HasSubstr("unknown format byte 0x07"));
  EXPECT_THAT(DecodeError(good + "x").message(),
              HasSubstr("1 bytes after the last cell"));
  EXPECT_THAT(DecodeError(std::string("\x01\x00\x00\x00", 4)).message(),
              HasSubstr("cell count of 0"));
  // Move code 9 in a low nibble; a padding nibble that is not 0.
  EXPECT_THAT(DecodeError(std::string("\x01\x02\x00\x00\x09", 5)).message(),
              HasSubstr("invalid move code 9"));
  EXPECT_THAT(DecodeError(std::string("\x01\x02\x00\x00\x30", 5)).message(),
              HasSubstr("padding nibble"));
  // A varint running past 64 bits; a coordinate beyond int32.
  EXPECT_THAT(
      DecodeError(std::string("\x01") + std::string(11, '\xff')).message(),
      HasSubstr("longer than 64 bits"));
  EXPECT_THAT(
      DecodeError(std::string("\x01\x01\x80\x80\x80\x80\x10\x00", 8)).message(),
      HasSubstr("cell 0: x outside the int32 range"));
  // int32 max, then a DELTAS step of +1.
  EXPECT_THAT(
      DecodeError(std::string("\x02\x02\xfe\xff\xff\xff\x0f\x00\x02\x00", 10))
          .message(),
      HasSubstr("cell 1: x outside the int32 range"));
  // A count far beyond the bytes: refused before anything is allocated.
  EXPECT_THAT(
      DecodeError(std::string("\x02\xff\xff\xff\xff\x0f\x00\x00\x02\x02", 10))
          .message(),
      HasSubstr("truncated"));
}

TEST(PathCodecTest, RandomBytesNeverCrash) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> length(0, 40);
  for (int trial = 0; trial < 20000; ++trial) {
    std::string bytes(length(rng), '\0');
    for (char& b : bytes) b = static_cast<char>(byte(rng));
    if (!bytes.empty()) bytes[0] = static_cast<char>(1 + trial % 2);
    const absl::StatusOr<std::vector<PackedCell>> cells =
        DecodePackedPath(bytes);
    if (!cells.ok()) {
      EXPECT_EQ(cells.status().code(), absl::StatusCode::kInvalidArgument);
    } else {
      EXPECT_EQ(RoundTrip(*cells), *cells);
    }
  }
}

TEST(PathCodecTest, UnpackPlanPathFillsTheReadableForm) {
  v1::PlanResponse response;
  const std::vector<PackedCell> cells = {{0, 0}, {1, 1}, {5, 1}};
  response.set_packed_path(EncodePackedPath(cells));
  response.mutable_path_frame()->set_resolution(0.05);
  response.mutable_path_frame()->mutable_origin()->set_x(-10.0);
  response.mutable_path_frame()->mutable_origin()->set_y(2.0);
  ASSERT_TRUE(UnpackPlanPath(&response).ok());
  ASSERT_EQ(response.path_size(), 3);
  ASSERT_EQ(response.world_path_size(), 3);
  EXPECT_EQ(response.path(2).x(), 5);
  EXPECT_EQ(response.path(2).y(), 1);
  EXPECT_DOUBLE_EQ(response.world_path(1).x(), -10.0 + 1.5 * 0.05);
  EXPECT_DOUBLE_EQ(response.world_path(1).y(), 2.0 + 1.5 * 0.05);
  EXPECT_THAT(response.packed_path(), IsEmpty());
  EXPECT_FALSE(response.has_path_frame());

  // Readable already, or nothing packed: untouched.
  v1::PlanResponse readable = response;
  ASSERT_TRUE(UnpackPlanPath(&readable).ok());
  EXPECT_EQ(readable.path_size(), 3);

  // Bad bytes or a missing frame: an error, the response as it was.
  v1::PlanResponse bad;
  bad.set_packed_path("\x01\x05");
  bad.mutable_path_frame()->set_resolution(1.0);
  EXPECT_EQ(UnpackPlanPath(&bad).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(bad.path_size(), 0);
  v1::PlanResponse no_frame;
  no_frame.set_packed_path(EncodePackedPath(cells));
  EXPECT_THAT(UnpackPlanPath(&no_frame).message(),
              HasSubstr("path_frame.resolution"));
  EXPECT_EQ(no_frame.path_size(), 0);
}

TEST(PathCodecTest, WorldPointsTurnWithTheFrame) {
  v1::PathFrame frame;
  frame.set_resolution(0.5);
  frame.mutable_origin()->set_x(1.0);
  frame.mutable_origin()->set_y(-1.0);
  frame.mutable_origin()->set_yaw(M_PI / 2);
  const v1::WorldPoint w = PathFrameCellCenter(frame, 1, 0);
  // Cell (1, 0)'s centre is (0.75, 0.25) m along the grid's axes; turned a
  // quarter: (-0.25, 0.75) from the origin.
  EXPECT_NEAR(w.x(), 1.0 - 0.25, 1e-12);
  EXPECT_NEAR(w.y(), -1.0 + 0.75, 1e-12);
}

}  // namespace
}  // namespace pathd
