#include "core/planners/kinematic/state_lattice.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <queue>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/kinematics/curves.h"
#include "core/kinematics/footprint.h"
#include "core/kinematics/lattice.h"
#include "core/kinematics/motion_check.h"
#include "core/kinematics/obstacle_heuristic.h"
#include "core/kinematics/pose.h"
#include "core/kinematics/pose_path.h"
#include "core/kinematics/smoother.h"
#include "core/kinematics/vehicle.h"
#include "core/map/cost_model.h"
#include "core/planners/planners.h"
#include "core/search/derived.h"
#include "core/search/endpoints.h"
#include "core/search/grid_planner.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// ---- Motions ----

// One motion of a path: poses between which the robot moves linearly in
// position and heading, and what the cost rules need to know about it.
struct Motion {
  std::vector<Pose> poses;
  // Distance driven, cells (0 for a turn in place).
  double length = 0.0;
  bool reverse = false;
  bool turns = false;
  bool left = false;
  bool in_place = false;
  // Turns in place: how many headings' worth (Nav2 prices one per heading).
  double rotation_steps = 0.0;
};

// The cost factor of a cell (Nav2: 1 + cost_penalty * cost / 252; unknown
// cells the query may cross count as free).
double CostFactor(const Grid& grid, const Pose& p, double cost_penalty) {
  const Cell c = p.cell();
  if (!grid.InBounds(c)) return 1.0;
  const uint8_t v = grid.cost(c);
  return 1.0 + cost_penalty * (v <= kMaxTraversableCost ? v : 0) / 252.0;
}

// How a motion is priced after `previous` (null at the start of a path).
double Multiplier(const Motion& m, const Motion* previous, const KinematicQuery& q) {
  double factor = 1.0;
  if (m.turns && !m.in_place) {
    const bool change = previous != nullptr &&
                        (previous->reverse != m.reverse ||
                         (previous->turns && !previous->in_place && previous->left != m.left));
    factor = q.non_straight_penalty + (change ? q.change_penalty : 0.0);
  }
  if (m.reverse) factor *= q.reverse_penalty;
  return factor;
}

// The motion's price, its poses moved by (dx, dy): length times the cells'
// cost factors along it (each piece between poses charged its share of the
// length at the cell it ends in), or the rotation penalty at the cell it
// turns in, times Multiplier.
double MotionCost(const Grid& grid, const Motion& m, double dx, double dy, const Motion* previous,
                  const KinematicQuery& q) {
  double raw = 0.0;
  if (m.in_place) {
    raw = kStateLatticeRotationPenalty * m.rotation_steps *
          CostFactor(grid, Pose{m.poses.front().x + dx, m.poses.front().y + dy, 0.0},
                     q.cost_penalty);
  } else {
    double chords = 0.0;
    for (size_t i = 1; i < m.poses.size(); ++i) {
      chords += std::hypot(m.poses[i].x - m.poses[i - 1].x, m.poses[i].y - m.poses[i - 1].y);
    }
    for (size_t i = 1; i < m.poses.size() && chords > 0.0; ++i) {
      const double piece =
          std::hypot(m.poses[i].x - m.poses[i - 1].x, m.poses[i].y - m.poses[i - 1].y);
      raw += m.length * piece / chords *
             CostFactor(grid, Pose{m.poses[i].x + dx, m.poses[i].y + dy, 0.0}, q.cost_penalty);
    }
  }
  return raw * Multiplier(m, previous, q);
}

double MotionCost(const Grid& grid, const Motion& m, const Motion* previous,
                  const KinematicQuery& q) {
  return MotionCost(grid, m, 0.0, 0.0, previous, q);
}

Pose Lerp(const Pose& a, const Pose& b, double f) {
  return Pose{a.x + f * (b.x - a.x), a.y + f * (b.y - a.y),
              NormalizeAngle(a.yaw + f * NormalizeAngle(b.yaw - a.yaw))};
}

// Appends the poses from the last one driving `length` cells (negative:
// backwards) with the wheels at `steer` (-1 right, 0 straight, 1 left) on a
// circle of `radius`, at most kLatticePoseSpacing / kLatticeYawSpacing
// apart. The heading changes by steer * length / radius: reversing with the
// wheels left lowers it, as OMPL's Reeds-Shepp segments do.
void Drive(int steer, double radius, double length, std::vector<Pose>* poses) {
  const Pose from = poses->back();
  const double turn = steer == 0 ? 0.0 : steer * length / radius;
  const int32_t pieces = std::max<int32_t>(
      1, static_cast<int32_t>(std::max(std::ceil(std::fabs(length) / kLatticePoseSpacing),
                                       std::ceil(std::fabs(turn) / kLatticeYawSpacing))));
  for (int32_t i = 1; i <= pieces; ++i) {
    const double s = length * i / pieces;
    Pose p;
    if (steer == 0) {
      p = Pose{from.x + s * std::cos(from.yaw), from.y + s * std::sin(from.yaw), from.yaw};
    } else {
      const double dyaw = steer * s / radius;
      // Left: the centre is `radius` to the left of the heading.
      p = Pose{from.x + steer * radius * (std::sin(from.yaw + dyaw) - std::sin(from.yaw)),
               from.y - steer * radius * (std::cos(from.yaw + dyaw) - std::cos(from.yaw)),
               NormalizeAngle(from.yaw + dyaw)};
    }
    poses->push_back(p);
  }
}

// The shortest car curve from `from` to `to` (Dubins 1957 forward only, or
// Reeds & Shepp 1990 both ways) at `radius` (core/kinematics/curves.h, the
// curves hybrid_astar expands with), as one Motion per segment.
std::vector<Motion> ShortestCarCurve(const Pose& from, const Pose& to, double radius,
                                     bool reverse) {
  const Curve curve = ShortestCurve(from, to, radius, reverse);
  std::vector<Motion> out;
  Pose at = from;
  for (int32_t i = 0; i < curve.count; ++i) {
    const CurveSegment& segment = curve.segments[i];
    if (segment.length == 0.0) continue;
    Motion m;
    m.poses.push_back(at);
    Drive(static_cast<int>(segment.steer), radius, segment.length, &m.poses);
    m.length = std::fabs(segment.length);
    m.reverse = segment.length < 0.0;
    m.turns = segment.steer != Steer::kStraight;
    m.left = NormalizeAngle(m.poses.back().yaw - m.poses.front().yaw) > 0.0;
    at = m.poses.back();
    out.push_back(std::move(m));
  }
  // The end is exact, whatever the rounding on the way.
  if (!out.empty()) out.back().poses.back() = to;
  return out;
}

