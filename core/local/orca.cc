#include "core/local/orca.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "absl/strings/str_format.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

// Tolerance for parallel lines in the programs.
constexpr double kParallel = 1e-9;

struct Vec {
  double x = 0.0;
  double y = 0.0;
};
Vec V(CellPoint p) { return Vec{p.x, p.y}; }
CellPoint P(Vec v) { return CellPoint{v.x, v.y}; }
Vec operator+(Vec a, Vec b) { return {a.x + b.x, a.y + b.y}; }
Vec operator-(Vec a, Vec b) { return {a.x - b.x, a.y - b.y}; }
Vec operator*(double s, Vec a) { return {s * a.x, s * a.y}; }
double Dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y; }
double Det(Vec a, Vec b) { return a.x * b.y - a.y * b.x; }
double Norm2(Vec a) { return Dot(a, a); }
double Norm(Vec a) { return std::sqrt(Norm2(a)); }
Vec Unit(Vec a) {
  const double n = Norm(a);
  return n > 0 ? (1.0 / n) * a : Vec{1.0, 0.0};
}

struct Line {
  Vec point;
  Vec dir;
};
Line L(const OrcaLine& l) { return Line{V(l.point), V(l.direction)}; }

// The 1-D program on line `k`: the point of it inside the disc and the
// half-planes of lines[0..k-1] that is closest to `target` (or, with
// `extreme`, farthest along the unit direction `target`). False when that
// part of the line is empty.
bool SolveOnLine(const std::vector<Line>& lines, size_t k, double radius,
                 Vec target, bool extreme, Vec* result) {
  const Line& line = lines[k];
  // The line's chord of the disc: point + t dir for t in [t_lo, t_hi].
  const double along = Dot(line.point, line.dir);
  const double disc = along * along + radius * radius - Norm2(line.point);
  if (disc < 0) return false;
  const double root = std::sqrt(disc);
  double t_lo = -along - root;
  double t_hi = -along + root;
  for (size_t i = 0; i < k; ++i) {
    const double denom = Det(line.dir, lines[i].dir);
    const double numer = Det(lines[i].dir, line.point - lines[i].point);
    if (std::fabs(denom) <= kParallel) {
      // Parallel: the whole line is on one side of line i.
      if (numer < 0) return false;
      continue;
    }
    const double t = numer / denom;
    if (denom > 0) {
      t_hi = std::min(t_hi, t);
    } else {
      t_lo = std::max(t_lo, t);
    }
    if (t_lo > t_hi) return false;
  }
  double t;
  if (extreme) {
    t = Dot(target, line.dir) > 0 ? t_hi : t_lo;
  } else {
    t = std::clamp(Dot(line.dir, target - line.point), t_lo, t_hi);
  }
  *result = line.point + t * line.dir;
  return true;
}

// The 2-D program: the velocity in the disc and every half-plane closest to
// `target` (or extreme along the unit `target`), adding the lines one at a
// time; when the current answer violates line i, the new answer lies on
// line i (the 1-D program). Returns lines.size() on success, else the index
// of the line that made it infeasible (`result` then holds the answer for
// the lines before it).
size_t SolvePlane(const std::vector<Line>& lines, double radius, Vec target,
                  bool extreme, Vec* result) {
  if (extreme) {
    *result = radius * target;
  } else if (Norm2(target) > radius * radius) {
    *result = radius * Unit(target);
  } else {
    *result = target;
  }
  for (size_t i = 0; i < lines.size(); ++i) {
    if (Det(lines[i].dir, lines[i].point - *result) > 0) {
      const Vec before = *result;
      if (!SolveOnLine(lines, i, radius, target, extreme, result)) {
        *result = before;
        return i;
      }
    }
  }
  return lines.size();
}

