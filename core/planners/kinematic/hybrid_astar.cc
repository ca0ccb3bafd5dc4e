// hybrid_astar: Hybrid A* over continuous poses, pruned per lattice state
// (hybrid_astar.h). docs/planners.md describes its options and guarantees,
// docs/decisions.md ("Hybrid A*") why it is built this way.
#include "core/planners/kinematic/hybrid_astar.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/kinematics/curves.h"
#include "core/kinematics/motion_check.h"
#include "core/kinematics/obstacle_heuristic.h"
#include "core/kinematics/pose_path.h"
#include "core/kinematics/smoother.h"
#include "core/kinematics/vehicle.h"
#include "core/map/cost_model.h"
#include "core/planners/planners.h"
#include "core/search/endpoints.h"
#include "core/search/grid_planner.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr char kName[] = "hybrid_astar";

// Within this many turning radii of the goal the curve heuristic is the
// exact Dubins / Reeds-Shepp length from OMPL; farther, the straight-line
// distance (a lower bound of it, and there the obstacle heuristic
// dominates anyway). OMPL's Reeds-Shepp length costs 5-10 us; docs/
// performance.md ("hybrid_astar") has the measurements behind the choice.
constexpr double kCurveHeuristicRadii = 8.0;
// Analytic expansions tried per attempt: the shortest curves to the goal
// headings the tolerance allows, shortest first.
constexpr int kAnalyticTries = 2;

// The query a request plans: its own, or the default one of a grid request,
// whose cost penalty is the request's cost weight (so cost_weight means the
// same to every planner).
std::shared_ptr<const KinematicQuery> QueryOf(const PlanRequest& request) {
  if (request.kinematic != nullptr) return request.kinematic;
  auto query =
      std::make_shared<KinematicQuery>(DefaultKinematicQuery(request.start, request.goal));
  query->cost_penalty = request.cost.cost_weight;
  return query;
}

std::string PoseString(const Pose& p) {
  return absl::StrFormat("(%g, %g, %g rad)", p.x, p.y, p.yaw);
}

bool Finite(const Pose& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.yaw);
}

// The goal headings a search may end with: the goal's, and when the
// tolerance allows others, `extra` (headings worth trying) moved into the
// tolerance.
double IntoTolerance(double yaw, const Pose& goal, double tolerance) {
  if (tolerance >= std::numbers::pi) return NormalizeAngle(yaw);
  const double off = std::clamp(NormalizeAngle(yaw - goal.yaw), -tolerance, tolerance);
  return NormalizeAngle(goal.yaw + off);
}