// Turning in place from `from` to `yaw`, in steps of at most
// kLatticeYawSpacing; `bin` is the angle of one heading (for the price).
Motion Rotation(const Pose& from, double yaw, double bin) {
  Motion m;
  m.in_place = true;
  m.turns = true;
  m.poses.push_back(from);
  const double turn = NormalizeAngle(yaw - from.yaw);
  m.left = turn > 0.0;
  const int32_t pieces =
      std::max<int32_t>(1, static_cast<int32_t>(std::ceil(std::fabs(turn) / kLatticeYawSpacing)));
  for (int32_t i = 1; i <= pieces; ++i) {
    m.poses.push_back(Pose{from.x, from.y, NormalizeAngle(from.yaw + turn * i / pieces)});
  }
  m.poses.back().yaw = NormalizeAngle(yaw);
  m.rotation_steps = std::fabs(turn) / bin;
  return m;
}

// A straight move from `from` to `to`'s position, turning linearly to
// `to`'s heading on the way (an omnidirectional base; with equal headings
// any base), forward unless it goes against the heading.
Motion Translation(const Pose& from, const Pose& to) {
  Motion m;
  m.poses.push_back(from);
  const double dx = to.x - from.x;
  const double dy = to.y - from.y;
  const double turn = NormalizeAngle(to.yaw - from.yaw);
  m.length = std::hypot(dx, dy);
  const int32_t pieces = std::max<int32_t>(
      1, static_cast<int32_t>(std::max(std::ceil(m.length / kLatticePoseSpacing),
                                       std::ceil(std::fabs(turn) / kLatticeYawSpacing))));
  for (int32_t i = 1; i <= pieces; ++i) m.poses.push_back(Lerp(from, to, static_cast<double>(i) / pieces));
  m.poses.back() = to;
  m.turns = std::fabs(turn) > 1e-12;
  m.left = turn > 0.0;
  m.reverse = dx * std::cos(from.yaw) + dy * std::sin(from.yaw) < -1e-9 * m.length;
  return m;
}

// ---- Collision checks of motions ----

// The query's checker, two grown copies, the grid and its distance field.
// One per query, used on its thread.
struct LatticeChecker {
  const Grid* grid = nullptr;
  bool unknown_is_free = false;
  const float* distance = nullptr;
  std::shared_ptr<const FootprintChecker> exact;
  std::shared_ptr<const FootprintChecker> coarse;
  // How far the grown footprint reaches from the reference point: the lever
  // arm of a heading change.
  double reach = 0.0;

  bool Free(const FootprintChecker& checker, const Pose& p) const {
    return !checker.Collides(*grid, p, unknown_is_free, distance);
  }
  // The footprint grown by a quarter of the margin, made on first use: only
  // exact start and goal poses near obstacles need it, and building masks
  // costs milliseconds.
  const FootprintChecker* Fine() const {
    if (fine_ == nullptr) {
      FootprintCheckerOptions options = exact->options();
      options.margin_cells += kStateLatticeMargin / 4.0;
      absl::StatusOr<std::shared_ptr<const FootprintChecker>> made =
          SharedFootprintChecker(exact->footprint(), options);
      // The options are the query's valid ones with a larger margin.
      fine_ = made.ok() ? *made : coarse;
    }
    return fine_.get();
  }

 private:
  mutable std::shared_ptr<const FootprintChecker> fine_;
};

double SweepBetween(const Pose& a, const Pose& b, double reach) {
  return std::hypot(b.x - a.x, b.y - a.y) + reach * std::fabs(NormalizeAngle(b.yaw - a.yaw));
}

// Sample positions along a motion: the pose where the footprint has moved
// `sweep` (cumulative) from the first pose.
class SweepWalk {
 public:
  SweepWalk(const std::vector<Pose>& poses, double reach) : poses_(poses) {
    cumulative_.push_back(0.0);
    for (size_t i = 1; i < poses.size(); ++i) {
      cumulative_.push_back(cumulative_.back() + SweepBetween(poses[i - 1], poses[i], reach));
    }
  }
  double total() const { return cumulative_.back(); }
  Pose At(double sweep) const {
    if (sweep <= 0.0) return poses_.front();
    if (sweep >= total()) return poses_.back();
    const size_t i =
        std::upper_bound(cumulative_.begin(), cumulative_.end(), sweep) - cumulative_.begin();
    const double span = cumulative_[i] - cumulative_[i - 1];
    return Lerp(poses_[i - 1], poses_[i], span > 0.0 ? (sweep - cumulative_[i - 1]) / span : 0.0);
  }

 private:
  const std::vector<Pose>& poses_;
  std::vector<double> cumulative_;
};

// The samples of a motion, first pose excluded, last included: n equal
// steps of the sweep with n the fewest that keeps steps within twice the
// margin.
std::vector<Pose> MotionSamples(const std::vector<Pose>& poses, double reach) {
  const SweepWalk walk(poses, reach);
  const int32_t n = std::max<int32_t>(
      1, static_cast<int32_t>(std::ceil(walk.total() / (2.0 * kStateLatticeMargin))));
  std::vector<Pose> out;
  for (int32_t k = 1; k <= n; ++k) out.push_back(walk.At(walk.total() * k / n));
  return out;
}

