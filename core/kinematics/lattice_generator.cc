#include "core/kinematics/lattice_generator.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <numeric>
#include <queue>
#include <tuple>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace pathd {
namespace {

constexpr double kPi = std::numbers::pi;

// A candidate primitive before it has poses: what the minimality test and
// the symmetry need, and the shape that makes the poses.
struct Candidate {
  enum class Shape { kCurve, kTranslation };
  Shape shape = Shape::kCurve;
  int32_t h0 = 0;
  int32_t h1 = 0;
  int32_t dx = 0;
  int32_t dy = 0;
  double length = 0.0;
  // kCurve: straight, arc (radius, signed turn), straight.
  double straight1 = 0.0;
  double radius = 0.0;
  double turn = 0.0;
  double straight2 = 0.0;
};

// The eight symmetries of the square lattice: mirror in the x axis when
// `mirror`, then `quarter_turns` quarter turns counter-clockwise.
struct Symmetry {
  bool mirror = false;
  int32_t quarter_turns = 0;

  Cell Apply(Cell c) const {
    if (mirror) c.y = -c.y;
    for (int32_t k = 0; k < quarter_turns; ++k) c = Cell{-c.y, c.x};
    return c;
  }
  CellPoint Apply(CellPoint p) const {
    if (mirror) p.y = -p.y;
    for (int32_t k = 0; k < quarter_turns; ++k) p = CellPoint{-p.y, p.x};
    return p;
  }
  double ApplyYaw(double yaw) const {
    return NormalizeAngle((mirror ? -yaw : yaw) + quarter_turns * kPi / 2.0);
  }
  // Heading indices: a quarter is headings / 4 indices; the mirror maps i to
  // -i.
  int32_t ApplyHeading(int32_t h, int32_t n) const {
    if (mirror) h = (n - h) % n;
    return (h + quarter_turns * (n / 4)) % n;
  }
};

std::vector<Symmetry> AllSymmetries() {
  std::vector<Symmetry> out;
  for (bool mirror : {false, true}) {
    for (int32_t k = 0; k < 4; ++k) out.push_back(Symmetry{mirror, k});
  }
  return out;
}

int64_t Cross(int64_t ax, int64_t ay, int64_t bx, int64_t by) { return ax * by - ay * bx; }

// Nav2's trajectory shape from heading angle a at the origin to heading angle
// b at `end`: along a's line, an arc tangent to both lines, along b's line,
// the arc as large as the shorter of the two distances to the lines'
// intersection allows. Straight when a == b and `end` lies ahead on a's line.
// False when there is no such motion forward, or its arc is tighter than
// `min_radius`.
bool CurveTo(const Candidate& c, double a, double b, Cell dir_a, double min_radius,
             Candidate* out) {
  *out = c;
  out->shape = Candidate::Shape::kCurve;
  const double ex = c.dx;
  const double ey = c.dy;
  if (c.h0 == c.h1) {
    if (Cross(dir_a.x, dir_a.y, c.dx, c.dy) != 0) return false;
    if (static_cast<int64_t>(dir_a.x) * c.dx + static_cast<int64_t>(dir_a.y) * c.dy <= 0) {
      return false;
    }
    out->length = std::hypot(ex, ey);
    out->straight1 = out->length;
    return true;
  }
  const double delta = NormalizeAngle(b - a);
  if (std::fabs(delta) > kPi / 2.0 + 1e-9) return false;
  const double ux = std::cos(a), uy = std::sin(a);
  const double vx = std::cos(b), vy = std::sin(b);
  const double det = ux * vy - uy * vx;  // sin(delta)
  // end = t * u + s * v: t along a's line to the intersection, s from there.
  const double t = (ex * vy - ey * vx) / det;
  const double s = (ux * ey - uy * ex) / det;
  if (t < -1e-9 || s < -1e-9) return false;
  const double tangent = std::min(t, s);
  if (tangent <= 1e-9) return false;
  const double radius = tangent / std::tan(std::fabs(delta) / 2.0);
  if (radius < min_radius * (1.0 - 1e-12)) return false;
  out->straight1 = std::max(0.0, t - tangent);
  out->straight2 = std::max(0.0, s - tangent);
  out->radius = radius;
  out->turn = delta;
  out->length = out->straight1 + radius * std::fabs(delta) + out->straight2;
  return true;
}

// Appends poses from `from` (exclusive) to `to` (inclusive), in `pieces`
// equal steps of position and heading.
void AppendLinear(const Pose& from, const Pose& to, int32_t pieces, std::vector<Pose>* poses) {
  const double dyaw = NormalizeAngle(to.yaw - from.yaw);
  for (int32_t i = 1; i <= pieces; ++i) {
    const double f = static_cast<double>(i) / pieces;
    poses->push_back(Pose{from.x + f * (to.x - from.x), from.y + f * (to.y - from.y),
                          NormalizeAngle(from.yaw + f * dyaw)});
  }
}

int32_t PiecesFor(double length, double turn) {
  return std::max<int32_t>(
      1, static_cast<int32_t>(std::max(std::ceil(length / kLatticePoseSpacing - 1e-9),
                                       std::ceil(std::fabs(turn) / kLatticeYawSpacing - 1e-9))));
}

// The primitive of a candidate from its representative heading, with poses.
LatticePrimitive Build(const Candidate& c, const std::vector<double>& angles) {
  LatticePrimitive p;
  p.start_heading = c.h0;
  p.end_heading = c.h1;
  p.dx = c.dx;
  p.dy = c.dy;
  p.length = c.length;
  const double a = angles[c.h0];
  const double b = angles[c.h1];
  Pose at{0.0, 0.0, NormalizeAngle(a)};
  p.poses.push_back(at);
  if (c.shape == Candidate::Shape::kTranslation) {
    p.left_turn = NormalizeAngle(b - a) > 0.0;
    AppendLinear(at, Pose{static_cast<double>(c.dx), static_cast<double>(c.dy), NormalizeAngle(b)},
                 PiecesFor(c.length, NormalizeAngle(b - a)), &p.poses);
    return p;
  }
  p.left_turn = c.turn > 0.0;
  p.radius = c.turn == 0.0 ? 0.0 : c.radius;
  p.arc_length = c.radius * std::fabs(c.turn);
  if (c.straight1 > 1e-9) {
    const Pose to{c.straight1 * std::cos(a), c.straight1 * std::sin(a), at.yaw};
    AppendLinear(at, to, PiecesFor(c.straight1, 0.0), &p.poses);
    at = to;
  }
  if (c.turn != 0.0) {
    const double side = c.turn > 0.0 ? 1.0 : -1.0;
    // The centre is `radius` to the side the arc turns to.
    const double cx = at.x - side * c.radius * std::sin(a);
    const double cy = at.y + side * c.radius * std::cos(a);
    const int32_t pieces = PiecesFor(p.arc_length, c.turn);
    for (int32_t i = 1; i <= pieces; ++i) {
      const double yaw = a + c.turn * i / pieces;
      p.poses.push_back(Pose{cx + side * c.radius * std::sin(yaw),
                             cy - side * c.radius * std::cos(yaw), NormalizeAngle(yaw)});
    }
    at = p.poses.back();
  }
  if (c.straight2 > 1e-9) {
    const Pose to{static_cast<double>(c.dx), static_cast<double>(c.dy), NormalizeAngle(b)};
    AppendLinear(at, to, PiecesFor(c.straight2, 0.0), &p.poses);
  }
  // The end is exact, whatever the rounding on the way.
  p.poses.back() = Pose{static_cast<double>(c.dx), static_cast<double>(c.dy), NormalizeAngle(b)};
  return p;
}

LatticePrimitive Transformed(const LatticePrimitive& p, const Symmetry& s,
                             const std::vector<double>& angles) {
  const int32_t n = static_cast<int32_t>(angles.size());
  LatticePrimitive out = p;
  out.start_heading = s.ApplyHeading(p.start_heading, n);
  out.end_heading = s.ApplyHeading(p.end_heading, n);
  const Cell end = s.Apply(Cell{p.dx, p.dy});
  out.dx = end.x;
  out.dy = end.y;
  // A mirror image turns the other way.
  if (s.mirror && p.turns()) out.left_turn = !p.left_turn;
  for (Pose& q : out.poses) {
    const CellPoint moved = s.Apply(CellPoint{q.x, q.y});
    q = Pose{moved.x, moved.y, s.ApplyYaw(q.yaw)};
  }
  out.poses.front() = Pose{0.0, 0.0, NormalizeAngle(angles[out.start_heading])};
  out.poses.back() = Pose{static_cast<double>(out.dx), static_cast<double>(out.dy),
                          NormalizeAngle(angles[out.end_heading])};
  return out;
}

// An edge of the composition graph: a primitive that moves (turns in place
// are not part of the minimality test).
struct Edge {
  int32_t dx;
  int32_t dy;
  int32_t h1;
  double length;
  friend bool operator==(const Edge&, const Edge&) = default;
};

// The primitives kept so far as a graph over (x, y, heading), and shortest
// chains of them from the origin.
class Composition {
 public:
  explicit Composition(int32_t headings) : n_(headings), edges_(headings) {}