// INVALID_ARGUMENT naming what is wrong with the query, or OK.
absl::Status ValidateQuery(const Grid& grid, const PlanRequest& request,
                           const KinematicQuery& q) {
  if (q.footprint == nullptr) {
    return absl::InvalidArgumentError("hybrid_astar needs a footprint in the kinematic query");
  }
  if (q.motion != MotionModel::kDubins && q.motion != MotionModel::kReedsShepp) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "hybrid_astar plans dubins or reeds_shepp motion, not %s",
        std::string(MotionModelName(q.motion))));
  }
  if (!std::isfinite(q.min_turning_radius_cells) || q.min_turning_radius_cells <= 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "min_turning_radius %g cells must be finite and > 0", q.min_turning_radius_cells));
  }
  // At least 1: the curve heuristic (the length without penalties) must not
  // exceed the priced cost (Nav2 has the same bounds).
  for (const auto& [name, value, least] : {
           std::tuple<const char*, double, double>{"reverse_penalty", q.reverse_penalty, 1.0},
           {"non_straight_penalty", q.non_straight_penalty, 1.0},
           {"change_penalty", q.change_penalty, 0.0},
           {"cost_penalty", q.cost_penalty, 0.0},
           {"goal_tolerance", q.goal_tolerance_cells, 0.0},
           {"goal_tolerance_yaw", q.goal_tolerance_yaw, 0.0},
       }) {
    if (!std::isfinite(value) || value < least) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s %g must be finite and >= %g", name, value, least));
    }
  }
  if (!Finite(q.start) || !Finite(q.goal)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s pose is not finite", Finite(q.start) ? "goal" : "start"));
  }
  if (!(request.start == q.start.cell()) || !(request.goal == q.goal.cell())) {
    const bool start = !(request.start == q.start.cell());
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s cell %s is not the cell of the kinematic %s pose %s", start ? "start" : "goal",
        CellToString(start ? request.start : request.goal), start ? "start" : "goal",
        PoseString(start ? q.start : q.goal)));
  }
  const FootprintChecker& checker = *q.footprint;
  const bool unknown_is_free = request.cost.unknown_is_free;
  if (checker.Collides(grid, q.start, unknown_is_free)) {
    return WithEndpointFault(
        absl::InvalidArgumentError(absl::StrFormat(
            "start pose %s collides: the footprint (%s) overlaps an obstacle or leaves the map",
            PoseString(q.start), checker.footprint().DebugString())),
        EndpointFault::kStartBlocked);
  }
  // The goal is blocked when every heading the tolerance allows collides
  // (checked at the footprint's heading bins).
  bool goal_free = !checker.Collides(grid, q.goal, unknown_is_free);
  const double bin = 2.0 * std::numbers::pi / checker.headings();
  const double tolerance = std::min(q.goal_tolerance_yaw, std::numbers::pi);
  for (double off = bin; !goal_free && off <= tolerance + 1e-12; off += bin) {
    for (const double yaw : {q.goal.yaw + off, q.goal.yaw - off}) {
      if (!checker.Collides(grid, Pose{q.goal.x, q.goal.y, yaw}, unknown_is_free)) {
        goal_free = true;
      }
    }
  }
  if (!goal_free) {
    return WithEndpointFault(
        absl::InvalidArgumentError(absl::StrFormat(
            "goal pose %s collides: the footprint (%s) overlaps an obstacle or leaves the map%s",
            PoseString(q.goal), checker.footprint().DebugString(),
            q.goal_tolerance_yaw > 0.0 ? " at every heading within the goal tolerance" : "")),
        EndpointFault::kGoalBlocked);
  }
  return absl::OkStatus();
}

absl::Status Validate(const Grid& grid, const PlanRequest& request,
                      const PlannerTraits& traits) {
  PATHD_RETURN_IF_ERROR(ValidateRequest(grid, request, kName, traits));
  return ValidateQuery(grid, request, *QueryOf(request));
}

// One driven motion of the search: a steering and a signed length, with
// what its collision test and pricing need.
struct Primitive {
  Steer steer = Steer::kStraight;
  double length = 0.0;
  // Returned pieces (each at most MaxPieceLength long).
  int32_t pieces = 1;
  // How far any point of the footprint moves over it, and how far the
  // returned pieces' chords stray from it.
  double sweep = 0.0;
  double deviation = 0.0;
};

// The greatest distance between an arc of `radius` and angle `angle` and its
// chord.
double Sagitta(double radius, double angle) {
  return radius * (1.0 - std::cos(angle / 2.0));
}

Primitive MakeMotion(Steer steer, double length, double radius, double reach) {
  Primitive p;
  p.steer = steer;
  p.length = length;
  const double abs_length = std::fabs(length);
  const bool turns = steer != Steer::kStraight;
  const double max_piece = MaxPieceLength(turns ? radius : kInfinity);
  p.pieces = std::max(1, static_cast<int32_t>(std::ceil(abs_length / max_piece - 1e-9)));
  const double turn = turns ? abs_length / radius : 0.0;
  p.sweep = abs_length + reach * turn;
  p.deviation = turns ? Sagitta(radius, turn / p.pieces) : 0.0;
  return p;
}

// The pose at fraction t of driving `p` from `from`.
Pose DriveFraction(const Pose& from, const Primitive& p, double radius, double t) {
  return Drive(from, p.steer, radius, p.length * t);
}

