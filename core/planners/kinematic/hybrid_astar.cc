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

// Analytic expansions tried per attempt: the shortest curves to the goal
// headings the tolerance allows, cheapest first.
constexpr int kAnalyticTries = 2;
// Curves are asked of OMPL only between poses at most this many turning
// radii apart (analytic expansions farther are not tried; the curve
// heuristic's window is capped here). OMPL's Reeds-Shepp words assert on
// their own rounding like its Dubins words do (curves.h); no assert fired
// in 6 million random pose pairs up to 280 radii apart, but a daemon
// should not bet on the far ones. Nav2 stops at 3 m (7.5 of its default
// radii, analytic_expansion_max_length).
constexpr double kMaxCurveRadii = 64.0;

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

double Distance(const Pose& a, const Pose& b) {
  return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y));
}

std::string PoseString(const Pose& p) {
  return absl::StrFormat("(%g, %g, %g rad)", p.x, p.y, p.yaw);
}

bool Finite(const Pose& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.yaw);
}

// `yaw` moved into the goal's heading tolerance (the nearest heading the
// tolerance allows).
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

// One driven motion: a steering and a signed length, with what its
// collision test and pricing need, precomputed in the frame of the pose it
// starts from (so driving it from a state costs one sine and cosine).
struct Primitive {
  Steer steer = Steer::kStraight;
  double length = 0.0;
  // How far any point of the footprint moves over it, and how far the
  // returned pieces' chords stray from it.
  double sweep = 0.0;
  double deviation = 0.0;
  // The ends of the returned pieces (each at most MaxPieceLength long),
  // relative to the start; the last is the motion's end.
  std::vector<Pose> pieces;
  // The collision samples at t = i / (samples.size() - 1), relative.
  std::vector<Pose> samples;
  // Every piece is as long and drives the same way.
  double piece_length = 0.0;
  PieceKind kind;
};

// The greatest distance between an arc of `radius` and angle `angle` and its
// chord.
double Sagitta(double radius, double angle) {
  return radius * (1.0 - std::cos(angle / 2.0));
}

// `a` in (-pi, pi] for |a| < 3 pi (a heading plus one motion's turn).
double Wrap(double a) {
  if (a > std::numbers::pi) return a - 2.0 * std::numbers::pi;
  if (a <= -std::numbers::pi) return a + 2.0 * std::numbers::pi;
  return a;
}

// The pose `local`, given relative to `from` (whose heading has cosine c
// and sine s), in cell coordinates.
Pose Place(const Pose& from, double c, double s, const Pose& local) {
  return Pose{from.x + c * local.x - s * local.y, from.y + s * local.x + c * local.y,
              Wrap(from.yaw + local.yaw)};
}

// How many pieces a motion is returned as.
int32_t PieceCount(Steer steer, double length, double radius) {
  const double max_piece = MaxPieceLength(steer != Steer::kStraight ? radius : kInfinity);
  return std::max(1, static_cast<int32_t>(std::ceil(std::fabs(length) / max_piece - 1e-9)));
}

Primitive MakeMotion(Steer steer, double length, double radius, double reach) {
  Primitive p;
  p.steer = steer;
  p.length = length;
  const double abs_length = std::fabs(length);
  const bool turns = steer != Steer::kStraight;
  const int32_t pieces = PieceCount(steer, length, radius);
  const double turn = turns ? abs_length / radius : 0.0;
  p.sweep = abs_length + reach * turn;
  p.deviation = turns ? Sagitta(radius, turn / pieces) : 0.0;
  const Pose origin;
  for (int32_t j = 1; j <= pieces; ++j) {
    p.pieces.push_back(Drive(origin, steer, radius, length * j / pieces));
  }
  const int32_t n = MotionChecker::SampleCount(p.sweep, p.deviation);
  for (int32_t i = 0; i < n; ++i) p.samples.push_back(Drive(origin, steer, radius, length * i / n));
  // The last sample is the end exactly as the pieces reach it.
  p.samples.push_back(p.pieces.back());
  p.piece_length = PieceLength(origin, p.pieces[0]);
  p.kind = KindOf(origin, p.pieces[0], length < 0.0);
  return p;
}