  void Add(int32_t h0, const Edge& e) { edges_[h0].push_back(e); }
  void Remove(int32_t h0, const Edge& e) {
    auto& list = edges_[h0];
    list.erase(std::find(list.begin(), list.end(), e));
  }
  bool Has(int32_t h0, const Edge& e) const {
    const auto& list = edges_[h0];
    return std::find(list.begin(), list.end(), e) != list.end();
  }
  const std::vector<Edge>& EdgesFrom(int32_t h) const { return edges_[h]; }

  // Shortest chain lengths from (0, 0, h0) to every state within `limit`
  // (farther states read +infinity), by Dijkstra in a box of half-width
  // ceil(limit): no chain within the limit leaves it.
  void Solve(int32_t h0, double limit) {
    box_ = static_cast<int32_t>(std::ceil(limit)) + 1;
    const int32_t w = 2 * box_ + 1;
    dist_.assign(static_cast<size_t>(w) * w * n_, std::numeric_limits<float>::infinity());
    using Item = std::pair<float, uint32_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
    const uint32_t start = Index(0, 0, h0);
    dist_[start] = 0.0f;
    open.push({0.0f, start});
    while (!open.empty()) {
      const auto [d, i] = open.top();
      open.pop();
      if (d > dist_[i]) continue;
      const int32_t h = static_cast<int32_t>(i % n_);
      const int32_t cell = static_cast<int32_t>(i / n_);
      const int32_t x = cell % w - box_;
      const int32_t y = cell / w - box_;
      for (const Edge& e : edges_[h]) {
        const float nd = d + static_cast<float>(e.length);
        if (nd > limit) continue;
        const int32_t nx = x + e.dx;
        const int32_t ny = y + e.dy;
        if (std::abs(nx) > box_ || std::abs(ny) > box_) continue;
        const uint32_t j = Index(nx, ny, e.h1);
        if (nd < dist_[j]) {
          dist_[j] = nd;
          open.push({nd, j});
        }
      }
    }
  }
  // The last Solve()'s chain length to (x, y, h).
  double Distance(int32_t x, int32_t y, int32_t h) const {
    if (std::abs(x) > box_ || std::abs(y) > box_) return std::numeric_limits<double>::infinity();
    return dist_[Index(x, y, h)];
  }