// Whether the motion through `poses` is free. `begin_proven`: its first pose
// is a search state already free with the margin; else it is an exact pose
// (the start) the caller found free with the query's checker. `end_exact`:
// its last pose is the exact goal, found free with the query's checker;
// else it must be free with the margin (it becomes a search state). An
// exact end that is not free with the margin is covered by samples with a
// quarter of the margin at a quarter-margin step, reaching the pose itself.
bool MotionFree(const LatticeChecker& checker, const std::vector<Pose>& poses, bool begin_proven,
                bool end_exact) {
  const SweepWalk walk(poses, checker.reach);
  const double total = walk.total();
  const double m = kStateLatticeMargin;
  const int32_t n = std::max<int32_t>(1, static_cast<int32_t>(std::ceil(total / (2.0 * m))));
  const double half_step = total / (2.0 * n);
  for (int32_t k = 0; k <= n; ++k) {
    if (k == 0 && begin_proven) continue;
    const double at = total * k / n;
    if (checker.Free(*checker.coarse, walk.At(at))) continue;
    const bool exact = (k == 0) || (k == n && end_exact);
    if (!exact) return false;
    // Cover [0, half_step] (or its mirror at the end) with fine samples:
    // the one at m/4 + j m/2 covers [j m/2, (j + 1) m/2].
    const int32_t fine =
        std::max<int32_t>(1, static_cast<int32_t>(std::ceil(half_step / (m / 2.0))));
    for (int32_t j = 0; j < fine; ++j) {
      const double offset = std::min(m / 4.0 + j * m / 2.0, total);
      if (!checker.Free(*checker.Fine(), walk.At(k == 0 ? offset : total - offset))) return false;
    }
  }
  return true;
}

// ---- Validation ----

absl::Status ValidateQuery(const PlanRequest& request, const KinematicQuery& q) {
  if (q.footprint == nullptr) {
    return absl::InvalidArgumentError("kinematic query has no footprint");
  }
  for (const auto& [what, pose] : {std::pair<const char*, const Pose*>{"start", &q.start},
                                   {"goal", &q.goal}}) {
    if (!std::isfinite(pose->x) || !std::isfinite(pose->y) || !std::isfinite(pose->yaw)) {
      return absl::InvalidArgumentError(absl::StrFormat("%s pose is not finite", what));
    }
  }
  if (!(q.start.cell() == request.start) || !(q.goal.cell() == request.goal)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "kinematic start (%g, %g) and goal (%g, %g) must lie in the request's start cell "
        "(%d, %d) and goal cell (%d, %d)",
        q.start.x, q.start.y, q.goal.x, q.goal.y, request.start.x, request.start.y,
        request.goal.x, request.goal.y));
  }
  if (!std::isfinite(q.min_turning_radius_cells) || q.min_turning_radius_cells < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "min_turning_radius %g cells must be finite and >= 0", q.min_turning_radius_cells));
  }
  for (const auto& [name, value, least] :
       {std::tuple<const char*, double, double>{"reverse_penalty", q.reverse_penalty, 1.0},
        {"non_straight_penalty", q.non_straight_penalty, 1.0},
        {"change_penalty", q.change_penalty, 0.0},
        {"cost_penalty", q.cost_penalty, 0.0},
        {"goal_tolerance", q.goal_tolerance_cells, 0.0},
        {"goal_yaw_tolerance", q.goal_tolerance_yaw, 0.0}}) {
    if (!std::isfinite(value) || value < least) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s %g must be finite and >= %g", name, value, least));
    }
  }
  return absl::OkStatus();
}

// Whether a primitive moves other than along its heading (an
// omnidirectional move): some piece between poses goes in a direction
// (forwards or backwards) outside the headings at its two ends, as a chord
// of an arc never does.
bool Sideways(const LatticePrimitive& p) {
  if (p.turn_in_place) return false;
  for (size_t i = 1; i < p.poses.size(); ++i) {
    const double dx = p.poses[i].x - p.poses[i - 1].x;
    const double dy = p.poses[i].y - p.poses[i - 1].y;
    if (std::hypot(dx, dy) < 1e-9) continue;
    const double turn = NormalizeAngle(p.poses[i].yaw - p.poses[i - 1].yaw);
    const double mean = p.poses[i - 1].yaw + turn / 2.0;
    const double direction = std::atan2(dy, dx);
    const double off =
        std::min(AngleBetween(direction, mean), AngleBetween(direction, mean + kPi));
    if (off > std::fabs(turn) / 2.0 + 1e-3) return true;
  }
  return false;
}

// Whether the motion model lets the robot drive primitive p.
bool Allowed(const LatticePrimitive& p, MotionModel model, bool sideways) {
  switch (model) {
    case MotionModel::kDubins:
      return !p.reverse && !p.turn_in_place && !sideways;
    case MotionModel::kReedsShepp:
      return !p.turn_in_place && !sideways;
    case MotionModel::kDifferential:
      return !sideways;
    case MotionModel::kOmnidirectional:
      return true;
  }
  return false;
}

// The tightest turn of a primitive, cells: its pieces' length over their
// heading change (the arc through both ends), +infinity when straight.
double TightestTurn(const LatticePrimitive& p) {
  double r = kInfinity;
  for (size_t i = 1; i < p.poses.size(); ++i) {
    const double turn = std::fabs(NormalizeAngle(p.poses[i].yaw - p.poses[i - 1].yaw));
    if (turn < 1e-12) continue;
    const double chord = std::hypot(p.poses[i].x - p.poses[i - 1].x, p.poses[i].y - p.poses[i - 1].y);
    r = std::min(r, chord / (2.0 * std::sin(turn / 2.0)));
  }
  return r;
}

// ---- The search ----

struct Primitive {
  const LatticePrimitive* p = nullptr;
  Motion motion;
  // Check samples relative to the start lattice point.
  struct Sample {
    Pose pose;
    // The coarse checker's heading bin.
    int32_t bin;
    // The centre of the footprint's bounding disc at this pose.
    double cx;
    double cy;
  };
  std::vector<Sample> samples;
  // Each piece's share of the length, in the order of the poses after the
  // first (MotionCost's weights, precomputed).
  std::vector<double> pieces;
  // How far the primitive's poses get from its start, cells.
  double extent = 0.0;
};