// A primitive driven from one pose: the poses MotionChecker asks for, from
// the precomputed samples.
class DrivenMotion {
 public:
  DrivenMotion(const Pose& from, const Primitive& p, double radius)
      : DrivenMotion(from, std::cos(from.yaw), std::sin(from.yaw), p, radius) {}
  // `c` and `s`: the cosine and sine of from.yaw.
  DrivenMotion(const Pose& from, double c, double s, const Primitive& p, double radius)
      : from_(from), p_(p), radius_(radius), c_(c), s_(s) {}

  Pose operator()(double t) const {
    const double k = t * static_cast<double>(p_.samples.size() - 1);
    const double i = std::round(k);
    if (std::fabs(k - i) < 1e-9) return At(p_.samples[static_cast<size_t>(i)]);
    return At(Drive(Pose{}, p_.steer, radius_, p_.length * t));
  }
  // The end of piece j (1-based).
  Pose Piece(int32_t j) const { return At(p_.pieces[static_cast<size_t>(j - 1)]); }
  Pose End() const { return At(p_.pieces.back()); }

 private:
  Pose At(const Pose& local) const { return Place(from_, c_, s_, local); }

  const Pose from_;
  const Primitive& p_;
  const double radius_;
  const double c_;
  const double s_;
};

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
    curve_window_ = std::min(options.curve_heuristic_radii, kMaxCurveRadii) * radius_;
  }

  // Searches the lattice of squares 1/subdivisions cell on a side, counting
  // expansions on from `expansions`.
  PlanResult Run(int32_t subdivisions, int64_t expansions);
  // The start cannot reach the goal cell even ignoring its heading (the
  // obstacle heuristic is infinite there): no lattice will do better.
  bool unreachable() const { return unreachable_; }

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
    // The heuristic, and whether the curve part is in it yet: it is added
    // when the state first reaches the top of the open list, so states
    // never expanded never pay for a Reeds-Shepp length (5-10 us).
    double h = 0.0;
    bool curve_heuristic = false;
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

  // The lattice state of a pose on the map: its square of 1/subdivisions_
  // cell and its heading bin.
  uint64_t Key(const Pose& p) const {
    const auto square = [this](double v) {
      return static_cast<uint64_t>(std::floor(v * subdivisions_));
    };
    const uint64_t row = static_cast<uint64_t>(grid_.width()) * subdivisions_;
    return (square(p.y) * row + square(p.x)) * static_cast<uint64_t>(bins_) +
           static_cast<uint64_t>(q_.footprint->HeadingIndex(p.yaw));
  }
  bool Reached(const Pose& p) const {
    return Distance(p, q_.goal) <= q_.goal_tolerance_cells &&
           (q_.goal_tolerance_yaw >= std::numbers::pi ||
            AngleBetween(p.yaw, q_.goal.yaw) <= q_.goal_tolerance_yaw);
  }
  double ObstacleHeuristic(const Pose& p) const {
    return obstacle_ == nullptr ? 0.0 : obstacle_->At(p.cell());
  }
  double CurveHeuristic(const Pose& p) const {
    double h = Distance(p, q_.goal);
    if (exact_curve_heuristic_ && h < curve_window_) {
      h = options_.curve_table ? TabledCurveLength(p, q_.goal, radius_, reverse_, bins_)
                               : ShortestCurveLength(p, q_.goal, radius_, reverse_);
    }
    return std::max(0.0, h - q_.goal_tolerance_cells);
  }
  // What a path through `n` is expected to cost, for weighing an analytic
  // expansion: h is a length, and a curve to the goal pays the
  // non-straight penalty on its turns, so the rest is priced as if turning.
  double Expected(const Node& n) const { return n.g + penalties_.non_straight * n.h; }
  MotionEnd FromEnd(uint32_t node) const {
    return node == 0 ? MotionEnd::kExact : MotionEnd::kProven;
  }

  // The priced cost of driving `p` from node `from` (PathCost of its pieces
  // up to rounding).
  double PriceMotion(const Node& from, const DrivenMotion& drive, const Primitive& p) const;
  void Expand(uint32_t id);
  // A curve's price under the penalties, cell costs aside.
  double CurvePrice(const Curve& curve) const;
  bool TryAnalytic(uint32_t id, Shot& shot) const;
  bool CurveFree(uint32_t id, const Curve& curve) const;
  // Appends the poses of `shot` driven from node `id` to `poses`; returns
  // their price.
  double DriveShot(uint32_t id, const Shot& shot, std::vector<PathPose>& poses) const;
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

  int32_t subdivisions_ = 1;
  bool unreachable_ = false;
  std::vector<Node> nodes_;
  absl::flat_hash_map<uint64_t, uint32_t> states_;
  std::priority_queue<OpenEntry> open_;
};