class HybridSearch {
 public:
  HybridSearch(const Grid& grid, const PlanRequest& request, const KinematicQuery& q,
               const StopCondition& stop, const HybridAStarOptions& options,
               const MotionChecker& motion, const ObstacleHeuristic* obstacle)
      : grid_(grid),
        request_(request),
        q_(q),
        stop_(stop),
        options_(options),
        motion_(motion),
        obstacle_(obstacle),
        radius_(q.min_turning_radius_cells),
        reverse_(AllowsReverse(q.motion)),
        bins_(q.footprint->headings()) {
    const HybridMotions m = HybridMotionsFor(radius_, bins_);
    penalties_ = PenaltiesOf(q, m.turn_length);
    const double reach = motion.reach();
    for (const double direction : {1.0, -1.0}) {
      if (direction < 0.0 && !reverse_) break;
      primitives_.push_back(
          MakeMotion(Steer::kStraight, direction * m.straight_length, radius_, reach));
      primitives_.push_back(MakeMotion(Steer::kLeft, direction * m.turn_length, radius_, reach));
      primitives_.push_back(MakeMotion(Steer::kRight, direction * m.turn_length, radius_, reach));
    }
    // The curve heuristic towards one heading is admissible only when the
    // goal heading is (nearly) fixed.
    const double bin = 2.0 * std::numbers::pi / bins_;
    exact_curve_heuristic_ = options.curve_heuristic && q.goal_tolerance_yaw < bin / 2.0;
    curve_window_ = kCurveHeuristicRadii * radius_;
  }

  PlanResult Run();

 private:
  static constexpr uint32_t kNoNode = std::numeric_limits<uint32_t>::max();

  struct Node {
    Pose pose;
    double g = 0.0;
    uint32_t parent = kNoNode;
    int8_t primitive = -1;
    bool closed = false;
    // The kind of the last piece driven into this pose (for the change
    // penalty of the next); none at the start.
    PieceKind kind;
  };
  struct OpenEntry {
    double f;
    double g;
    uint32_t node;
    // Smallest f first; on equal f the larger g (deeper) first.
    bool operator<(const OpenEntry& other) const {
      return f != other.f ? f > other.f : g < other.g;
    }
  };
  // An analytic expansion that reached the goal: the curve and the goal pose
  // it ends on.
  struct Shot {
    Curve curve;
    Pose goal;
  };

  uint64_t Key(const Pose& p) const {
    return static_cast<uint64_t>(grid_.Index(p.cell())) * static_cast<uint64_t>(bins_) +
           static_cast<uint64_t>(q_.footprint->HeadingIndex(p.yaw));
  }
  bool Reached(const Pose& p) const {
    return std::hypot(p.x - q_.goal.x, p.y - q_.goal.y) <= q_.goal_tolerance_cells &&
           (q_.goal_tolerance_yaw >= std::numbers::pi ||
            AngleBetween(p.yaw, q_.goal.yaw) <= q_.goal_tolerance_yaw);
  }
  double ObstacleHeuristic(const Pose& p) const {
    return obstacle_ == nullptr ? 0.0 : obstacle_->At(p.cell());
  }
  double CurveHeuristic(const Pose& p) const {
    double h = std::hypot(p.x - q_.goal.x, p.y - q_.goal.y);
    if (exact_curve_heuristic_ && h < curve_window_) {
      h = ShortestCurveLength(p, q_.goal, radius_, reverse_);
    }
    return std::max(0.0, h - q_.goal_tolerance_cells);
  }
  MotionEnd FromEnd(uint32_t node) const {
    return node == 0 ? MotionEnd::kExact : MotionEnd::kProven;
  }

  // The priced cost of driving `p` from node `from`, and the kind of its last
  // piece.
  double PriceMotion(const Node& from, const Primitive& p, PieceKind& last) const;
  void Expand(uint32_t id);
  bool TryAnalytic(uint32_t id, Shot& shot) const;
  bool CurveFree(uint32_t id, const Curve& curve) const;
  PlanResult Finish(uint32_t id, const Shot* shot, int64_t expansions) const;

  const Grid& grid_;
  const PlanRequest& request_;
  const KinematicQuery& q_;
  const StopCondition& stop_;
  const HybridAStarOptions& options_;
  const MotionChecker& motion_;
  const pathd::ObstacleHeuristic* obstacle_;
  const double radius_;
  const bool reverse_;
  const int32_t bins_;
  MotionPenalties penalties_;
  std::vector<Primitive> primitives_;
  bool exact_curve_heuristic_ = false;
  double curve_window_ = 0.0;

  std::vector<Node> nodes_;
  absl::flat_hash_map<uint64_t, uint32_t> states_;
  std::priority_queue<OpenEntry> open_;
};