struct Node {
  int32_t ix = 0;
  int32_t iy = 0;
  int32_t heading = 0;
  int32_t parent = -1;
  // Index into the primitives, or -1 for a root.
  int32_t primitive = -1;
  int32_t root = -1;
  double g = 0.0;
  bool closed = false;
};

struct Root {
  int32_t heading = 0;
  // The connecting motions from the exact start (empty: the start is the
  // root).
  std::vector<Motion> connection;
  double cost = 0.0;
  // The root pose is the exact start and did not pass the margin check.
  bool exact = false;
};

uint64_t Key(int32_t ix, int32_t iy, int32_t heading) {
  constexpr int64_t kBias = int64_t{1} << 23;
  return (static_cast<uint64_t>(ix + kBias) << 40) | (static_cast<uint64_t>(iy + kBias) << 16) |
         static_cast<uint64_t>(heading);
}

class LatticeSearch {
 public:
  LatticeSearch(const Grid& grid, const PlanRequest& request, const KinematicQuery& q,
                const ControlSet& set, const StopCondition& stop, const StateLatticeOptions& options,
                const LatticeChecker& checker, const ObstacleHeuristic* field, bool goal_free)
      : grid_(grid),
        request_(request),
        q_(q),
        set_(set),
        stop_(stop),
        options_(options),
        checker_(checker),
        field_(field),
        goal_free_(goal_free) {}

  absl::StatusOr<PlanResult> Run() {
    Prepare();
    PlanResult result;
    if (WithinGoal(q_.start, q_.start.yaw)) {
      Finish({}, {}, &result);
      return result;
    }
    for (Root& root : MakeRoots()) AddRoot(std::move(root));
    int64_t countdown = 0;
    while (!open_.empty()) {
      const Entry top = open_.top();
      open_.pop();
      Node& node = nodes_[top.node];
      if (node.closed || top.g > node.g) continue;
      const PlanOutcome outcome = stop_.Check(result.expansions, top.f);
      if (outcome != PlanOutcome::kFound) {
        result.outcome = outcome;
        return result;
      }
      node.closed = true;
      ++result.expansions;
      const Pose at = PoseOf(node);
      if (request_.expansion_recorder != nullptr) request_.expansion_recorder->Record(at.cell());
      if (WithinGoal(at, at.yaw)) {
        Finish(Chain(top.node), {}, &result);
        return result;
      }
      if (options_.analytic_expansion && goal_free_ && --countdown <= 0) {
        const double d = std::hypot(q_.goal.x - at.x, q_.goal.y - at.y);
        countdown = std::max<int64_t>(1, static_cast<int64_t>(d / options_.analytic_expansion_ratio));
        if (d <= analytic_reach_) {
          std::vector<Motion> connection = Connect(top.node, at);
          if (!connection.empty()) {
            Finish(Chain(top.node), std::move(connection), &result);
            return result;
          }
        }
      }
      Expand(top.node);
    }
    result.outcome = PlanOutcome::kNoPath;
    return result;
  }

 private:
  struct Entry {
    double f;
    double g;
    uint32_t node;
    // Smaller f first; on ties, larger g (deeper) first.
    bool operator<(const Entry& o) const { return f != o.f ? f > o.f : g < o.g; }
  };

  void Prepare() {
    // The footprint's bounding disc: about its vertices' bounding box's
    // centre (for a polygon), through the farthest vertex.
    const Footprint& footprint = checker_.coarse->footprint();
    disc_ = CellPoint{0.0, 0.0};
    double disc_radius = footprint.circle_radius();
    if (!footprint.is_circle()) {
      double x0 = kInfinity, y0 = kInfinity, x1 = -kInfinity, y1 = -kInfinity;
      for (const CellPoint& v : footprint.vertices()) {
        x0 = std::min(x0, v.x);
        y0 = std::min(y0, v.y);
        x1 = std::max(x1, v.x);
        y1 = std::max(y1, v.y);
      }
      disc_ = CellPoint{(x0 + x1) / 2.0, (y0 + y1) / 2.0};
      for (const CellPoint& v : footprint.vertices()) {
        disc_radius = std::max(disc_radius, std::hypot(v.x - disc_.x, v.y - disc_.y));
      }
    }
    disc_clear_ = disc_radius + checker_.coarse->options().margin_cells + kSqrt2 + 1e-6;
    bin_ = 2.0 * kPi / set_.headings();
    primitives_.clear();
    by_heading_.assign(set_.headings(), {});
    rotates_ = false;
    for (const LatticePrimitive& p : set_.primitives) {
      if (!Allowed(p, q_.motion, Sideways(p))) continue;
      Primitive prim;
      prim.p = &p;
      prim.motion.poses = p.poses;
      prim.motion.length = p.length;
      prim.motion.reverse = p.reverse;
      prim.motion.turns = p.turns();
      prim.motion.left = p.left_turn;
      prim.motion.in_place = p.turn_in_place;
      prim.motion.rotation_steps = 1.0;
      for (const Pose& q : MotionSamples(p.poses, checker_.reach)) {
        prim.samples.push_back(
            {q, checker_.coarse->HeadingIndex(q.yaw),
             q.x + std::cos(q.yaw) * disc_.x - std::sin(q.yaw) * disc_.y,
             q.y + std::sin(q.yaw) * disc_.x + std::cos(q.yaw) * disc_.y});
      }
      double chords = 0.0;
      for (size_t i = 1; i < p.poses.size(); ++i) {
        prim.pieces.push_back(
            std::sqrt((p.poses[i].x - p.poses[i - 1].x) * (p.poses[i].x - p.poses[i - 1].x) +
                      (p.poses[i].y - p.poses[i - 1].y) * (p.poses[i].y - p.poses[i - 1].y)));
        chords += prim.pieces.back();
      }
      for (double& piece : prim.pieces) piece = chords > 0.0 ? p.length * piece / chords : 0.0;
      for (const Pose& q : p.poses) prim.extent = std::max(prim.extent, std::hypot(q.x, q.y));
      rotates_ = rotates_ || p.turn_in_place;
      by_heading_[p.start_heading].push_back(static_cast<int32_t>(primitives_.size()));
      primitives_.push_back(std::move(prim));
    }
    reverse_ = AllowsReverse(q_.motion) && set_.has_reverse();
    // Without weighted cells (or a cost penalty) a motion costs its length:
    // no cell needs reading.
    weighted_ = false;
    if (q_.cost_penalty > 0.0) {
      for (const uint8_t v : grid_.cells()) {
        if (v > kFreeCost && v <= kMaxTraversableCost) {
          weighted_ = true;
          break;
        }
      }
    }
    // Farther than this from every obstacle (cell centre to cell centre),
    // the grown footprint anywhere in the cell is free: it reaches its
    // circumscribed radius plus the margins, and a pose is at most half a
    // diagonal from its cell's centre, an obstacle's boundary half a
    // diagonal from its centre.
    clear_beyond_ = checker_.coarse->footprint().circumscribed_radius() +
                    checker_.coarse->options().margin_cells + kSqrt2 + 1e-6;
    car_radius_ = std::max(set_.turning_radius_cells(), q_.min_turning_radius_cells);
    // The curve heuristic applies to cars aiming at a heading; the table's
    // rounding (0.1 radius) and the goal tolerances come off it.
    curve_heuristic_ = options_.curve_heuristic && !rotates_ && q_.goal_tolerance_yaw < kPi &&
                       (q_.motion == MotionModel::kDubins || q_.motion == MotionModel::kReedsShepp);
    curve_reach_ = (kCurveTableRadii - 1.0) * car_radius_;
    curve_slack_ = 0.1 * car_radius_ + q_.goal_tolerance_cells +
                   car_radius_ * q_.goal_tolerance_yaw;
    analytic_reach_ = std::max(60.0, 6.0 * car_radius_);
  }