double HybridSearch::PriceMotion(const Node& from, const DrivenMotion& drive,
                                 const Primitive& p) const {
  double cost = 0.0;
  const int32_t pieces = static_cast<int32_t>(p.pieces.size());
  for (int32_t j = 1; j <= pieces; ++j) {
    const Cell c = drive.Piece(j).cell();
    const uint8_t cell_cost = grid_.InBounds(c) ? grid_.cost(c) : kFreeCost;
    const bool first = j == 1;
    cost += PieceCost(p.piece_length, cell_cost, p.kind,
                      first ? (from.primitive >= 0 ? &from.kind : nullptr) : &p.kind,
                      penalties_);
  }
  return cost;
}

void HybridSearch::Expand(uint32_t id) {
  const Node from = nodes_[id];
  const double c = std::cos(from.pose.yaw);
  const double s = std::sin(from.pose.yaw);
  for (size_t k = 0; k < primitives_.size(); ++k) {
    const Primitive& p = primitives_[k];
    const DrivenMotion drive(from.pose, c, s, p, radius_);
    const Pose end = drive.End();
    if (!grid_.InBounds(end.cell())) continue;
    const uint64_t key = Key(end);
    const auto it = states_.find(key);
    if (it != states_.end() && nodes_[it->second].closed) continue;
    const double h_obstacle = ObstacleHeuristic(end);
    if (!(h_obstacle < kInfinity)) continue;
    const double g = from.g + PriceMotion(from, drive, p);
    if (it != states_.end() && g >= nodes_[it->second].g) continue;
    if (!motion_.MotionFree(drive, p.sweep, p.deviation, FromEnd(id), MotionEnd::kSample)) {
      continue;
    }
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
    n.kind = p.kind;
    n.h = h_obstacle;
    n.curve_heuristic = false;
    open_.push(OpenEntry{g + h_obstacle, g, next});
  }
}

bool HybridSearch::CurveFree(uint32_t id, const Curve& curve) const {
  // Most curves tried collide early: the segments are driven sample by
  // sample, not precomputed like the primitives.
  Pose at = nodes_[id].pose;
  for (int32_t i = 0; i < curve.count; ++i) {
    const CurveSegment& s = curve.segments[i];
    const bool turns = s.steer != Steer::kStraight;
    const double abs_length = std::fabs(s.length);
    const int32_t pieces = PieceCount(s.steer, s.length, radius_);
    const double turn = turns ? abs_length / radius_ : 0.0;
    const double deviation = turns ? Sagitta(radius_, turn / pieces) : 0.0;
    const MotionEnd from = i == 0 ? FromEnd(id) : MotionEnd::kProven;
    const MotionEnd to = i + 1 == curve.count ? MotionEnd::kExact : MotionEnd::kSample;
    if (!motion_.MotionFree(
            [&](double t) { return Drive(at, s.steer, radius_, s.length * t); },
            abs_length + motion_.reach() * turn, deviation, from, to)) {
      return false;
    }
    at = Drive(at, s.steer, radius_, s.length);
  }
  return true;
}

double HybridSearch::CurvePrice(const Curve& curve) const {
  double price = 0.0;
  for (int32_t i = 0; i < curve.count; ++i) {
    const CurveSegment& s = curve.segments[i];
    double p = std::fabs(s.length);
    if (s.steer != Steer::kStraight) p *= penalties_.non_straight;
    if (s.length < 0.0) p *= penalties_.reverse;
    price += p;
  }
  return price;
}