 private:
  uint32_t Index(int32_t x, int32_t y, int32_t h) const {
    const int32_t w = 2 * box_ + 1;
    return static_cast<uint32_t>(((y + box_) * w + (x + box_)) * n_ + h);
  }

  int32_t n_;
  std::vector<std::vector<Edge>> edges_;
  int32_t box_ = 0;
  std::vector<float> dist_;
};

// A kept primitive and its images under the symmetries (distinct ones only).
struct Orbit {
  Candidate rep;
  std::vector<std::pair<int32_t, Edge>> edges;
  std::vector<Symmetry> images;
  size_t order = 0;
};

Orbit MakeOrbit(const Candidate& c, int32_t n) {
  Orbit orbit;
  orbit.rep = c;
  for (const Symmetry& s : AllSymmetries()) {
    const Cell end = s.Apply(Cell{c.dx, c.dy});
    const std::pair<int32_t, Edge> e{s.ApplyHeading(c.h0, n),
                                     Edge{end.x, end.y, s.ApplyHeading(c.h1, n), c.length}};
    if (std::find(orbit.edges.begin(), orbit.edges.end(), e) != orbit.edges.end()) continue;
    orbit.edges.push_back(e);
    orbit.images.push_back(s);
  }
  return orbit;
}

// Every heading reachable from every heading by chains of primitives.
bool Spans(const Composition& graph, int32_t n) {
  for (int32_t from = 0; from < n; ++from) {
    std::vector<bool> seen(n, false);
    std::vector<int32_t> stack{from};
    seen[from] = true;
    while (!stack.empty()) {
      const int32_t h = stack.back();
      stack.pop_back();
      for (const Edge& e : graph.EdgesFrom(h)) {
        if (!seen[e.h1]) {
          seen[e.h1] = true;
          stack.push_back(e.h1);
        }
      }
    }
    if (std::find(seen.begin(), seen.end(), false) != seen.end()) return false;
  }
  return true;
}

absl::Status Validate(const LatticeGeneratorOptions& o) {
  if (!std::isfinite(o.resolution_m) || o.resolution_m <= 0.0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("lattice resolution must be a positive number of metres, got %g",
                        o.resolution_m));
  }
  if (!std::isfinite(o.turning_radius_m) || o.turning_radius_m <= 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "lattice turning radius must be a positive number of metres, got %g", o.turning_radius_m));
  }
  const double cells = o.turning_radius_m / o.resolution_m;
  if (cells < 0.5 || cells > 64.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "lattice turning radius must be 0.5 to 64 cells, got %g m / %g m = %g cells",
        o.turning_radius_m, o.resolution_m, cells));
  }
  if (o.headings < 8 || o.headings > 64 || o.headings % 8 != 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "lattice headings must be a multiple of 8 in 8..64, got %d", o.headings));
  }
  if (!(o.length_tolerance >= 0.0 && o.length_tolerance <= 1.0)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "lattice length tolerance must be in [0, 1], got %g", o.length_tolerance));
  }
  if (o.stopping_threshold < 1 || o.stopping_threshold > 50) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "lattice stopping threshold must be in 1..50, got %d", o.stopping_threshold));
  }
  return absl::OkStatus();
}

}  // namespace