  bool WithinGoal(const Pose& p, double yaw) const {
    if (std::hypot(p.x - q_.goal.x, p.y - q_.goal.y) > q_.goal_tolerance_cells + 1e-9) return false;
    return q_.goal_tolerance_yaw >= kPi || AngleBetween(yaw, q_.goal.yaw) <= q_.goal_tolerance_yaw + 1e-9;
  }

  Pose PoseOf(const Node& n) const {
    return Pose{anchor_.x + n.ix, anchor_.y + n.iy, set_.heading_angles[n.heading]};
  }

  double Heuristic(const Pose& p) const {
    const double tol = q_.goal_tolerance_cells;
    const double dx = p.x - q_.goal.x;
    const double dy = p.y - q_.goal.y;
    double h = std::sqrt(dx * dx + dy * dy) - tol;
    if (field_ != nullptr) {
      const Cell c = p.cell();
      if (grid_.InBounds(c)) {
        const double f = field_->At(c);
        if (std::isinf(f)) return tol > 0.0 ? std::max(0.0, h) : kInfinity;
        // Cell centres to cell centres: the poses may be up to half a
        // diagonal from theirs.
        h = std::max(h, f - kSqrt2 - tol);
      }
    }
    // Near the goal, a car's shortest curve to it (Nav2's distance
    // heuristic, from hybrid A*'s shared table: within 0.1 radius of the
    // exact length) bounds what turning to its heading costs.
    if (curve_heuristic_ && dx * dx + dy * dy < curve_reach_ * curve_reach_) {
      h = std::max(h, TabledCurveLength(p, q_.goal, car_radius_, reverse_, 72) - curve_slack_);
    }
    return std::max(0.0, h) * request_.heuristic_weight;
  }

  // The roots and the anchor (see the file comment).
  std::vector<Root> MakeRoots() {
    std::vector<Root> roots;
    const Pose& s = q_.start;
    const bool start_margin_free = checker_.Free(*checker_.coarse, s);
    const int32_t on = set_.HeadingOf(s.yaw, 1e-9);
    if (on >= 0) {
      anchor_ = Pose{s.x, s.y, 0.0};
      Root root;
      root.heading = on;
      root.exact = !start_margin_free;
      roots.push_back(std::move(root));
      return roots;
    }
    // The two neighbouring headings, nearer first.
    const int32_t nearest = set_.NearestHeading(s.yaw);
    const double off = NormalizeAngle(s.yaw - set_.heading_angles[nearest]);
    const int32_t other =
        (nearest + (off > 0.0 ? 1 : set_.headings() - 1)) % set_.headings();
    anchor_ = Pose{s.x, s.y, 0.0};
    if (rotates_) {
      for (int32_t h : {nearest, other}) {
        Root root;
        root.heading = h;
        root.connection.push_back(Rotation(s, set_.heading_angles[h], bin_));
        if (!MotionFree(checker_, root.connection.back().poses, start_margin_free, false)) continue;
        root.cost = MotionCost(grid_, root.connection.back(), nullptr, q_);
        roots.push_back(std::move(root));
      }
      return roots;
    }
    for (int32_t h : {nearest, other}) {
      for (bool backwards : {false, true}) {
        if (backwards && !reverse_) continue;
        const double turn = NormalizeAngle(set_.heading_angles[h] - s.yaw);
        // Forward, steering left raises the heading; backwards, steering
        // right does.
        const int steer = (turn > 0.0) != backwards ? 1 : -1;
        Motion m;
        m.poses.push_back(s);
        const double length = car_radius_ * std::fabs(turn);
        Drive(steer, car_radius_, backwards ? -length : length, &m.poses);
        m.poses.back().yaw = NormalizeAngle(set_.heading_angles[h]);
        m.length = length;
        m.reverse = backwards;
        m.turns = true;
        m.left = turn > 0.0;
        if (!MotionFree(checker_, m.poses, start_margin_free, false)) continue;
        Root root;
        root.heading = h;
        root.cost = MotionCost(grid_, m, nullptr, q_);
        anchor_ = Pose{m.poses.back().x, m.poses.back().y, 0.0};
        root.connection.push_back(std::move(m));
        roots.push_back(std::move(root));
        return roots;
      }
    }
    return roots;
  }