double HybridSearch::PriceMotion(const Node& from, const Primitive& p, PieceKind& last) const {
  double cost = 0.0;
  Pose previous = from.pose;
  const bool has_kind = from.primitive >= 0;
  PieceKind kind = from.kind;
  const bool reverse = p.length < 0.0;
  for (int32_t j = 1; j <= p.pieces; ++j) {
    const Pose next = DriveFraction(from.pose, p, radius_, static_cast<double>(j) / p.pieces);
    const PieceKind piece = KindOf(previous, next, reverse);
    const Cell c = next.cell();
    const uint8_t cell_cost = grid_.InBounds(c) ? grid_.cost(c) : kFreeCost;
    cost += PieceCost(PieceLength(previous, next), cell_cost, piece,
                      (j > 1 || has_kind) ? &kind : nullptr, penalties_);
    kind = piece;
    previous = next;
  }
  last = kind;
  return cost;
}

void HybridSearch::Expand(uint32_t id) {
  const Node from = nodes_[id];
  for (size_t k = 0; k < primitives_.size(); ++k) {
    const Primitive& p = primitives_[k];
    const Pose end = DriveFraction(from.pose, p, radius_, 1.0);
    if (!grid_.InBounds(end.cell())) continue;
    const uint64_t key = Key(end);
    const auto it = states_.find(key);
    if (it != states_.end() && nodes_[it->second].closed) continue;
    const double h_obstacle = ObstacleHeuristic(end);
    if (!(h_obstacle < kInfinity)) continue;
    PieceKind kind;
    const double g = from.g + PriceMotion(from, p, kind);
    if (it != states_.end() && g >= nodes_[it->second].g) continue;
    if (!motion_.MotionFree(
            [&](double t) { return DriveFraction(from.pose, p, radius_, t); }, p.sweep,
            p.deviation, FromEnd(id), MotionEnd::kSample)) {
      continue;
    }
    const double h = std::max(h_obstacle, CurveHeuristic(end));
    uint32_t next;
    if (it == states_.end()) {
      next = static_cast<uint32_t>(nodes_.size());
      nodes_.emplace_back();
      states_.emplace(key, next);
    } else {
      // An open state reached more cheaply: Hybrid A* keeps one continuous
      // pose per lattice state, the cheapest found (an open state has no
      // children yet, so none is orphaned).
      next = it->second;
    }
    Node& n = nodes_[next];
    n.pose = end;
    n.g = g;
    n.parent = id;
    n.primitive = static_cast<int8_t>(k);
    n.kind = kind;
    open_.push(OpenEntry{g + h, g, next});
  }
}

bool HybridSearch::CurveFree(uint32_t id, const Curve& curve) const {
  Pose at = nodes_[id].pose;
  for (int32_t i = 0; i < curve.count; ++i) {
    const CurveSegment& s = curve.segments[i];
    const Primitive p = MakeMotion(s.steer, s.length, radius_, motion_.reach());
    const MotionEnd from = i == 0 ? FromEnd(id) : MotionEnd::kProven;
    const MotionEnd to = i + 1 == curve.count ? MotionEnd::kExact : MotionEnd::kSample;
    if (!motion_.MotionFree([&](double t) { return DriveFraction(at, p, radius_, t); },
                            p.sweep, p.deviation, from, to)) {
      return false;
    }
    at = DriveFraction(at, p, radius_, 1.0);
  }
  return true;
}

bool HybridSearch::TryAnalytic(uint32_t id, Shot& shot) const {
  const Pose& from = nodes_[id].pose;
  const Pose& goal = q_.goal;
  // Goal headings worth a curve: the goal's own; with a tolerance, also the
  // heading closest to the robot's and to the bearing of the goal (driving
  // straight in, or backing straight in).
  std::vector<double> headings = {goal.yaw};
  if (q_.goal_tolerance_yaw > 0.0) {
    const double bearing = std::atan2(goal.y - from.y, goal.x - from.x);
    for (const double yaw : {from.yaw, bearing, bearing + std::numbers::pi}) {
      if (yaw != bearing + std::numbers::pi || reverse_) {
        headings.push_back(IntoTolerance(yaw, goal, q_.goal_tolerance_yaw));
      }
    }
  }
  std::vector<Shot> shots;
  for (const double yaw : headings) {
    const Pose target{goal.x, goal.y, yaw};
    bool seen = false;
    for (const Shot& s : shots) seen = seen || AngleBetween(s.goal.yaw, yaw) < 1e-9;
    if (seen) continue;
    // The validation tested the goal's own heading only.
    if (yaw != goal.yaw && !motion_.PoseFree(target)) continue;
    shots.push_back(Shot{ShortestCurve(from, target, radius_, reverse_), target});
  }
  std::sort(shots.begin(), shots.end(),
            [](const Shot& a, const Shot& b) { return a.curve.length < b.curve.length; });
  for (size_t i = 0; i < shots.size() && i < kAnalyticTries; ++i) {
    if (CurveFree(id, shots[i].curve)) {
      shot = shots[i];
      return true;
    }
  }
  return false;
}