// The 3-D program (the paper's fallback): minimise the largest violation d of
// lines [hard, n) while keeping lines [0, hard). Incremental in the
// violation: whenever line i is violated by more than the current d, the
// optimum has line i's violation equal to the largest of the earlier soft
// lines, which in the velocity plane is a 2-D program over the bisectors of
// line i with each earlier soft line (plus the hard lines), solved for the
// velocity farthest into line i's half-plane.
void SolveSpace(const std::vector<Line>& lines, size_t hard,
                size_t first_failed, double radius, Vec* result) {
  double worst = 0.0;
  std::vector<Line> projected;
  for (size_t i = first_failed; i < lines.size(); ++i) {
    if (Det(lines[i].dir, lines[i].point - *result) <= worst) continue;
    projected.assign(lines.begin(),
                     lines.begin() + static_cast<std::ptrdiff_t>(hard));
    for (size_t j = hard; j < i; ++j) {
      Line bisector;
      const double determinant = Det(lines[i].dir, lines[j].dir);
      if (std::fabs(determinant) <= kParallel) {
        if (Dot(lines[i].dir, lines[j].dir) > 0) continue;  // same direction
        bisector.point = 0.5 * (lines[i].point + lines[j].point);
      } else {
        bisector.point =
            lines[i].point +
            (Det(lines[j].dir, lines[i].point - lines[j].point) / determinant) *
                lines[i].dir;
      }
      bisector.dir = Unit(lines[j].dir - lines[i].dir);
      projected.push_back(bisector);
    }
    const Vec before = *result;
    // Farthest into line i: along its inward normal (-dir.y, dir.x).
    if (SolvePlane(projected, radius, Vec{-lines[i].dir.y, lines[i].dir.x},
                   true, result) < projected.size()) {
      // Only floating point can get here (the previous answer is feasible
      // for the projected program); keep it.
      *result = before;
    }
    worst = Det(lines[i].dir, lines[i].point - *result);
  }
}

// Differential drive: the forward speed t in [0, v] along the unit heading
// h whose velocity t h satisfies every line, nearest v; when none does, the
// t in [0, v] with the smallest largest violation (the violation is convex
// and piecewise linear in t, so its minimum is at 0, v or a breakpoint).
double SafeForwardSpeed(const std::vector<OrcaLine>& lines, Vec h, double v) {
  if (v <= 0) return v;
  double lo = 0.0, hi = v;
  bool empty = false;
  for (const OrcaLine& l : lines) {
    // det(dir, t h - point) >= 0  <=>  t det(dir, h) >= det(dir, point).
    const double a = Det(V(l.direction), h);
    const double b = Det(V(l.direction), V(l.point));
    if (a > kParallel) {
      lo = std::max(lo, b / a);
    } else if (a < -kParallel) {
      hi = std::min(hi, b / a);
    } else if (b > 0) {
      empty = true;
    }
  }
  if (!empty && lo <= hi) return hi;
  const auto worst = [&](double t) {
    double w = -std::numeric_limits<double>::infinity();
    for (const OrcaLine& l : lines) {
      w = std::max(
          w, Det(V(l.direction), V(l.point)) - Det(V(l.direction), h) * t);
    }
    return w;
  };
  double best_t = 0.0, best = worst(0.0);
  const auto consider = [&](double t) {
    if (t < 0 || t > v) return;
    const double w = worst(t);
    if (w < best) {
      best = w;
      best_t = t;
    }
  };
  consider(v);
  for (const OrcaLine& l : lines) {
    const double a = Det(V(l.direction), h);
    if (std::fabs(a) > kParallel) {
      consider(Det(V(l.direction), V(l.point)) / a);
    }
  }
  return best_t;
}

Vec GridVelocity(const RobotState& s) {
  const double c = std::cos(s.pose.yaw), sn = std::sin(s.pose.yaw);
  return Vec{s.v * c - s.vy * sn, s.v * sn + s.vy * c};
}

// The distance from point p to segment ab.
double PointSegmentDistance(Vec p, Vec a, Vec b) {
  const Vec ab = b - a;
  const double len2 = Norm2(ab);
  const double t =
      len2 > 0 ? std::clamp(Dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return Norm(p - (a + t * ab));
}

}  // namespace

double OrcaViolation(const OrcaLine& line, CellPoint v) {
  return Det(V(line.direction), V(line.point) - V(v));
}