  void AddRoot(Root root) {
    Node n;
    n.heading = root.heading;
    n.g = root.cost;
    n.root = static_cast<int32_t>(roots_.size());
    const double h = Heuristic(PoseOf(n));
    roots_.push_back(std::move(root));
    if (std::isinf(h)) return;
    const uint32_t id = static_cast<uint32_t>(nodes_.size());
    auto [it, inserted] = index_.emplace(Key(0, 0, n.heading), id);
    if (!inserted) {
      Node& existing = nodes_[it->second];
      if (n.g >= existing.g) return;
      existing = n;
      open_.push({n.g + h, n.g, it->second});
      return;
    }
    nodes_.push_back(n);
    open_.push({n.g + h, n.g, id});
  }

  // The motion that reached node `id` (null for a root without one).
  const Motion* IncomingMotion(const Node& n) const {
    if (n.primitive >= 0) return &primitives_[n.primitive].motion;
    const Root& root = roots_[n.root];
    return root.connection.empty() ? nullptr : &root.connection.back();
  }

  void Expand(uint32_t id) {
    const Node node = nodes_[id];
    const Pose at = PoseOf(node);
    const Motion* incoming = IncomingMotion(node);
    const bool exact_root = node.primitive < 0 && roots_[node.root].exact;
    // The state's cell's distance to the nearest obstacle, centre to centre.
    const Cell cell = at.cell();
    const double clearance = grid_.InBounds(cell) ? checker_.distance[grid_.Index(cell)] : 0.0;
    for (int32_t pi : by_heading_[node.heading]) {
      const Primitive& prim = primitives_[pi];
      const LatticePrimitive& p = *prim.p;
      const int32_t cx = node.ix + p.dx;
      const int32_t cy = node.iy + p.dy;
      const uint64_t key = Key(cx, cy, p.end_heading);
      auto found = index_.find(key);
      if (found != index_.end() && nodes_[found->second].closed) continue;
      bool free = true;
      if (exact_root) {
        std::vector<Pose> moved = prim.motion.poses;
        for (Pose& q : moved) {
          q.x += at.x;
          q.y += at.y;
        }
        free = MotionFree(checker_, moved, false, false);
      } else if (clearance <= prim.extent + clear_beyond_ + kSqrt2) {
        // Nearer an obstacle than the primitive reaches: test its samples
        // (farther, every sample's cell is beyond clear_beyond_).
        for (const Primitive::Sample& s : prim.samples) {
          if (!SampleFree(s, at)) {
            free = false;
            break;
          }
        }
      }
      if (!free) continue;
      const double g = node.g + PrimitiveCost(prim, at, incoming);
      Node child;
      child.ix = cx;
      child.iy = cy;
      child.heading = p.end_heading;
      child.parent = static_cast<int32_t>(id);
      child.primitive = pi;
      child.g = g;
      if (found != index_.end()) {
        Node& existing = nodes_[found->second];
        if (g >= existing.g) continue;
        existing = child;
        open_.push({g + Heuristic(PoseOf(child)), g, found->second});
        continue;
      }
      const double h = Heuristic(PoseOf(child));
      if (std::isinf(h)) continue;
      const uint32_t child_id = static_cast<uint32_t>(nodes_.size());
      index_.emplace(key, child_id);
      nodes_.push_back(child);
      open_.push({g + h, g, child_id});
    }
  }

  // Whether the grown footprint at sample `s` of a primitive from `at` is
  // free. Far from obstacles the distance field says so at once: when the
  // cell of the footprint's bounding disc's centre is farther than the
  // disc's radius, the margin and a cell's diagonal from every obstacle
  // cell's centre, the grown footprint touches none (what the motion check
  // needs of a sample). Nearer, the coarse checker decides, its verdict
  // remembered per (cell, heading bin, subcell): it depends on nothing else
  // (FootprintChecker::Collides picks its mask by these, the same way).
  bool SampleFree(const Primitive::Sample& s, const Pose& at) {
    const Cell centre = Pose{at.x + s.cx, at.y + s.cy, 0.0}.cell();
    if (grid_.InBounds(centre) && checker_.distance[grid_.Index(centre)] > disc_clear_) return true;
    const Pose p{at.x + s.pose.x, at.y + s.pose.y, s.pose.yaw};
    const Cell c = p.cell();
    if (!grid_.InBounds(c)) return false;
    const size_t index = grid_.Index(c);
    const int32_t bin = s.bin;
    const FootprintChecker& checker = *checker_.coarse;
    const int32_t n = checker.options().subcells;
    const auto sub = [n](double v) {
      return std::clamp(static_cast<int32_t>((v - std::floor(v)) * n), 0, n - 1);
    };
    const uint64_t mask = (static_cast<uint64_t>(bin) * n + sub(p.y)) * n + sub(p.x);
    const uint64_t key = static_cast<uint64_t>(index) *
                             (static_cast<uint64_t>(checker.headings()) * n * n) +
                         mask;
    auto [it, inserted] = verdicts_.emplace(key, false);
    if (inserted) it->second = checker_.Free(checker, p);
    return it->second;
  }

  // MotionCost of a primitive from `at`, with the precomputed weights.
  double PrimitiveCost(const Primitive& prim, const Pose& at, const Motion* incoming) const {
    const Motion& m = prim.motion;
    double raw;
    if (m.in_place) {
      raw = kStateLatticeRotationPenalty * CostFactor(grid_, at, q_.cost_penalty);
    } else if (!weighted_) {
      raw = m.length;
    } else {
      raw = 0.0;
      for (size_t i = 1; i < m.poses.size(); ++i) {
        raw += prim.pieces[i - 1] *
               CostFactor(grid_, Pose{at.x + m.poses[i].x, at.y + m.poses[i].y, 0.0},
                          q_.cost_penalty);
      }
    }
    return raw * Multiplier(m, incoming, q_);
  }