std::vector<Cell> LatticeHeadingDirections(int32_t headings) {
  const int32_t m = headings / 8;
  std::vector<Cell> dirs;
  // Counter-clockwise around the square's border from (m, 0).
  for (int32_t y = 0; y < m; ++y) dirs.push_back({m, y});
  for (int32_t x = m; x > -m; --x) dirs.push_back({x, m});
  for (int32_t y = m; y > -m; --y) dirs.push_back({-m, y});
  for (int32_t x = -m; x < m; ++x) dirs.push_back({x, -m});
  for (int32_t y = -m; y < 0; ++y) dirs.push_back({m, y});
  return dirs;
}

std::vector<double> LatticeHeadingAngles(int32_t headings) {
  std::vector<double> angles;
  for (const Cell& d : LatticeHeadingDirections(headings)) {
    double a = std::atan2(static_cast<double>(d.y), static_cast<double>(d.x));
    if (a < 0.0) a += 2.0 * kPi;
    angles.push_back(a);
  }
  return angles;
}

absl::StatusOr<ControlSet> GenerateControlSet(const LatticeGeneratorOptions& options) {
  if (absl::Status s = Validate(options); !s.ok()) return s;
  const int32_t n = options.headings;
  const int32_t m = n / 8;
  const double radius = options.turning_radius_m / options.resolution_m;
  const double tolerance = 1.0 + options.length_tolerance;
  // Rings start one cell out: one-cell straight moves are what lets chains
  // of primitives reach the end points between longer ones
  // (docs/decisions.md, "Control sets").
  const double min_length = 1.0;
  const std::vector<double> angles = LatticeHeadingAngles(n);
  const std::vector<Cell> dirs = LatticeHeadingDirections(n);
  const bool omni = options.robot == LatticeRobot::kOmnidirectional;
  // Each direction's shortest lattice step.
  std::vector<Cell> steps;
  for (const Cell& d : dirs) {
    const int32_t g = std::gcd(std::abs(d.x), std::abs(d.y));
    steps.push_back({d.x / g, d.y / g});
  }

  Composition graph(n);
  std::vector<Orbit> orbits;
  // Ring k holds the end points whose distance from the origin is in
  // [min_length + k, min_length + k + 1).
  const int32_t max_ring = static_cast<int32_t>(std::ceil(6.0 * radius)) + 16;
  int32_t quiet_rings = 0;
  bool spans = false;
  for (int32_t ring = 0; ring <= max_ring; ++ring) {
    const double lo = min_length + ring;
    const double hi = lo + 1.0;
    std::vector<Candidate> candidates;
    const int32_t reach = static_cast<int32_t>(std::ceil(hi));
    for (int32_t h0 = 0; h0 <= m; ++h0) {
      for (int32_t y = -reach; y <= reach; ++y) {
        for (int32_t x = -reach; x <= reach; ++x) {
          const double d = std::hypot(x, y);
          if (d < lo - 1e-9 || d >= hi - 1e-9) continue;
          for (int32_t turn = -2 * m; turn <= 2 * m; ++turn) {
            Candidate c;
            c.h0 = h0;
            c.h1 = ((h0 + turn) % n + n) % n;
            c.dx = x;
            c.dy = y;
            Candidate curve;
            if (CurveTo(c, angles[c.h0], angles[c.h1], dirs[h0], radius, &curve)) {
              candidates.push_back(curve);
            }
          }
        }
      }
      if (!omni) continue;
      // Moves along a lattice direction other than the heading's (or along
      // it while turning), keeping the heading or turning by one.
      for (int32_t j = 0; j < n; ++j) {
        const bool along = j == h0 || j == (h0 + n / 2) % n;
        for (int32_t k = 1;; ++k) {
          const Cell e{steps[j].x * k, steps[j].y * k};
          const double d = std::hypot(e.x, e.y);
          if (d >= hi - 1e-9) break;
          if (d < lo - 1e-9) continue;
          for (int32_t turn = -1; turn <= 1; ++turn) {
            if (along && turn == 0) continue;
            Candidate c;
            c.shape = Candidate::Shape::kTranslation;
            c.h0 = h0;
            c.h1 = ((h0 + turn) % n + n) % n;
            c.dx = e.x;
            c.dy = e.y;
            c.length = d;
            candidates.push_back(c);
          }
        }
      }
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      return std::tie(a.length, a.h0, a.h1, a.dx, a.dy, a.shape) <
             std::tie(b.length, b.h0, b.h1, b.dx, b.dy, b.shape);
    });
    // One Dijkstra per start heading, redone after each addition.
    std::vector<bool> solved(m + 1, false);
    const double limit = candidates.empty() ? 0.0 : candidates.back().length * tolerance;
    bool added = false;
    for (const Candidate& c : candidates) {
      if (graph.Has(c.h0, Edge{c.dx, c.dy, c.h1, c.length})) continue;
      if (!solved[c.h0]) {
        graph.Solve(c.h0, limit);
        std::fill(solved.begin(), solved.end(), false);
        solved[c.h0] = true;
      }
      if (graph.Distance(c.dx, c.dy, c.h1) <= c.length * tolerance) continue;
      Orbit orbit = MakeOrbit(c, n);
      orbit.order = orbits.size();
      for (const auto& [h0, e] : orbit.edges) graph.Add(h0, e);
      orbits.push_back(std::move(orbit));
      std::fill(solved.begin(), solved.end(), false);
      added = true;
    }
    if (!spans) spans = Spans(graph, n);
    quiet_rings = added ? 0 : quiet_rings + 1;
    if (spans && quiet_rings >= options.stopping_threshold) break;
  }
  if (!spans) {
    return absl::InternalError(absl::StrFormat(
        "lattice generator: no spanning set within %d rings (radius %g cells)", max_ring, radius));
  }
  // The last pass: longest first, drop what the others compose.
  std::vector<size_t> by_length(orbits.size());
  std::iota(by_length.begin(), by_length.end(), 0);
  std::sort(by_length.begin(), by_length.end(), [&](size_t a, size_t b) {
    return std::tie(orbits[b].rep.length, orbits[b].order) <
           std::tie(orbits[a].rep.length, orbits[a].order);
  });
  std::vector<bool> kept(orbits.size(), true);
  for (size_t i : by_length) {
    const Orbit& o = orbits[i];
    for (const auto& [h0, e] : o.edges) graph.Remove(h0, e);
    graph.Solve(o.rep.h0, o.rep.length * tolerance);
    if (graph.Distance(o.rep.dx, o.rep.dy, o.rep.h1) <= o.rep.length * tolerance &&
        Spans(graph, n)) {
      kept[i] = false;
      continue;
    }
    for (const auto& [h0, e] : o.edges) graph.Add(h0, e);
  }

  ControlSet set;
  set.robot = options.robot;
  set.resolution_m = options.resolution_m;
  set.turning_radius_m = options.turning_radius_m;
  set.stopping_threshold = options.stopping_threshold;
  set.length_tolerance = options.length_tolerance;
  set.heading_angles = angles;
  for (size_t i = 0; i < orbits.size(); ++i) {
    if (!kept[i]) continue;
    const LatticePrimitive base = Build(orbits[i].rep, angles);
    for (const Symmetry& s : orbits[i].images) set.primitives.push_back(Transformed(base, s, angles));
  }
  const bool reverse = options.robot != LatticeRobot::kAckermann || options.reverse;
  if (reverse) {
    const size_t forward = set.primitives.size();
    for (size_t i = 0; i < forward; ++i) {
      const LatticePrimitive& p = set.primitives[i];
      // Sideways moves already go every way.
      if (p.radius == 0.0 && p.turns()) continue;
      if (p.radius == 0.0 && Cross(dirs[p.start_heading].x, dirs[p.start_heading].y, p.dx, p.dy) != 0) {
        continue;
      }
      LatticePrimitive back = p;
      back.reverse = true;
      back.dx = -p.dx;
      back.dy = -p.dy;
      for (Pose& q : back.poses) {
        q.x = -q.x;
        q.y = -q.y;
        if (q.x == 0.0) q.x = 0.0;  // no -0 in files
        if (q.y == 0.0) q.y = 0.0;
      }
      set.primitives.push_back(std::move(back));
    }
  }
  if (options.robot != LatticeRobot::kAckermann) {
    for (int32_t h = 0; h < n; ++h) {
      for (int32_t step : {1, -1}) {
        LatticePrimitive p;
        p.start_heading = h;
        p.end_heading = ((h + step) % n + n) % n;
        p.turn_in_place = true;
        p.left_turn = step > 0;
        const Pose from{0.0, 0.0, NormalizeAngle(angles[h])};
        const Pose to{0.0, 0.0, NormalizeAngle(angles[p.end_heading])};
        p.poses.push_back(from);
        AppendLinear(from, to, PiecesFor(0.0, NormalizeAngle(to.yaw - from.yaw)), &p.poses);
        set.primitives.push_back(std::move(p));
      }
    }
  }
  // Omnidirectional moves that go backwards relative to the heading.
  for (LatticePrimitive& p : set.primitives) {
    if (p.turn_in_place || p.radius != 0.0) continue;
    const Cell d = dirs[p.start_heading];
    if (static_cast<int64_t>(d.x) * p.dx + static_cast<int64_t>(d.y) * p.dy < 0) p.reverse = true;
  }
  set.name = absl::StrFormat("generated %s%s, %d headings, turning radius %g cells",
                             LatticeRobotName(options.robot),
                             options.robot == LatticeRobot::kAckermann && options.reverse
                                 ? " with reverse"
                                 : "",
                             n, radius);
  set.Index();
  return set;
}

}  // namespace pathd