PlanResult HybridSearch::Finish(uint32_t id, const Shot* shot, int64_t expansions) const {
  std::vector<uint32_t> chain;
  for (uint32_t at = id; at != kNoNode; at = nodes_[at].parent) chain.push_back(at);
  std::reverse(chain.begin(), chain.end());
  std::vector<PathPose> poses = {PathPose{nodes_[0].pose, false}};
  for (size_t i = 1; i < chain.size(); ++i) {
    const Node& n = nodes_[chain[i]];
    const Primitive& p = primitives_[static_cast<size_t>(n.primitive)];
    const Pose& from = nodes_[n.parent].pose;
    for (int32_t j = 1; j <= p.pieces; ++j) {
      poses.push_back(PathPose{
          DriveFraction(from, p, radius_, static_cast<double>(j) / p.pieces), p.length < 0.0});
    }
  }
  if (shot != nullptr) {
    Pose at = nodes_[id].pose;
    for (int32_t i = 0; i < shot->curve.count; ++i) {
      const CurveSegment& s = shot->curve.segments[i];
      const Primitive p = MakeMotion(s.steer, s.length, radius_, motion_.reach());
      for (int32_t j = 1; j <= p.pieces; ++j) {
        poses.push_back(PathPose{DriveFraction(at, p, radius_, static_cast<double>(j) / p.pieces),
                                 p.length < 0.0});
      }
      at = DriveFraction(at, p, radius_, 1.0);
    }
    // Driving the curve ends on the goal up to rounding; end exactly there.
    if (shot->curve.count > 0) poses.back().pose = shot->goal;
  }
  if (poses.size() > 1) poses[0].reverse = poses[1].reverse;

  if (options_.smooth && q_.smooth && poses.size() > 2) {
    SmootherOptions smoothing;
    smoothing.min_turning_radius = radius_;
    poses = SmoothPath(poses, motion_, smoothing);
  }

  PlanResult result;
  result.outcome = PlanOutcome::kFound;
  result.expansions = expansions;
  result.path = PathCells(grid_, poses, request_.cost.unknown_is_free);
  result.length = PathLength(poses);
  result.cost = PathCost(grid_, poses, penalties_);
  result.poses = std::move(poses);
  return result;
}

PlanResult HybridSearch::Run() {
  Node start;
  start.pose = q_.start;
  start.pose.yaw = NormalizeAngle(start.pose.yaw);
  nodes_.push_back(start);
  states_.emplace(Key(start.pose), 0);
  open_.push(OpenEntry{std::max(ObstacleHeuristic(start.pose), CurveHeuristic(start.pose)),
                       0.0, 0});
  int64_t expansions = 0;
  int64_t until_analytic = 0;
  while (!open_.empty()) {
    const OpenEntry top = open_.top();
    open_.pop();
    Node& n = nodes_[top.node];
    if (n.closed || top.g != n.g) continue;
    const PlanOutcome stop = stop_.Check(expansions, top.f);
    if (stop != PlanOutcome::kFound) {
      PlanResult result;
      result.outcome = stop;
      result.expansions = expansions;
      return result;
    }
    n.closed = true;
    ++expansions;
    if (request_.expansion_recorder != nullptr) {
      request_.expansion_recorder->Record(n.pose.cell());
    }
    if (Reached(n.pose)) return Finish(top.node, nullptr, expansions);
    if (options_.analytic_expansion && --until_analytic <= 0) {
      const double h = top.f - top.g;
      until_analytic = std::max<int64_t>(
          1, static_cast<int64_t>(std::floor(h / options_.analytic_expansion_ratio)));
      Shot shot;
      if (TryAnalytic(top.node, shot)) return Finish(top.node, &shot, expansions);
    }
    Expand(top.node);
  }
  PlanResult result;
  result.outcome = PlanOutcome::kNoPath;
  result.expansions = expansions;
  return result;
}