  // The analytic expansion from node `id` at `at` to the exact goal: the
  // connecting motions, or nothing when none is free.
  std::vector<Motion> Connect(uint32_t id, const Pose& at) {
    const Node& node = nodes_[id];
    const bool exact_root = node.primitive < 0 && roots_[node.root].exact;
    const bool any_yaw = q_.goal_tolerance_yaw >= kPi;
    std::vector<std::vector<Motion>> options;
    const double dx = q_.goal.x - at.x;
    const double dy = q_.goal.y - at.y;
    const double toward = std::atan2(dy, dx);
    if (rotates_ && q_.motion == MotionModel::kOmnidirectional) {
      options.push_back({Translation(at, Pose{q_.goal.x, q_.goal.y, any_yaw ? at.yaw : q_.goal.yaw})});
    } else if (rotates_) {
      // Turn to face the goal (or away from it, to back up), drive, turn to
      // the goal's heading.
      for (bool backwards : {false, true}) {
        if (backwards && !AllowsReverse(q_.motion)) continue;
        std::vector<Motion> chain;
        Pose p = at;
        if (std::hypot(dx, dy) > 1e-9) {
          const double face = NormalizeAngle(backwards ? toward + kPi : toward);
          if (AngleBetween(face, p.yaw) > 1e-12) {
            chain.push_back(Rotation(p, face, bin_));
            p.yaw = face;
          }
          chain.push_back(Translation(p, Pose{q_.goal.x, q_.goal.y, p.yaw}));
          p = chain.back().poses.back();
        }
        if (!any_yaw && AngleBetween(p.yaw, q_.goal.yaw) > 1e-12) {
          chain.push_back(Rotation(p, q_.goal.yaw, bin_));
        }
        if (!chain.empty()) options.push_back(std::move(chain));
      }
    } else {
      std::vector<double> yaws = {q_.goal.yaw};
      if (any_yaw) yaws = {toward, at.yaw, NormalizeAngle(toward + kPi)};
      for (double yaw : yaws) {
        std::vector<Motion> curve =
            ShortestCarCurve(at, Pose{q_.goal.x, q_.goal.y, yaw}, car_radius_, reverse_);
        if (!curve.empty()) options.push_back(std::move(curve));
      }
    }
    const Motion* incoming = IncomingMotion(node);
    std::vector<std::pair<double, size_t>> order;
    for (size_t i = 0; i < options.size(); ++i) {
      double cost = 0.0;
      const Motion* previous = incoming;
      for (const Motion& m : options[i]) {
        cost += MotionCost(grid_, m, previous, q_);
        previous = &m;
      }
      order.push_back({cost, i});
    }
    std::sort(order.begin(), order.end());
    for (const auto& [cost, i] : order) {
      std::vector<Pose> all;
      for (const Motion& m : options[i]) {
        all.insert(all.end(), m.poses.begin() + (all.empty() ? 0 : 1), m.poses.end());
      }
      if (all.empty()) continue;
      if (MotionFree(checker_, all, !exact_root, true)) return std::move(options[i]);
    }
    return {};
  }

  // The nodes from a root to `id`.
  std::vector<uint32_t> Chain(uint32_t id) const {
    std::vector<uint32_t> chain;
    for (int32_t n = static_cast<int32_t>(id); n >= 0; n = nodes_[n].parent) chain.push_back(n);
    std::reverse(chain.begin(), chain.end());
    return chain;
  }

  // Fills `result` with the path through `chain` (empty: the start meets
  // the goal) and then `tail`.
  void Finish(const std::vector<uint32_t>& chain, std::vector<Motion> tail, PlanResult* result) {
    std::vector<Motion> motions;
    if (!chain.empty()) {
      const Root& root = roots_[nodes_[chain.front()].root];
      motions = root.connection;
      for (size_t i = 1; i < chain.size(); ++i) {
        const Node& n = nodes_[chain[i]];
        const Pose from = PoseOf(nodes_[n.parent]);
        Motion m = primitives_[n.primitive].motion;
        for (Pose& p : m.poses) {
          p.x += from.x;
          p.y += from.y;
        }
        motions.push_back(std::move(m));
      }
    }
    for (Motion& m : tail) motions.push_back(std::move(m));
    result->outcome = PlanOutcome::kFound;
    result->poses.push_back(PathPose{q_.start, motions.empty() ? false : motions.front().reverse});
    const Motion* previous = nullptr;
    for (const Motion& m : motions) {
      for (size_t i = 1; i < m.poses.size(); ++i) {
        result->poses.push_back(PathPose{m.poses[i], m.reverse});
      }
      result->length += m.length;
      result->cost += MotionCost(grid_, m, previous, q_);
      previous = &m;
    }
    result->path = PathCells(result->poses);
  }

  const Grid& grid_;
  const PlanRequest& request_;
  const KinematicQuery& q_;
  const ControlSet& set_;
  const StopCondition& stop_;
  const StateLatticeOptions& options_;
  const LatticeChecker& checker_;
  const ObstacleHeuristic* field_;
  const bool goal_free_;

  double bin_ = 0.0;
  std::vector<Primitive> primitives_;
  std::vector<std::vector<int32_t>> by_heading_;
  bool rotates_ = false;
  bool reverse_ = false;
  bool weighted_ = false;
  double clear_beyond_ = 0.0;
  // The footprint's bounding disc (centre in the body frame) and the
  // distance beyond which it is clear with the margin.
  CellPoint disc_;
  double disc_clear_ = 0.0;
  // Collision verdicts of the coarse checker by (cell, heading bin,
  // subcell): neighbouring states' primitives sample the same masks at the
  // same cells over and over.
  absl::flat_hash_map<uint64_t, bool> verdicts_;
  double car_radius_ = 0.0;
  bool curve_heuristic_ = false;
  double curve_reach_ = 0.0;
  double curve_slack_ = 0.0;
  double analytic_reach_ = 0.0;
  Pose anchor_;
  std::vector<Root> roots_;
  std::vector<Node> nodes_;
  absl::flat_hash_map<uint64_t, uint32_t> index_;
  std::priority_queue<Entry> open_;
};

