// Control sets: the generator's primitives checked independently of it (end
// states on lattice points with the right headings, curvature, direction
// and collisions of their poses by the independent kinematic checker), the
// minimality rule and spanning by a search of the test's own, the file
// format's round trip and its named errors, the shipped sets against a
// regeneration, and the per-query choice and cache.
#include "core/kinematics/lattice.h"

#include <algorithm>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <queue>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "core/kinematics/lattice_generator.h"
#include "core/kinematics/vehicle.h"
#include "gtest/gtest.h"
#include "tests/testing/kinematic_checker.h"

namespace pathd {
namespace {

constexpr double kPi = std::numbers::pi;

std::string Describe(const LatticePrimitive& p) {
  return absl::StrCat("primitive from heading ", p.start_heading, " to (", p.dx, ", ", p.dy,
                      ") heading ", p.end_heading, p.reverse ? " reversing" : "",
                      p.turn_in_place ? " in place" : "");
}

ControlSet Generate(LatticeRobot robot, double radius_cells, int32_t headings = 16,
                    bool reverse = false) {
  LatticeGeneratorOptions o;
  o.robot = robot;
  o.reverse = reverse;
  o.resolution_m = 0.05;
  o.turning_radius_m = radius_cells * 0.05;
  o.headings = headings;
  absl::StatusOr<ControlSet> set = GenerateControlSet(o);
  EXPECT_TRUE(set.ok()) << set.status();
  return set.ok() ? *std::move(set) : ControlSet{};
}

// Whether a primitive moves off its heading's line (an omnidirectional move):
// the test's own rule, by the angle between each piece's chord and the
// heading halfway along it.
bool MovesSideways(const LatticePrimitive& p) {
  for (size_t i = 1; i < p.poses.size(); ++i) {
    const double dx = p.poses[i].x - p.poses[i - 1].x;
    const double dy = p.poses[i].y - p.poses[i - 1].y;
    const double chord = std::hypot(dx, dy);
    if (chord < 1e-9) continue;
    const double mid = p.poses[i - 1].yaw + NormalizeAngle(p.poses[i].yaw - p.poses[i - 1].yaw) / 2;
    const double along = std::fabs(dx * std::cos(mid) + dy * std::sin(mid)) / chord;
    if (along < 1.0 - 1e-6) return true;
  }
  return false;
}

struct SetCase {
  LatticeRobot robot;
  double radius;
  int32_t headings;
  bool reverse;
};

class GeneratedSets : public ::testing::TestWithParam<SetCase> {};

// Every primitive: first pose the origin at its start heading, last pose its
// lattice end at its end heading; the headings are the directions to the
// border of a (2m+1)-cell square; consecutive poses at most half a cell and
// 0.1 rad apart; and the independent checker finds its motion feasible:
// radius at least the turning radius, going the way its reverse flag says,
// turning in place or moving sideways only when it is such a primitive.
TEST_P(GeneratedSets, PrimitivesEndOnLatticePointsAndRespectTheTurningRadius) {
  const SetCase c = GetParam();
  const ControlSet set = Generate(c.robot, c.radius, c.headings, c.reverse);
  ASSERT_EQ(set.headings(), c.headings);
  // The headings, from their integer directions (the test's own list).
  const int32_t m = c.headings / 8;
  std::vector<double> expected;
  for (int32_t y = -m; y <= m; ++y) {
    for (int32_t x = -m; x <= m; ++x) {
      if (std::max(std::abs(x), std::abs(y)) != m) continue;
      double a = std::atan2(y, x);
      if (a < 0) a += 2 * kPi;
      expected.push_back(a);
    }
  }
  std::sort(expected.begin(), expected.end());
  ASSERT_EQ(expected.size(), set.heading_angles.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NEAR(set.heading_angles[i], expected[i], 1e-12) << i;
  }
  const Grid empty = Grid::Create(200, 200).value();
  for (const LatticePrimitive& p : set.primitives) {
    SCOPED_TRACE(Describe(p));
    ASSERT_GE(p.poses.size(), 2u);
    EXPECT_EQ(p.poses.front().x, 0.0);
    EXPECT_EQ(p.poses.front().y, 0.0);
    EXPECT_NEAR(AngleBetween(p.poses.front().yaw, set.heading_angles[p.start_heading]), 0, 1e-12);
    EXPECT_EQ(p.poses.back().x, static_cast<double>(p.dx));
    EXPECT_EQ(p.poses.back().y, static_cast<double>(p.dy));
    EXPECT_NEAR(AngleBetween(p.poses.back().yaw, set.heading_angles[p.end_heading]), 0, 1e-12);
    double travelled = 0;
    for (size_t i = 1; i < p.poses.size(); ++i) {
      const double step = std::hypot(p.poses[i].x - p.poses[i - 1].x, p.poses[i].y - p.poses[i - 1].y);
      EXPECT_LE(step, kLatticePoseSpacing + 1e-9);
      EXPECT_LE(AngleBetween(p.poses[i].yaw, p.poses[i - 1].yaw), kLatticeYawSpacing + 1e-9);
      travelled += step;
    }
    // The length is the arc length: at least the chords, at most a little
    // more (chords of arcs are within 0.05% at these spacings).
    EXPECT_GE(p.length, travelled - 1e-9);
    EXPECT_LE(p.length, travelled * 1.001 + 1e-9);
    EXPECT_EQ(p.turn_in_place, travelled == 0.0);
    const bool sideways = MovesSideways(p);
    if (c.robot != LatticeRobot::kOmnidirectional) {
      EXPECT_FALSE(sideways);
    }
    if (c.robot == LatticeRobot::kAckermann) {
      EXPECT_FALSE(p.turn_in_place);
    }
    if (c.robot == LatticeRobot::kAckermann && !c.reverse) {
      EXPECT_FALSE(p.reverse);
    }
    testing::KinematicCheck check;
    check.circle_radius = 0.1;
    check.check_ends = false;
    check.min_turning_radius = sideways || p.turn_in_place ? 0.0 : c.radius;
    check.allow_reverse = p.reverse;
    check.allow_turn_in_place = p.turn_in_place;
    check.allow_sideways = sideways;
    std::vector<Pose> poses;
    std::vector<bool> reverse;
    for (const Pose& q : p.poses) {
      poses.push_back(Pose{q.x + 100, q.y + 100, q.yaw});
      reverse.push_back(p.reverse);
    }
    EXPECT_EQ(testing::CheckKinematicPath(empty, poses, sideways ? std::vector<bool>{} : reverse,
                                          check),
              "");
  }
}

// The test's own search: the shortest chain of `edges` from (0, 0, from) to
// (x, y, to), by Dijkstra in a box of half-width `box`; +inf when none.
struct Edge {
  int32_t h0, dx, dy, h1;
  double length;
};
double Chain(const std::vector<Edge>& edges, int32_t headings, int32_t from, int32_t x, int32_t y,
             int32_t to, double limit) {
  const int32_t box = static_cast<int32_t>(std::ceil(limit)) + 1;
  const int32_t w = 2 * box + 1;
  std::vector<double> dist(static_cast<size_t>(w) * w * headings,
                           std::numeric_limits<double>::infinity());
  const auto index = [&](int32_t px, int32_t py, int32_t h) {
    return (static_cast<size_t>(py + box) * w + (px + box)) * headings + h;
  };
  using Item = std::tuple<double, int32_t, int32_t, int32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  dist[index(0, 0, from)] = 0;
  open.push({0.0, 0, 0, from});
  while (!open.empty()) {
    const auto [d, px, py, h] = open.top();
    open.pop();
    if (d > dist[index(px, py, h)]) continue;
    if (px == x && py == y && h == to) return d;
    for (const Edge& e : edges) {
      if (e.h0 != h) continue;
      const double nd = d + e.length;
      const int32_t nx = px + e.dx, ny = py + e.dy;
      if (nd > limit || std::abs(nx) > box || std::abs(ny) > box) continue;
      if (nd < dist[index(nx, ny, e.h1)]) {
        dist[index(nx, ny, e.h1)] = nd;
        open.push({nd, nx, ny, e.h1});
      }
    }
  }
  return std::numeric_limits<double>::infinity();
}

// Minimal per the rule: no moving primitive driven forwards is reached by a
// chain of the others (those of another length: a primitive's mirror images
// share its length and are kept or dropped with it) within (1 + the length
// tolerance) times its length. Spanning: from every heading, chains reach
// every heading, and every lattice point within the turning radius (with
// some heading) inside a box of six turning radii.
TEST_P(GeneratedSets, IsMinimalAndSpans) {
  const SetCase c = GetParam();
  const ControlSet set = Generate(c.robot, c.radius, c.headings, c.reverse);
  std::vector<Edge> forward;
  for (const LatticePrimitive& p : set.primitives) {
    if (p.turn_in_place || p.reverse) continue;
    forward.push_back({p.start_heading, p.dx, p.dy, p.end_heading, p.length});
  }
  ASSERT_FALSE(forward.empty());
  for (const Edge& e : forward) {
    std::vector<Edge> others;
    for (const Edge& o : forward) {
      if (std::fabs(o.length - e.length) > 1e-9) others.push_back(o);
    }
    const double limit = e.length * (1 + set.length_tolerance);
    EXPECT_GT(Chain(others, set.headings(), e.h0, e.dx, e.dy, e.h1, limit), limit)
        << "heading " << e.h0 << " to (" << e.dx << ", " << e.dy << ") heading " << e.h1
        << " is composed of the others";
  }
  // Spanning, over every primitive the robot may drive.
  std::vector<Edge> all;
  for (const LatticePrimitive& p : set.primitives) {
    all.push_back({p.start_heading, p.dx, p.dy, p.end_heading, p.turn_in_place ? 0.5 : p.length});
  }
  const int32_t box = static_cast<int32_t>(std::ceil(6 * c.radius)) + 4;
  const int32_t near = static_cast<int32_t>(std::ceil(c.radius));
  for (int32_t from = 0; from < set.headings(); from += std::max(1, set.headings() / 8)) {
    // Breadth-first over the box.
    const int32_t w = 2 * box + 1;
    std::vector<bool> seen(static_cast<size_t>(w) * w * set.headings(), false);
    const auto index = [&](int32_t x, int32_t y, int32_t h) {
      return (static_cast<size_t>(y + box) * w + (x + box)) * set.headings() + h;
    };
    std::vector<std::tuple<int32_t, int32_t, int32_t>> stack{{0, 0, from}};
    seen[index(0, 0, from)] = true;
    std::vector<bool> heading_seen(set.headings(), false);
    while (!stack.empty()) {
      const auto [x, y, h] = stack.back();
      stack.pop_back();
      heading_seen[h] = true;
      for (const Edge& e : all) {
        if (e.h0 != h) continue;
        const int32_t nx = x + e.dx, ny = y + e.dy;
        if (std::abs(nx) > box || std::abs(ny) > box || seen[index(nx, ny, e.h1)]) continue;
        seen[index(nx, ny, e.h1)] = true;
        stack.push_back({nx, ny, e.h1});
      }
    }
    for (int32_t h = 0; h < set.headings(); ++h) {
      EXPECT_TRUE(heading_seen[h]) << "heading " << h << " unreachable from " << from;
    }
    for (int32_t y = -near; y <= near; ++y) {
      for (int32_t x = -near; x <= near; ++x) {
        bool any = false;
        for (int32_t h = 0; h < set.headings() && !any; ++h) any = seen[index(x, y, h)];
        EXPECT_TRUE(any) << "(" << x << ", " << y << ") unreachable from heading " << from;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Robots, GeneratedSets,
    ::testing::Values(SetCase{LatticeRobot::kAckermann, 1.0, 16, false},
                      SetCase{LatticeRobot::kAckermann, 10.0, 16, false},
                      SetCase{LatticeRobot::kAckermann, 5.0, 16, true},
                      SetCase{LatticeRobot::kAckermann, 3.0, 8, false},
                      SetCase{LatticeRobot::kAckermann, 4.0, 24, true},
                      SetCase{LatticeRobot::kDifferential, 10.0, 16, false},
                      SetCase{LatticeRobot::kDifferential, 2.0, 16, false},
                      SetCase{LatticeRobot::kOmnidirectional, 10.0, 16, false},
                      SetCase{LatticeRobot::kOmnidirectional, 1.0, 16, false}),
    [](const auto& info) {
      return absl::StrCat(std::string(LatticeRobotName(info.param.robot)), info.param.reverse ? "_reverse" : "",
                          "_r", static_cast<int>(info.param.radius), "_h", info.param.headings);
    });

TEST(LatticeGenerator, IsDeterministicAndKeepsItsRobotsApart) {
  const ControlSet a = Generate(LatticeRobot::kAckermann, 6.0);
  const ControlSet b = Generate(LatticeRobot::kAckermann, 6.0);
  EXPECT_EQ(WriteControlSet(a), WriteControlSet(b));
  EXPECT_FALSE(a.has_reverse());
  EXPECT_FALSE(a.has_turn_in_place());
  const ControlSet diff = Generate(LatticeRobot::kDifferential, 6.0);
  EXPECT_TRUE(diff.has_reverse());
  EXPECT_TRUE(diff.has_turn_in_place());
  // Turns in place go to the neighbouring headings only.
  for (const LatticePrimitive& p : diff.primitives) {
    if (!p.turn_in_place) continue;
    const int32_t step = (p.end_heading - p.start_heading + 16) % 16;
    EXPECT_TRUE(step == 1 || step == 15) << Describe(p);
  }
  const ControlSet omni = Generate(LatticeRobot::kOmnidirectional, 6.0);
  EXPECT_TRUE(std::any_of(omni.primitives.begin(), omni.primitives.end(), MovesSideways));
  // Sideways moves both keeping and changing the heading.
  EXPECT_TRUE(std::any_of(omni.primitives.begin(), omni.primitives.end(),
                          [](const LatticePrimitive& p) { return MovesSideways(p) && !p.turns(); }));
  EXPECT_TRUE(std::any_of(omni.primitives.begin(), omni.primitives.end(),
                          [](const LatticePrimitive& p) { return MovesSideways(p) && p.turns(); }));
}

TEST(LatticeGenerator, BadOptionsNameTheOption) {
  LatticeGeneratorOptions o;
  o.headings = 12;
  EXPECT_NE(GenerateControlSet(o).status().message().find("headings"), std::string::npos);
  o = {};
  o.turning_radius_m = -1;
  EXPECT_NE(GenerateControlSet(o).status().message().find("turning radius"), std::string::npos);
  o = {};
  o.resolution_m = 0;
  EXPECT_NE(GenerateControlSet(o).status().message().find("resolution"), std::string::npos);
  o = {};
  o.turning_radius_m = 10.0;  // 200 cells at 5 cm
  EXPECT_EQ(GenerateControlSet(o).status().code(), absl::StatusCode::kInvalidArgument);
  o = {};
  o.length_tolerance = 2;
  EXPECT_NE(GenerateControlSet(o).status().message().find("tolerance"), std::string::npos);
}

void ExpectSameSet(const ControlSet& a, const ControlSet& b) {
  EXPECT_EQ(a.robot, b.robot);
  EXPECT_NEAR(a.turning_radius_cells(), b.turning_radius_cells(), 1e-9);
  ASSERT_EQ(a.heading_angles.size(), b.heading_angles.size());
  for (size_t i = 0; i < a.heading_angles.size(); ++i) {
    EXPECT_NEAR(a.heading_angles[i], b.heading_angles[i], 1e-12);
  }
  ASSERT_EQ(a.primitives.size(), b.primitives.size());
  for (size_t i = 0; i < a.primitives.size(); ++i) {
    const LatticePrimitive& p = a.primitives[i];
    const LatticePrimitive& q = b.primitives[i];
    SCOPED_TRACE(Describe(p));
    EXPECT_EQ(std::tie(p.start_heading, p.end_heading, p.dx, p.dy, p.left_turn, p.reverse,
                       p.turn_in_place),
              std::tie(q.start_heading, q.end_heading, q.dx, q.dy, q.left_turn, q.reverse,
                       q.turn_in_place));
    EXPECT_NEAR(p.length, q.length, 1e-8);
    EXPECT_NEAR(p.arc_length, q.arc_length, 1e-8);
    EXPECT_NEAR(p.radius, q.radius, 1e-8);
    ASSERT_EQ(p.poses.size(), q.poses.size());
    for (size_t k = 0; k < p.poses.size(); ++k) {
      EXPECT_NEAR(p.poses[k].x, q.poses[k].x, 1e-7);
      EXPECT_NEAR(p.poses[k].y, q.poses[k].y, 1e-7);
      EXPECT_NEAR(AngleBetween(p.poses[k].yaw, q.poses[k].yaw), 0.0, 1e-8);
    }
  }
}

TEST(ControlSetFile, RoundTrips) {
  for (const LatticeRobot robot :
       {LatticeRobot::kAckermann, LatticeRobot::kDifferential, LatticeRobot::kOmnidirectional}) {
    const ControlSet set = Generate(robot, 4.0, 16, true);
    const std::string text = WriteControlSet(set);
    absl::StatusOr<ControlSet> back = ParseControlSet(text, "round trip");
    ASSERT_TRUE(back.ok()) << back.status();
    ExpectSameSet(set, *back);
  }
}

// A control set as Nav2's generator writes it: tabs, no start pose on a
// motion, no "reverse", numbers of headings as floats in places.
constexpr char kNav2Style[] = R"({
	"version": 1.0,
	"date_generated": "2022-03-03",
	"lattice_metadata": {
		"motion_model": "ackermann",
		"turning_radius": 0.5,
		"grid_resolution": 0.05,
		"stopping_threshold": 5,
		"num_of_headings": 16,
		"heading_angles": [0.0, 0.4636476090008061, 0.7853981633974483, 1.1071487177940904,
			1.5707963267948966, 2.0344439357957027, 2.356194490192345, 2.677945044588987,
			3.141592653589793, 3.6052402625905993, 3.9269908169872414, 4.2487413713838835,
			4.71238898038469, 5.176036589385496, 5.497787143782138, 5.81953769817878],
		"number_of_trajectories": 2
	},
	"primitives": [
		{
			"trajectory_id": 0,
			"start_angle_index": 0,
			"end_angle_index": 0,
			"left_turn": true,
			"trajectory_radius": 0.0,
			"trajectory_length": 0.15,
			"arc_length": 0.0,
			"straight_length": 0.15,
			"poses": [[0.05, 0.0, 0.0], [0.1, 0.0, 0.0], [0.15, 0.0, 0.0]]
		},
		{
			"trajectory_id": 1,
			"start_angle_index": 0,
			"end_angle_index": 1,
			"left_turn": true,
			"trajectory_radius": 0.63541,
			"trajectory_length": 0.36821,
			"arc_length": 0.29461,
			"straight_length": 0.07361,
			"poses": [[0.05254, 0.00218, 0.0827841472401804], [0.10472, 0.00869, 0.1655682944803608],
				[0.15619, 0.0195, 0.2483524417205412], [0.20658, 0.03452, 0.3311365889607216],
				[0.25556, 0.05366, 0.413920736200902], [0.30295, 0.07648, 0.4636476090008061],
				[0.35, 0.1, 0.4636476090008061]]
		}
	]
})";

TEST(ControlSetFile, ReadsNav2Files) {
  absl::StatusOr<ControlSet> set = ParseControlSet(kNav2Style, "nav2.json");
  ASSERT_TRUE(set.ok()) << set.status();
  ASSERT_EQ(set->primitives.size(), 2u);
  const LatticePrimitive& straight = set->primitives[0];
  EXPECT_EQ(straight.dx, 3);
  EXPECT_EQ(straight.dy, 0);
  EXPECT_NEAR(straight.length, 3.0, 1e-9);
  // The start is put back, and the poses made half a cell apart.
  EXPECT_EQ(straight.poses.front().x, 0.0);
  EXPECT_EQ(straight.poses.size(), 7u);
  const LatticePrimitive& turn = set->primitives[1];
  EXPECT_EQ(turn.dx, 7);
  EXPECT_EQ(turn.dy, 2);
  EXPECT_EQ(turn.end_heading, 1);
  EXPECT_FALSE(turn.reverse);
  EXPECT_NEAR(turn.radius, 0.63541 / 0.05, 1e-9);
  EXPECT_NEAR(set->turning_radius_cells(), 10.0, 1e-12);
}

// Each broken file's error names the source, the line and the field.
TEST(ControlSetFile, ErrorsNameTheFileLineAndField) {
  const std::string good = WriteControlSet(Generate(LatticeRobot::kAckermann, 2.0));
  ASSERT_TRUE(ParseControlSet(good, "good.json").ok());
  struct Case {
    std::string text;
    std::vector<std::string> words;
  };
  const auto line_of = [&](const std::string& needle) {
    const size_t at = good.find(needle);
    EXPECT_NE(at, std::string::npos) << needle;
    return std::to_string(1 + std::count(good.begin(), good.begin() + at, '\n'));
  };
  std::string missing = absl::StrReplaceAll(good, {{"\"num_of_headings\"", "\"headings\""}});
  std::string bad_index = good;
  bad_index.replace(bad_index.find("\"start_angle_index\": 0"),
                    std::string("\"start_angle_index\": 0").size(), "\"start_angle_index\": 16");
  std::string off_lattice = good;
  // The first primitive's last pose, nudged off its lattice point.
  const size_t first_end = off_lattice.find("]\n      ]");
  const size_t open = off_lattice.rfind('[', first_end);
  off_lattice.replace(open, first_end - open + 1, "[0.0712, 0.0, 0.0]");
  std::string not_number = good;
  not_number.replace(not_number.find("\"grid_resolution\": 0.05"),
                     std::string("\"grid_resolution\": 0.05").size(), "\"grid_resolution\": \"x\"");
  const std::vector<Case> cases = {
      {"{\"version\": 1.0,\n  \"lattice_metadata\": [1, 2\n", {"broken.json:", "not JSON"}},
      {missing, {"broken.json:", "lattice_metadata", "num_of_headings", "missing"}},
      {bad_index,
       {"broken.json:" + line_of("\"start_angle_index\": 0"), "primitives[0].start_angle_index",
        "16"}},
      {off_lattice,
       {"broken.json:", "primitives[0].poses", "not on a lattice point"}},
      {not_number,
       {"broken.json:" + line_of("\"grid_resolution\""), "lattice_metadata.grid_resolution",
        "number"}},
      {"[1, 2, 3]", {"broken.json", "object"}},
  };
  for (const Case& c : cases) {
    const absl::Status s = ParseControlSet(c.text, "broken.json").status();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
    for (const std::string& w : c.words) {
      EXPECT_NE(s.message().find(w), std::string::npos) << "'" << w << "' not in: " << s;
    }
  }
}

// The shipped files are what the generator makes from the parameters they
// record: regenerating each gives the same set.
TEST(ShippedControlSets, AreTheGeneratorsOutput) {
  const std::vector<std::string> names = ShippedControlSetNames();
  ASSERT_GE(names.size(), 3u);
  bool robots[3] = {false, false, false};
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    absl::StatusOr<std::shared_ptr<const ControlSet>> shipped = LoadControlSet(name);
    ASSERT_TRUE(shipped.ok()) << shipped.status();
    const ControlSet& s = **shipped;
    robots[static_cast<int>(s.robot)] = true;
    LatticeGeneratorOptions o;
    o.robot = s.robot;
    o.reverse = s.has_reverse();
    o.resolution_m = s.resolution_m;
    o.turning_radius_m = s.turning_radius_m;
    o.headings = s.headings();
    o.length_tolerance = s.length_tolerance;
    o.stopping_threshold = s.stopping_threshold;
    absl::StatusOr<ControlSet> again = GenerateControlSet(o);
    ASSERT_TRUE(again.ok()) << again.status();
    absl::StatusOr<ControlSet> written = ParseControlSet(WriteControlSet(*again), name);
    ASSERT_TRUE(written.ok()) << written.status();
    ExpectSameSet(s, *written);
  }
  EXPECT_TRUE(robots[0] && robots[1] && robots[2]) << "a shipped set for every robot";
}

KinematicQuery Query(MotionModel model, double radius) {
  KinematicQuery q = DefaultKinematicQuery(Cell{0, 0}, Cell{1, 1});
  q.motion = model;
  q.min_turning_radius_cells = radius;
  return q;
}

TEST(ControlSetForQuery, PicksTheShippedSetOfTheMotionModelAndRadius) {
  const std::map<std::tuple<MotionModel, double>, std::string> expected = {
      {{MotionModel::kDubins, 10.0}, "ackermann_5cm_r50cm"},
      {{MotionModel::kReedsShepp, 10.0}, "ackermann_5cm_r50cm"},
      {{MotionModel::kReedsShepp, 5.0}, "ackermann_10cm_r50cm"},
      {{MotionModel::kDifferential, 10.0}, "diff_5cm_r50cm"},
      {{MotionModel::kOmnidirectional, 10.0}, "omni_5cm_r50cm"},
  };
  for (const auto& [key, name] : expected) {
    auto set = ControlSetForQuery(Query(std::get<0>(key), std::get<1>(key)));
    ASSERT_TRUE(set.ok()) << set.status();
    EXPECT_EQ((*set)->name, name);
  }
}

TEST(ControlSetForQuery, GeneratesOtherRadiiOnceForTheProcess) {
  auto a = ControlSetForQuery(Query(MotionModel::kReedsShepp, 3.5));
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_NE((*a)->name.find("generated"), std::string::npos) << (*a)->name;
  EXPECT_NEAR((*a)->turning_radius_cells(), 3.5, 1e-12);
  EXPECT_TRUE((*a)->has_reverse());
  auto b = ControlSetForQuery(Query(MotionModel::kReedsShepp, 3.5));
  ASSERT_TRUE(b.ok());
  EXPECT_EQ(a->get(), b->get());
  // Differential and omnidirectional robots without a radius get the
  // default arcs.
  auto diff = ControlSetForQuery(Query(MotionModel::kDifferential, 0.0));
  ASSERT_TRUE(diff.ok()) << diff.status();
  EXPECT_NEAR((*diff)->turning_radius_cells(), kDefaultArcRadiusCells, 1e-12);
  // Many threads at once get one set.
  std::vector<std::thread> threads;
  std::vector<const ControlSet*> got(4, nullptr);
  for (int i = 0; i < 4; ++i) {
    threads.emplace_back([&got, i] {
      auto s = ControlSetForQuery(Query(MotionModel::kDubins, 2.75));
      if (s.ok()) got[i] = s->get();
    });
  }
  for (std::thread& t : threads) t.join();
  ASSERT_NE(got[0], nullptr);
  auto again = ControlSetForQuery(Query(MotionModel::kDubins, 2.75));
  ASSERT_TRUE(again.ok());
  for (const ControlSet* s : got) EXPECT_NE(s, nullptr);
  EXPECT_EQ(WriteControlSet(*got[0]), WriteControlSet(**again));
}

TEST(ControlSetForQuery, BadNamesFilesAndRadiiAreInvalidArgument) {
  KinematicQuery q = Query(MotionModel::kDubins, 0.0);
  absl::Status s = ControlSetForQuery(q).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("min_turning_radius"), std::string::npos) << s;
  q = Query(MotionModel::kDubins, 500.0);
  EXPECT_EQ(ControlSetForQuery(q).status().code(), absl::StatusCode::kInvalidArgument);
  q.lattice = "no_such_set";
  s = ControlSetForQuery(q).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("ackermann_5cm_r50cm"), std::string::npos) << s;
  q.lattice = "/no/such/dir/set.json";
  s = ControlSetForQuery(q).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("/no/such/dir/set.json"), std::string::npos) << s;
}

TEST(ControlSetForQuery, LoadsFilesAndRereadsThemWhenTheyChange) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() /
      absl::StrCat("lattice_test_", ::getpid(), ".json");
  {
    std::ofstream out(path);
    out << WriteControlSet(Generate(LatticeRobot::kAckermann, 2.0));
  }
  KinematicQuery q = Query(MotionModel::kDubins, 2.0);
  q.lattice = path.string();
  auto first = ControlSetForQuery(q);
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ((*first)->name, path.string());
  EXPECT_NEAR((*first)->turning_radius_cells(), 2.0, 1e-9);
  {
    std::ofstream out(path);
    out << "{\"lattice_metadata\": {}}\n";
  }
  // A different modification time: read again, and its error names it.
  std::filesystem::last_write_time(
      path, std::filesystem::last_write_time(path) + std::chrono::seconds(5));
  const absl::Status s = ControlSetForQuery(q).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find(path.string() + ":1"), std::string::npos) << s;
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace pathd