OrcaLine OrcaLineForNeighbour(CellPoint position, CellPoint velocity,
                              double radius, const MovingObstacle& other,
                              double horizon, double period, double share) {
  const Vec rel_pos = V(other.position) - V(position);
  const Vec rel_vel = V(velocity) - V(other.velocity);
  const double dist2 = Norm2(rel_pos);
  const double r = radius + other.radius;
  const double r2 = r * r;
  Vec dir;
  Vec u;  // the smallest change of rel_vel that leaves the velocity obstacle
  if (dist2 > r2) {
    // The velocity obstacle: the cone from the origin tangent to the disc of
    // radius r about rel_pos, truncated by the disc about rel_pos / horizon
    // of radius r / horizon.
    const double inv_h = 1.0 / horizon;
    const Vec w = rel_vel - inv_h * rel_pos;  // from the cutoff centre
    const double w2 = Norm2(w);
    const double w_dot = Dot(w, rel_pos);
    if (w_dot < 0 && w_dot * w_dot > r2 * w2) {
      // Nearest boundary point is on the cutoff circle.
      const double w_len = std::sqrt(w2);
      const Vec unit_w = (1.0 / w_len) * w;
      dir = Vec{unit_w.y, -unit_w.x};
      u = (r * inv_h - w_len) * unit_w;
    } else {
      // On one of the cone's legs: the one on w's side of rel_pos.
      const double leg = std::sqrt(dist2 - r2);
      if (Det(rel_pos, w) > 0) {
        dir = (1.0 / dist2) * Vec{rel_pos.x * leg - rel_pos.y * r,
                                  rel_pos.x * r + rel_pos.y * leg};
      } else {
        dir = (-1.0 / dist2) * Vec{rel_pos.x * leg + rel_pos.y * r,
                                   -rel_pos.x * r + rel_pos.y * leg};
      }
      u = Dot(rel_vel, dir) * dir - rel_vel;
    }
  } else {
    // Already overlapping: leave the overlap within one period.
    const double inv_p = 1.0 / period;
    const Vec w = rel_vel - inv_p * rel_pos;
    const double w_len = Norm(w);
    const Vec unit_w =
        w_len > 0 ? (1.0 / w_len) * w : Unit(Vec{-rel_pos.x, -rel_pos.y});
    dir = Vec{unit_w.y, -unit_w.x};
    u = (r * inv_p - w_len) * unit_w;
  }
  return OrcaLine{P(V(velocity) + share * u), P(dir)};
}