class StateLatticePlanner final : public GridPlanner {
 public:
  StateLatticePlanner()
      : GridPlanner("state_lattice", [] {
          PlannerTraits t;
          t.kinematic = true;
          // Complete on its lattice only: a grid path may be too tight to
          // drive with the control set's primitives.
          t.complete = false;
          t.description =
              "state lattice (Pivtoraiko & Kelly 2005; Nav2 Smac State Lattice): A* over "
              "(lattice point, heading) with a minimal control set of motion primitives for "
              "the robot's motion model, footprint collision checks, Nav2 Smac penalties, "
              "the heuristic weighted by heuristic_weight, and an analytic expansion to the "
              "exact goal pose";
          return t;
        }()) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    return PlanStateLattice(q.grid, q.request, q.stop);
  }
};

}  // namespace

absl::StatusOr<PlanResult> PlanStateLattice(const Grid& grid, const PlanRequest& request,
                                            const StopCondition& stop,
                                            const StateLatticeOptions& options) {
  PATHD_RETURN_IF_ERROR(ValidateEndpoints(grid, request));
  const absl::Time started = absl::Now();
  std::shared_ptr<const KinematicQuery> query = request.kinematic;
  if (query == nullptr) {
    // A grid request: the default robot, its cost penalty the request's
    // cost weight (so cost_weight means the same to every planner, as for
    // hybrid_astar).
    auto defaults =
        std::make_shared<KinematicQuery>(DefaultKinematicQuery(request.start, request.goal));
    defaults->cost_penalty = request.cost.cost_weight;
    query = std::move(defaults);
  }
  const KinematicQuery& q = *query;
  PATHD_RETURN_IF_ERROR(ValidateQuery(request, q));
  PATHD_ASSIGN_OR_RETURN(const std::shared_ptr<const ControlSet> set, ControlSetForQuery(q));
  if (q.motion == MotionModel::kDubins || q.motion == MotionModel::kReedsShepp) {
    if (!(q.min_turning_radius_cells > 0.0)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "min_turning_radius must be > 0 for a %s robot", MotionModelName(q.motion)));
    }
    for (const LatticePrimitive& p : set->primitives) {
      if (!Allowed(p, q.motion, Sideways(p))) continue;
      const double r = TightestTurn(p);
      if (r < q.min_turning_radius_cells * (1.0 - 1e-6)) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "control set %s turns at a radius of %.4g cells (primitive from heading %d to (%d, "
            "%d) heading %d), tighter than the query's min_turning_radius of %.4g cells",
            set->name, r, p.start_heading, p.dx, p.dy, p.end_heading, q.min_turning_radius_cells));
      }
    }
  }
  const bool unknown_is_free = request.cost.unknown_is_free;
  const std::shared_ptr<const std::vector<float>> distance =
      GetObstacleDistance(request.derived, grid, unknown_is_free);
  LatticeChecker checker;
  checker.grid = &grid;
  checker.unknown_is_free = unknown_is_free;
  checker.distance = distance->data();
  checker.exact = q.footprint;
  FootprintCheckerOptions grown = q.footprint->options();
  grown.margin_cells = q.footprint->options().margin_cells + kStateLatticeMargin;
  PATHD_ASSIGN_OR_RETURN(checker.coarse, SharedFootprintChecker(q.footprint->footprint(), grown));
  checker.reach = q.footprint->footprint().circumscribed_radius() +
                  q.footprint->options().margin_cells + kStateLatticeMargin;
  if (!checker.Free(*checker.exact, q.start)) {
    return WithEndpointFault(
        absl::InvalidArgumentError(absl::StrFormat(
            "start pose (%g, %g, %g) collides: the robot's footprint overlaps an obstacle or "
            "leaves the map",
            q.start.x, q.start.y, q.start.yaw)),
        EndpointFault::kStartBlocked);
  }
  const bool goal_free = checker.Free(*checker.exact, q.goal);
  if (!goal_free && q.goal_tolerance_cells == 0.0) {
    return WithEndpointFault(
        absl::InvalidArgumentError(absl::StrFormat(
            "goal pose (%g, %g, %g) collides: the robot's footprint overlaps an obstacle or "
            "leaves the map",
            q.goal.x, q.goal.y, q.goal.yaw)),
        EndpointFault::kGoalBlocked);
  }
  std::shared_ptr<const ObstacleHeuristic> field;
  if (options.obstacle_heuristic && Traversable(grid.cost(request.goal), unknown_is_free)) {
    DerivedStop derived_stop(stop);
    ObstacleHeuristicParams params;
    params.goal = request.goal;
    params.unknown_is_free = unknown_is_free;
    params.cost_penalty = q.cost_penalty;
    // No free pose lies in a cell whose centre is nearer an obstacle's than
    // the footprint's inscribed radius less half a cell's diagonal.
    params.blocked_within = q.footprint->footprint().inscribed_radius() - kSqrt2 / 2.0;
    field = GetObstacleHeuristic(request.derived, grid, params, derived_stop);
    if (field == nullptr) return StoppedWhileDeriving(derived_stop);
  }
  LatticeSearch search(grid, request, q, *set, stop, options, checker, field.get(), goal_free);
  absl::StatusOr<PlanResult> result = search.Run();
  if (!result.ok()) return result;
  // Smoothing (KinematicQuery::smooth): cars only. A differential or
  // omnidirectional robot's path turns in place or slides, which the
  // smoother's recomputed headings would undo. Cost stays the lattice's
  // price of the path found; poses, cells and length are the smoothed ones.
  const bool car = q.motion == MotionModel::kDubins || q.motion == MotionModel::kReedsShepp;
  if (car && q.smooth && options.smooth && result->found() && result->poses.size() > 2) {
    PATHD_ASSIGN_OR_RETURN(const MotionChecker motion,
                           MotionChecker::Create(q.footprint, grid, unknown_is_free,
                                                 distance->data()));
    SmootherOptions smoothing;
    smoothing.min_turning_radius = q.min_turning_radius_cells;
    result->poses = SmoothPath(result->poses, motion, smoothing);
    result->path = PathCells(result->poses);
    result->length = PathLength(result->poses);
  }
  result->planning_time = absl::Now() - started;
  return result;
}

std::unique_ptr<Planner> MakeStateLatticePlanner() {
  return std::make_unique<StateLatticePlanner>();
}

}  // namespace pathd