// Validated request in, result out.
absl::StatusOr<PlanResult> Run(const Grid& grid, const PlanRequest& request,
                               const StopCondition& stop, const HybridAStarOptions& options) {
  const std::shared_ptr<const KinematicQuery> q = QueryOf(request);
  const bool unknown_is_free = request.cost.unknown_is_free;
  const std::shared_ptr<const std::vector<float>> distance =
      GetObstacleDistance(request.derived, grid, unknown_is_free);
  PATHD_ASSIGN_OR_RETURN(
      const MotionChecker motion,
      MotionChecker::Create(q->footprint, grid, unknown_is_free, distance->data()));
  std::shared_ptr<const ObstacleHeuristic> obstacle;
  if (options.obstacle_heuristic) {
    DerivedStop derived_stop(stop);
    ObstacleHeuristicParams params;
    params.goal = request.goal;
    params.unknown_is_free = unknown_is_free;
    params.cost_penalty = q->cost_penalty;
    params.blocked_within = std::max(
        0.0, q->footprint->footprint().inscribed_radius() +
                 q->footprint->options().margin_cells - std::numbers::sqrt2 / 2.0);
    obstacle = GetObstacleHeuristic(request.derived, grid, params, derived_stop);
    if (obstacle == nullptr) return StoppedWhileDeriving(derived_stop);
  }
  HybridSearch search(grid, request, *q, stop, options, motion, obstacle.get());
  return search.Run();
}

class HybridAStarPlanner final : public GridPlanner {
 public:
  HybridAStarPlanner()
      : GridPlanner(kName, [] {
          PlannerTraits t;
          t.kinematic = true;
          t.optimal = false;
          // Pruning to one pose per lattice state can lose the only way
          // through a tight place (docs/planners.md).
          t.complete = false;
          t.description =
              "Hybrid A* (Dolgov et al. 2010, as Nav2 Smac Hybrid-A*): poses on a "
              "cell x heading lattice, arcs at the turning radius and straight "
              "motions, Dubins/Reeds-Shepp analytic expansions to the exact goal pose "
              "(OMPL), max of curve and obstacle heuristics; swept-footprint checked, "
              "smoothed";
          return t;
        }()) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& query) const override {
    return Run(query.grid, query.request, query.stop, HybridAStarOptions{});
  }
  absl::Status Validate(const Grid& grid, const PlanRequest& request) const override {
    return pathd::Validate(grid, request, traits());
  }
};

}  // namespace

HybridMotions HybridMotionsFor(double min_turning_radius_cells, int32_t heading_bins) {
  const double r = min_turning_radius_cells;
  const double bin = 2.0 * std::numbers::pi / heading_bins;
  // The smallest turn whose chord 2 r sin(turn / 2) reaches sqrt(2).
  const double leave = std::numbers::sqrt2 / (2.0 * r) < 1.0
                           ? 2.0 * std::asin(std::numbers::sqrt2 / (2.0 * r))
                           : std::numbers::pi / 2.0;
  const double increments = std::max(1.0, std::ceil(leave / bin - 1e-9));
  HybridMotions m;
  m.turn = increments * bin;
  m.turn_length = r * m.turn;
  m.straight_length = std::max(std::numbers::sqrt2, 2.0 * r * std::sin(m.turn / 2.0));
  return m;
}

absl::StatusOr<PlanResult> PlanHybridAStar(const Grid& grid, const PlanRequest& request,
                                           const StopCondition& stop,
                                           const HybridAStarOptions& options) {
  static const PlannerTraits* const kTraits = [] {
    auto* t = new PlannerTraits();
    t->kinematic = true;
    t->complete = false;
    return t;
  }();
  PATHD_RETURN_IF_ERROR(Validate(grid, request, *kTraits));
  const absl::Time started = absl::Now();
  absl::StatusOr<PlanResult> result = Run(grid, request, stop, options);
  if (result.ok()) result->planning_time = absl::Now() - started;
  return result;
}

std::unique_ptr<Planner> MakeHybridAStarPlanner() {
  return std::make_unique<HybridAStarPlanner>();
}

}  // namespace pathd