OrcaLine OrcaLineForSegment(CellPoint position, double radius,
                            const ObstacleSegment& segment, double horizon,
                            double period) {
  const Vec p = V(position), a = V(segment.a), b = V(segment.b);
  const Vec ab = b - a;
  const double len2 = Norm2(ab);
  const double t = len2 > 0 ? std::clamp(Dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  const Vec q = a + t * ab;
  const double d = Norm(p - q);
  // n: away from the segment. A robot centred on the segment has no such
  // direction; the segment's normal then stands in.
  const Vec n = d > 1e-12 ? (1.0 / d) * (p - q) : Unit(Vec{-ab.y, ab.x});
  // n . v >= bound is the half-plane left of the line through bound * n
  // along dir = (n.y, -n.x), whose left normal (-dir.y, dir.x) is n.
  const double bound =
      d >= radius ? -(d - radius) / horizon : (radius - d) / period;
  const Vec dir{n.y, -n.x};
  return OrcaLine{P(bound * n), P(dir)};
}

std::vector<ObstacleSegment> ObstacleSegmentsNear(
    const ObstaclePolygons& polygons, CellPoint center, double range,
    size_t max_segments) {
  std::vector<std::pair<double, ObstacleSegment>> found;
  for (const BoundaryRing& ring : polygons.rings()) {
    // Box distance: the nearest point of the ring's bounding box.
    const double bx =
        std::max({ring.min.x - center.x, 0.0, center.x - ring.max.x});
    const double by =
        std::max({ring.min.y - center.y, 0.0, center.y - ring.max.y});
    if (bx * bx + by * by > range * range) continue;
    const size_t n = ring.vertices.size();
    for (size_t i = 0; i < n; ++i) {
      const GridCorner& ga = ring.vertices[i];
      const GridCorner& gb = ring.vertices[(i + 1) % n];
      const ObstacleSegment s{
          CellPoint{static_cast<double>(ga.x), static_cast<double>(ga.y)},
          CellPoint{static_cast<double>(gb.x), static_cast<double>(gb.y)}};
      const double d = PointSegmentDistance(V(center), V(s.a), V(s.b));
      if (d <= range) found.emplace_back(d, s);
    }
  }
  std::sort(found.begin(), found.end(),
            [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<ObstacleSegment> out;
  for (size_t i = 0; i < found.size() && i < max_segments; ++i)
    out.push_back(found[i].second);
  return out;
}

namespace {

// The distance between segments ab and cd (0 when they cross).
double SegmentDistance(Vec a, Vec b, Vec c, Vec d) {
  const double d1 = Det(b - a, c - a), d2 = Det(b - a, d - a);
  const double d3 = Det(d - c, a - c), d4 = Det(d - c, b - c);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) &&
      ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) {
    return 0.0;
  }
  return std::min({PointSegmentDistance(a, c, d), PointSegmentDistance(b, c, d),
                   PointSegmentDistance(c, a, b),
                   PointSegmentDistance(d, a, b)});
}

}  // namespace

PathTarget VisibleTarget(absl::Span<const CellPoint> path, CellPoint position,
                         double radius,
                         absl::Span<const ObstacleSegment> segments,
                         double lookahead) {
  const Vec p = V(position);
  // The robot may already be closer to a segment than `radius` (it slid
  // along a wall): the sight line must not get closer than it is now.
  double now = std::numeric_limits<double>::infinity();
  for (const ObstacleSegment& s : segments) {
    now = std::min(now, PointSegmentDistance(p, V(s.a), V(s.b)));
  }
  const double need = std::min(radius, now) - 1e-6;
  constexpr int kTries = 8;
  PathTarget target;
  for (int i = 0; i < kTries; ++i) {
    // lookahead, then shorter by equal steps down to an eighth of it.
    const double reach = lookahead * (kTries - i) / kTries;
    target = FindPathTarget(path, position, reach);
    const Vec t = V(target.point);
    bool clear = true;
    for (const ObstacleSegment& s : segments) {
      if (SegmentDistance(p, t, V(s.a), V(s.b)) < need) {
        clear = false;
        break;
      }
    }
    if (clear) return target;
  }
  return target;
}

OrcaSolution SolveOrcaLines(absl::Span<const OrcaLine> lines, size_t hard_lines,
                            double max_speed, CellPoint preferred) {
  std::vector<Line> ls;
  ls.reserve(lines.size());
  for (const OrcaLine& l : lines) ls.push_back(L(l));
  hard_lines = std::min(hard_lines, ls.size());
  // The soft lines in a random order (fixed seed: the same input gives the
  // same answer): the incremental program's expected linear time.
  std::mt19937 rng(static_cast<uint32_t>(ls.size()));
  std::shuffle(ls.begin() + static_cast<std::ptrdiff_t>(hard_lines), ls.end(),
               rng);
  Vec result;
  OrcaSolution solution;
  const size_t failed = SolvePlane(ls, max_speed, V(preferred), false, &result);
  if (failed < ls.size()) {
    SolveSpace(ls, hard_lines, failed, max_speed, &result);
  }
  solution.velocity = P(result);
  double worst = 0.0;
  for (const Line& l : ls)
    worst = std::max(worst, Det(l.dir, l.point - result));
  solution.max_violation = worst;
  solution.feasible = failed >= ls.size() || worst <= 1e-9;
  return solution;
}

absl::Status ValidateOrcaOptions(const OrcaOptions& o) {
  if (!(std::isfinite(o.keep_right) && std::fabs(o.keep_right) < 1.0)) {
    return absl::InvalidArgumentError(
        "orca options: keep_right must be in (-1, 1) radians");
  }
  PATHD_RETURN_IF_ERROR(
      CheckOptionValues("orca",
                        {{"time_horizon", o.time_horizon},
                         {"obstacle_time_horizon", o.obstacle_time_horizon},
                         {"neighbour_range", o.neighbour_range},
                         {"obstacle_range", o.obstacle_range},
                         {"lookahead", o.lookahead},
                         {"goal_tolerance", o.goal_tolerance},
                         {"turn_gain", o.turn_gain},
                         {"window_seconds", o.window_seconds}},
                        /*zero_ok=*/false));
  if (!(std::isfinite(o.min_progress) && o.min_progress >= 0)) {
    return absl::InvalidArgumentError(
        "orca options: min_progress must be >= 0 and finite");
  }
  if (!(std::isfinite(o.safety_margin) && o.safety_margin >= 0)) {
    return absl::InvalidArgumentError(
        "orca options: safety_margin must be >= 0 and finite");
  }
  if (o.trajectory_steps < 1 || o.trajectory_steps > 1000) {
    return absl::InvalidArgumentError(
        "orca options: trajectory_steps must be in 1..1000");
  }
  if (o.max_neighbours > 10000 || o.max_obstacle_lines > 10000) {
    return absl::InvalidArgumentError(
        "orca options: max_neighbours and max_obstacle_lines must be at most "
        "10000");
  }
  return absl::OkStatus();
}

absl::StatusOr<LocalPlan> OrcaStep(const RobotState& state, double radius,
                                   const VelocityLimits& limits,
                                   absl::Span<const MovingObstacle> neighbours,
                                   absl::Span<const ObstacleSegment> segments,
                                   absl::Span<const CellPoint> path,
                                   double period, const OrcaOptions& options,
                                   ProgressWindow* progress) {
  if (absl::Status s = ValidateOrcaOptions(options); !s.ok()) return s;
  if (absl::Status s = ValidateVelocityLimits(limits); !s.ok()) return s;
  if (!(std::isfinite(radius) && radius > 0)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("orca: radius must be positive (got %g)", radius));
  }
  if (!(std::isfinite(period) && period > 0)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "orca: control period must be positive (got %g)", period));
  }
  if (path.empty())
    return absl::InvalidArgumentError("orca: the global path is empty");

  LocalPlan plan;
  const CellPoint position = state.pose.point();
  const Vec velocity = GridVelocity(state);
  const double r = radius + options.safety_margin;
  const double max_speed = std::max(limits.max_v, 0.0);

  // Preferred velocity: toward the lookahead point, slowing to stop at the
  // end; the lookahead shortened until the robot sees it past the static
  // obstacles (a point round a corner would pull it into the corner).
  const PathTarget target =
      VisibleTarget(path, position, r, segments, options.lookahead);
  Vec preferred;
  const bool at_goal = target.distance_to_goal <= options.goal_tolerance;
  if (!at_goal) {
    const Vec to = V(target.point) - V(position);
    const double dist = Norm(to);
    if (dist > 1e-12)
      preferred = (std::min(max_speed, dist / period) / dist) * to;
  }

  std::vector<OrcaLine> lines;
  for (const ObstacleSegment& s : segments) {
    if (lines.size() >= options.max_obstacle_lines) break;
    lines.push_back(OrcaLineForSegment(position, r, s,
                                       options.obstacle_time_horizon, period));
  }
  const size_t hard = lines.size();
  // The nearest neighbours within range.
  std::vector<std::pair<double, size_t>> near;
  for (size_t i = 0; i < neighbours.size(); ++i) {
    const double d = Norm(V(neighbours[i].position) - V(position));
    if (d <= options.neighbour_range) near.emplace_back(d, i);
  }
  const size_t keep = std::min(near.size(), options.max_neighbours);
  std::partial_sort(near.begin(),
                    near.begin() + static_cast<std::ptrdiff_t>(keep),
                    near.end());
  const double speed = Norm(velocity);
  for (size_t k = 0; k < keep; ++k) {
    const MovingObstacle& o = neighbours[near[k].second];
    double share = o.reciprocal ? 0.5 : 1.0;
    // Following: a robot ahead that goes our way is not expected to give
    // way (it may be braking for its own reasons; with the acceleration
    // clamp half the avoidance came too late, docs/decisions.md): the
    // follower keeps the gap alone. More than half is always safe.
    const Vec ahead = V(o.position) - V(position);
    if (share < 1.0 && speed > 1e-6 && Norm(ahead) > 1e-9 &&
        Dot(velocity, ahead) > 0.7 * speed * Norm(ahead) &&
        Dot(velocity, V(o.velocity)) > 0) {
      share = 1.0;
    }
    lines.push_back(OrcaLineForNeighbour(position, P(velocity), r, o,
                                         options.time_horizon, period, share));
  }
  plan.constraints = static_cast<int64_t>(lines.size());
  if (keep > 0 && options.keep_right != 0) {
    const double c = std::cos(-options.keep_right),
                 s = std::sin(-options.keep_right);
    preferred = Vec{c * preferred.x - s * preferred.y,
                    s * preferred.x + c * preferred.y};
  }
  const OrcaSolution solution =
      SolveOrcaLines(lines, hard, max_speed, P(preferred));
  const Vec chosen = V(solution.velocity);

  // The command in the body frame.
  const double c = std::cos(state.pose.yaw), s = std::sin(state.pose.yaw);
  double v, vy = 0.0, w;
  if (limits.holonomic) {
    v = Dot(chosen, Vec{c, s});
    vy = Dot(chosen, Vec{-s, c});
    // Heading: toward the path's lookahead point (the body turns; the
    // velocity does not depend on it).
    const Vec to = V(target.point) - V(position);
    const double err =
        Norm(to) > 1e-6 && !at_goal
            ? NormalizeAngle(std::atan2(to.y, to.x) - state.pose.yaw)
            : 0.0;
    w = std::clamp(options.turn_gain * err, -limits.max_w, limits.max_w);
    v = std::clamp(v, limits.min_v, limits.max_v);
    vy = std::clamp(vy, -limits.max_vy, limits.max_vy);
  } else {
    FollowVelocityDiffDrive(P(chosen), state.pose.yaw, options.turn_gain,
                            limits, &v, &w);
    // The robot moves along its heading, not along `chosen`: keep the
    // forward speed inside the half-planes along the current heading.
    v = SafeForwardSpeed(lines, Vec{c, s}, v);
  }
  if (options.respect_acceleration) {
    v = ClampToWindow(v, state.v, limits.acc_v, period, limits.min_v,
                      limits.max_v);
    w = ClampToWindow(w, state.w, limits.acc_w, period, -limits.max_w,
                      limits.max_w);
    if (limits.holonomic) {
      vy = ClampToWindow(vy, state.vy, limits.acc_vy, period, -limits.max_vy,
                         limits.max_vy);
    }
  }
  plan.v = v;
  plan.vy = vy;
  plan.w = w;
  plan.samples = 1;
  const int32_t steps = options.trajectory_steps;
  const double h = options.time_horizon / steps;
  plan.trajectory.reserve(static_cast<size_t>(steps) + 1);
  plan.trajectory.push_back(state.pose);
  for (int32_t i = 0; i < steps; ++i) {
    plan.trajectory.push_back(
        IntegrateVelocity(plan.trajectory.back(), v, vy, w, h, 1));
  }
  if (at_goal) {
    plan.status = LocalStatus::kGoalReached;
    plan.reason = absl::StrFormat("within %g cells of the path's end",
                                  options.goal_tolerance);
  } else if (!solution.feasible) {
    plan.status = LocalStatus::kBlocked;
    plan.reason = absl::StrFormat(
        "no velocity satisfies all %d constraints; the least-violating one (by "
        "%.3g cells/s) "
        "is commanded",
        static_cast<int>(lines.size()), solution.max_violation);
  }
  if (at_goal && progress != nullptr) progress->remaining.clear();
  if (!at_goal) {
    ReportStall(progress, target, period, options.window_seconds,
                options.min_progress, &plan);
  }
  return plan;
}

}  // namespace pathd