bool HybridSearch::TryAnalytic(uint32_t id, Shot& shot) const {
  const Pose& from = nodes_[id].pose;
  const Pose& goal = q_.goal;
  if (Distance(from, goal) > kMaxCurveRadii * radius_) return false;
  // Goal headings worth a curve: the goal's own; with a tolerance, also the
  // ones closest to the robot's heading and to the bearing of the goal
  // (driving straight in).
  std::vector<double> headings = {goal.yaw};
  if (q_.goal_tolerance_yaw > 0.0) {
    const double bearing = std::atan2(goal.y - from.y, goal.x - from.x);
    for (const double yaw : {from.yaw, bearing}) {
      headings.push_back(IntoTolerance(yaw, goal, q_.goal_tolerance_yaw));
    }
  }
  // For each, the shortest curve, and for Reeds-Shepp also the shortest
  // forward one (Dubins): the shortest Reeds-Shepp curve often reverses,
  // which the reverse penalty prices at twice its length, where a forward
  // curve a little longer costs less. Tried cheapest first by their price
  // without cell costs.
  struct Candidate {
    Shot shot;
    double price;
  };
  std::vector<Candidate> candidates;
  for (size_t h = 0; h < headings.size(); ++h) {
    const double yaw = headings[h];
    bool seen = false;
    for (size_t k = 0; k < h; ++k) seen = seen || AngleBetween(headings[k], yaw) < 1e-9;
    if (seen) continue;
    const Pose target{goal.x, goal.y, yaw};
    // With a heading tolerance the validation only showed that some
    // heading is free.
    if (!motion_.PoseFree(target)) continue;
    for (const bool reverse : {reverse_, false}) {
      const Curve curve = ShortestCurve(from, target, radius_, reverse);
      candidates.push_back(Candidate{Shot{curve, target}, CurvePrice(curve)});
      if (!reverse_) break;
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.price < b.price; });
  for (size_t i = 0; i < candidates.size() && i < kAnalyticTries; ++i) {
    if (CurveFree(id, candidates[i].shot.curve)) {
      shot = candidates[i].shot;
      return true;
    }
  }
  return false;
}

double HybridSearch::DriveShot(uint32_t id, const Shot& shot,
                               std::vector<PathPose>& poses) const {
  // Driven as CurveFree drove it.
  const Node& n = nodes_[id];
  Pose at = n.pose;
  Pose previous = at;
  std::optional<PieceKind> kind;
  if (n.primitive >= 0) kind = n.kind;
  double cost = 0.0;
  for (int32_t i = 0; i < shot.curve.count; ++i) {
    const CurveSegment& s = shot.curve.segments[i];
    const int32_t pieces = PieceCount(s.steer, s.length, radius_);
    for (int32_t j = 1; j <= pieces; ++j) {
      const bool last = i + 1 == shot.curve.count && j == pieces;
      // Driving the curve ends on the goal up to rounding; end exactly there.
      const Pose next = last ? shot.goal : Drive(at, s.steer, radius_, s.length * j / pieces);
      const PieceKind piece = KindOf(previous, next, s.length < 0.0);
      const Cell c = next.cell();
      cost += PieceCost(PieceLength(previous, next), grid_.InBounds(c) ? grid_.cost(c) : kFreeCost,
                        piece, kind ? &*kind : nullptr, penalties_);
      kind = piece;
      previous = next;
      poses.push_back(PathPose{next, s.length < 0.0});
    }
    at = Drive(at, s.steer, radius_, s.length);
  }
  return cost;
}

PlanResult HybridSearch::Finish(uint32_t id, const Shot* shot, int64_t expansions) const {
  std::vector<uint32_t> chain;
  for (uint32_t at = id; at != kNoNode; at = nodes_[at].parent) chain.push_back(at);
  std::reverse(chain.begin(), chain.end());
  std::vector<PathPose> poses = {PathPose{nodes_[0].pose, false}};
  const auto append = [&poses](const DrivenMotion& drive, const Primitive& p) {
    for (int32_t j = 1; j <= static_cast<int32_t>(p.pieces.size()); ++j) {
      poses.push_back(PathPose{drive.Piece(j), p.length < 0.0});
    }
  };
  for (size_t i = 1; i < chain.size(); ++i) {
    const Node& n = nodes_[chain[i]];
    const Primitive& p = primitives_[static_cast<size_t>(n.primitive)];
    append(DrivenMotion(nodes_[n.parent].pose, p, radius_), p);
  }
  if (shot != nullptr) DriveShot(id, *shot, poses);
  if (poses.size() > 1) poses[0].reverse = poses[1].reverse;

  if (options_.smooth && q_.smooth && poses.size() > 2) {
    SmootherOptions smoothing;
    smoothing.min_turning_radius = radius_;
    poses = SmoothPath(poses, motion_, smoothing);
  }

  PlanResult result;
  result.outcome = PlanOutcome::kFound;
  result.expansions = expansions;
  result.path = PathCells(poses);
  result.length = PathLength(poses);
  result.cost = PathCost(grid_, poses, penalties_);
  result.poses = std::move(poses);
  return result;
}

PlanResult HybridSearch::Run(int32_t subdivisions, int64_t expansions) {
  subdivisions_ = subdivisions;
  nodes_.clear();
  states_.clear();
  open_ = {};
  Node start;
  start.pose = q_.start;
  start.pose.yaw = NormalizeAngle(start.pose.yaw);
  start.h = ObstacleHeuristic(start.pose);
  unreachable_ = !(start.h < kInfinity);
  nodes_.push_back(start);
  states_.emplace(Key(start.pose), 0);
  open_.push(OpenEntry{start.h, 0.0, 0});
  int64_t until_analytic = 0;
  // The cheapest analytic expansion found so far that was not taken at once
  // (HybridAStarOptions::analytic_slack).
  uint32_t best_node = kNoNode;
  Shot best_shot;
  double best_cost = kInfinity;
  while (!open_.empty()) {
    const OpenEntry top = open_.top();
    open_.pop();
    Node& n = nodes_[top.node];
    if (n.closed || top.g != n.g) continue;
    if (!n.curve_heuristic) {
      n.curve_heuristic = true;
      const double h = std::max(n.h, CurveHeuristic(n.pose));
      if (h > n.h) {
        n.h = h;
        open_.push(OpenEntry{n.g + h, n.g, top.node});
        continue;
      }
    }
    if (best_node != kNoNode && Expected(n) * options_.analytic_slack >= best_cost) break;
    const PlanOutcome stop = stop_.Check(expansions, top.f);
    if (stop != PlanOutcome::kFound) {
      // A path in hand is an answer, even if not the best the search would
      // have found.
      if (best_node != kNoNode) break;
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
    if (Reached(n.pose) && n.g <= best_cost) return Finish(top.node, nullptr, expansions);
    if (options_.analytic_expansion && --until_analytic <= 0) {
      until_analytic = std::max<int64_t>(
          1, static_cast<int64_t>(std::floor(n.h / options_.analytic_expansion_ratio)));
      Shot shot;
      if (TryAnalytic(top.node, shot)) {
        std::vector<PathPose> poses;
        const double cost = n.g + DriveShot(top.node, shot, poses);
        if (cost <= options_.analytic_slack * Expected(n)) {
          return Finish(top.node, &shot, expansions);
        }
        if (cost < best_cost) {
          best_node = top.node;
          best_shot = shot;
          best_cost = cost;
        }
      }
    }
    Expand(top.node);
  }
  if (best_node != kNoNode) return Finish(best_node, &best_shot, expansions);
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
  // A lattice exhausted without reaching the goal is searched again with
  // squares of half the size (docs/planners.md, "hybrid_astar"): keeping one
  // pose per coarse state can lose the only way through a tight place.
  int64_t expansions = 0;
  for (int32_t subdivisions = 1;; subdivisions *= 2) {
    PlanResult result = search.Run(subdivisions, expansions);
    if (result.outcome != PlanOutcome::kNoPath || search.unreachable() ||
        subdivisions >= options.max_subdivisions) {
      return result;
    }
    expansions = result.expansions;
  }
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
