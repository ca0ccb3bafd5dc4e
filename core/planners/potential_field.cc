// Artificial potential field planner (Khatib, "Real-Time Obstacle Avoidance for
// Manipulators and Mobile Robots", IJRR 1986), with the combined
// quadratic/conic attractive and the repulsive potential of Choset et al.,
// "Principles of Robot Motion" (2005), ch. 4: normalised gradient descent on
// U = U_att + U_rep in continuous cell coordinates. Heuristic and incomplete:
// the descent can stall in a local minimum (a concave obstacle facing the
// goal), which is reported as such. Cell costs only matter as blocked or not;
// the path found is measured under the cost model.
//
// Per query the obstacle distance costs one exact distance transform of the
// map (core/map/euclidean_distance.h), O(cells) but bounded by the influence
// distance: about 1 ms on a 512 x 512 map.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/search/checked_path.h"
#include "core/search/path_measure.h"
#include "core/search/endpoints.h"
#include "core/search/grid_planner.h"
#include "core/map/euclidean_distance.h"
#include "core/search/line_of_sight.h"
#include "core/planners/planners.h"
#include "core/search/grid_view.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

// Hard ceiling on descent steps whatever max_steps says, so a tiny step size
// cannot grow the trajectory (16 bytes a step) without bound: 64 MiB.
constexpr int64_t kStepCeiling = int64_t{1} << 22;
// A step that would enter a blocked cell is halved up to this many times
// (down to 1/64 of step_size) before the descent counts as stuck.
constexpr int kMaxHalvings = 6;
// Local-minimum detection: the descent is stuck when the potential has not
// dropped below its best value for this many cells of travel (at least
// kMinStallSteps steps). Near a minimum a fixed-length step overshoots and
// the walk settles into a short cycle, so the potential stops improving.
constexpr double kStallTravel = 8.0;
constexpr int64_t kMinStallSteps = 24;
// Gradients shorter than this have no direction to follow.
constexpr double kFlatGradient = 1e-12;

// D(q): distance from a point to the nearest obstacle. Obstacles are the cells
// not traversable under the request and the ring of cells just outside the
// map, so the repulsion also keeps the robot inside it. D is the exact
// centre-to-centre distance at cell centres (a free cell beside a wall has
// D = 1), bilinearly interpolated between the four centres around q; its
// gradient is the interpolant's. Inside a traversable cell D >= 1/4 (q's own
// centre, with D >= 1, has weight >= 1/4), so 1/D stays finite.
class ObstacleDistance {
 public:
  // Distances beyond `influence` only need to be known to exceed it.
  ObstacleDistance(const Grid& grid, const CostParams& cost, double influence)
      : width_(grid.width()), height_(grid.height()), far_(influence + 2.0) {
    DistanceSources sources;
    for (int c = 0; c < 256; ++c) {
      sources.by_cost[c] =
          !Traversable(static_cast<uint8_t>(c), cost.unknown_is_free);
    }
    sources.border = true;
    // A bounded transform is exact up to far_. If a corner of q's square were
    // beyond it, every corner (within sqrt(2) of it) is beyond influence, so
    // both the true and the stand-in interpolant exceed influence and the
    // repulsion is zero either way.
    const double bound = std::ceil(far_ * far_);
    squared_ = &transform_.Compute(
        grid, sources,
        bound >= 1e15 ? EuclideanDistanceField::kFar : static_cast<int64_t>(bound));
  }
  // Holds a pointer into its own transform.
  ObstacleDistance(const ObstacleDistance&) = delete;
  ObstacleDistance& operator=(const ObstacleDistance&) = delete;

  struct Sample {
    double d;
    double dx;
    double dy;
  };

  Sample At(CellPoint q) const {
    // Cell centres sit at integer + 1/2; (i, j) is the lower-left centre.
    const double u = q.x - 0.5;
    const double v = q.y - 0.5;
    const double fi = std::floor(u);
    const double fj = std::floor(v);
    const double fx = u - fi;
    const double fy = v - fj;
    const auto i = static_cast<int32_t>(fi);
    const auto j = static_cast<int32_t>(fj);
    const double d00 = Centre(i, j);
    const double d10 = Centre(i + 1, j);
    const double d01 = Centre(i, j + 1);
    const double d11 = Centre(i + 1, j + 1);
    Sample s;
    s.d = (1 - fx) * (1 - fy) * d00 + fx * (1 - fy) * d10 +
          (1 - fx) * fy * d01 + fx * fy * d11;
    s.dx = (1 - fy) * (d10 - d00) + fy * (d11 - d01);
    s.dy = (1 - fx) * (d01 - d00) + fx * (d11 - d10);
    return s;
  }

 private:
  // D at the centre of cell (x, y), for x in -1..width and y in -1..height.
  double Centre(int32_t x, int32_t y) const {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return 0.0;  // the ring
    const int64_t sq =
        (*squared_)[static_cast<size_t>(y) * static_cast<size_t>(width_) +
                    static_cast<size_t>(x)];
    return sq == EuclideanDistanceField::kFar ? far_
                                         : std::sqrt(static_cast<double>(sq));
  }

  int32_t width_;
  int32_t height_;
  double far_;
  EuclideanDistanceField transform_;
  const std::vector<int64_t>* squared_;
};

// U(q) and its gradient.
struct FieldSample {
  double u;
  double gx;
  double gy;
};

class PotentialField {
 public:
  PotentialField(const PotentialFieldParams& params, CellPoint goal,
                 const ObstacleDistance& obstacles)
      : p_(params), goal_(goal), obstacles_(obstacles) {}

  FieldSample At(CellPoint q) const {
    FieldSample f{0.0, 0.0, 0.0};
    // Attractive. Quadratic near the goal and conic beyond switch_distance,
    // continuous in value and gradient at the switch; the conic form alone
    // pulls with constant strength.
    const double ex = q.x - goal_.x;
    const double ey = q.y - goal_.y;
    const double d = std::hypot(ex, ey);
    const double k = p_.attractive_gain;
    if (p_.attractive == AttractiveShape::kQuadratic &&
        d <= p_.switch_distance) {
      f.u = 0.5 * k * d * d;
      f.gx = k * ex;
      f.gy = k * ey;
    } else if (d > 0.0) {
      // Conic pull of strength k * scale.
      const double scale = p_.attractive == AttractiveShape::kQuadratic
                               ? p_.switch_distance
                               : 1.0;
      f.u = p_.attractive == AttractiveShape::kQuadratic
                ? scale * k * d - 0.5 * k * scale * scale
                : k * d;
      f.gx = scale * k * ex / d;
      f.gy = scale * k * ey / d;
    }
    // Repulsive: 1/2 eta (1/D - 1/Q*)^2 within Q*, whose gradient is
    // -eta (1/D - 1/Q*) / D^2 grad D.
    const ObstacleDistance::Sample o = obstacles_.At(q);
    const double influence = p_.influence_distance;
    if (o.d < influence) {
      const double excess = 1.0 / o.d - 1.0 / influence;
      f.u += 0.5 * p_.repulsive_gain * excess * excess;
      const double slope = -p_.repulsive_gain * excess / (o.d * o.d);
      f.gx += slope * o.dx;
      f.gy += slope * o.dy;
    }
    return f;
  }

 private:
  const PotentialFieldParams& p_;
  CellPoint goal_;
  const ObstacleDistance& obstacles_;
};

Cell CellOf(CellPoint p) {
  return Cell{static_cast<int32_t>(std::floor(p.x)),
              static_cast<int32_t>(std::floor(p.y))};
}

// The cells the trajectory passes through as a path of legal moves. First the
// supercover of each segment (ForEachCellOnSegment), where consecutive cells
// share an edge; where a segment crosses exactly through a corner the two
// side cells are only touched (and were checked traversable), so 8-connected
// the chain takes the diagonal, 4-connected it goes through the first side
// cell. Loops the trajectory makes (oscillation, detours that come back) are
// erased, keeping the path simple; `scratch` remembers each cell's position
// in the chain. Last, 8-connected, staircase corners become diagonal moves.
std::vector<Cell> CellChain(const Grid& grid,
                            const std::vector<CellPoint>& trajectory,
                            const CostParams& cost, SearchScratch& scratch) {
  const Connectivity connectivity = cost.connectivity;
  scratch.BeginSearch(grid.size());
  std::vector<Cell> chain;
  auto append = [&](Cell c) {
    const size_t index = grid.Index(c);
    if (scratch.Seen(index) &&
        scratch.Raw(index).parent != SearchScratch::kNoParent) {
      // Back at a cell already on the chain: cut the loop.
      const size_t keep = scratch.Raw(index).parent + size_t{1};
      for (size_t i = keep; i < chain.size(); ++i) {
        scratch.Raw(grid.Index(chain[i])).parent = SearchScratch::kNoParent;
      }
      chain.resize(keep);
      return;
    }
    scratch.At(index).parent = static_cast<uint32_t>(chain.size());
    chain.push_back(c);
  };
  append(CellOf(trajectory.front()));
  for (size_t s = 1; s < trajectory.size(); ++s) {
    ForEachCellOnSegment(
        trajectory[s - 1], trajectory[s],
        [&](int32_t x, int32_t y, bool corner_only) {
          const Cell c{x, y};
          const Cell last = chain.back();
          if (c == last) return true;
          if (corner_only) {
            const bool edge_neighbour =
                std::abs(c.x - last.x) + std::abs(c.y - last.y) == 1;
            if (connectivity == Connectivity::kEight || !edge_neighbour) {
              return true;
            }
          }
          append(c);
          return true;
        });
  }
  if (connectivity == Connectivity::kFour) return chain;
  // 8-connected: where the chain turns a corner A -> B -> C with A and C
  // diagonal neighbours, the diagonal A -> C is legal when the other side
  // cell is traversable too (B is); taking it follows the trajectory's
  // length instead of a staircase. Every kept cell is still one the
  // trajectory passes through.
  std::vector<Cell> path;
  path.reserve(chain.size());
  for (const Cell& c : chain) {
    const size_t n = path.size();
    if (n >= 2) {
      const Cell a = path[n - 2];
      const Cell b = path[n - 1];
      if (std::abs(c.x - a.x) == 1 && std::abs(c.y - a.y) == 1) {
        // The side cells of a -> c are b and the cell opposite b.
        const Cell other{a.x + c.x - b.x, a.y + c.y - b.y};
        if (grid.InBounds(other) &&
            Traversable(grid.cost(other), cost.unknown_is_free)) {
          path.back() = c;
          continue;
        }
      }
    }
    path.push_back(c);
  }
  return path;
}

class PotentialFieldPlanner final : public GridPlanner {
 public:
  PotentialFieldPlanner()
      : GridPlanner("potential_field",
                    PlannerTraits{
                        .complete = false,
                        .description =
                            "artificial potential field: gradient descent on goal "
                            "attraction plus obstacle repulsion; heuristic, may "
                            "stop in a local minimum"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& query) const override {
    [[maybe_unused]] const Grid& grid = query.grid;
    [[maybe_unused]] const PlanRequest& request = query.request;
    [[maybe_unused]] const StopCondition& stop = query.stop;
    [[maybe_unused]] SearchScratch& scratch = query.scratch;
    const PotentialFieldParams& params = request.potential;
    const internal::GridView view(grid, request.cost);
    const ObstacleDistance obstacles(grid, request.cost,
                                     params.influence_distance);
    const CellPoint goal_point{request.goal.x + 0.5, request.goal.y + 0.5};
    const PotentialField field(params, goal_point, obstacles);

    const double step = params.step_size;
    const double window_steps = std::ceil(kStallTravel / step);
    const int64_t stall_window =
        window_steps >= static_cast<double>(kStepCeiling)
            ? kStepCeiling
            : std::max(kMinStallSteps, static_cast<int64_t>(window_steps));
    int64_t max_steps = params.max_steps;
    if (max_steps == 0) {
      // Room to cross the map four times, and on small maps enough steps for
      // the stall test to see a local minimum before the limit cuts in.
      const double default_steps = std::max(
          std::ceil(4.0 * static_cast<double>(grid.width() + grid.height()) / step),
          8.0 * static_cast<double>(stall_window));
      max_steps = default_steps >= static_cast<double>(kStepCeiling)
                      ? kStepCeiling
                      : static_cast<int64_t>(default_steps);
    }
    max_steps = std::min(max_steps, kStepCeiling);

    // A segment is clear when every cell it meets, including cells touched
    // only at a corner, is on the map and traversable: no corner cutting.
    auto clear = [&](CellPoint a, CellPoint b) {
      return ForEachCellOnSegment(a, b, [&](int32_t x, int32_t y, bool) {
        return view.Passable(x, y);
      });
    };

    PlanResult result;
    CellPoint q{request.start.x + 0.5, request.start.y + 0.5};
    result.trajectory.push_back(q);
    FieldSample here = field.At(q);
    double best_u = here.u;
    CellPoint best_q = q;
    int64_t best_step = 0;
    int64_t steps = 0;
    while (true) {
      if (CellOf(q) == request.goal) {
        // A step can end exactly on the goal cell's left or lower edge,
        // which floor() counts as inside the goal cell but which the step's
        // supercover only touches; finishing at the centre makes the cell
        // chain, and so the path, end in the goal cell.
        if (q.x != goal_point.x || q.y != goal_point.y) {
          result.trajectory.push_back(goal_point);
        }
        result.outcome = PlanOutcome::kFound;
        break;
      }
      if (steps >= max_steps) {
        result.outcome = PlanOutcome::kExpansionLimit;
        break;
      }
      if (const PlanOutcome why = stop.Check(steps);
          why != PlanOutcome::kFound) {
        result.outcome = why;
        break;
      }
      // Final approach. Close to the goal the quadratic pull vanishes while
      // an obstacle or the map edge beside the goal still repels, so the
      // descent would stall next to a goal that borders an obstacle (the
      // "goal non-reachable with obstacles nearby" problem, Ge & Cui 2000).
      // Within the influence distance, in line of sight, go straight there.
      if (std::hypot(q.x - goal_point.x, q.y - goal_point.y) <=
              params.influence_distance &&
          clear(q, goal_point)) {
        ++steps;
        q = goal_point;
        result.trajectory.push_back(q);
        continue;
      }
      if (steps - best_step >= stall_window) {
        result.outcome = PlanOutcome::kLocalMinimum;
        result.stall_point = best_q;
        break;
      }
      const double norm = std::hypot(here.gx, here.gy);
      if (!(norm > kFlatGradient)) {
        result.outcome = PlanOutcome::kLocalMinimum;
        result.stall_point = q;
        break;
      }
      ++steps;
      // Normalised step: the gradient's magnitude varies by orders of
      // magnitude near obstacles, its direction is what descent needs.
      const double ux = -here.gx / norm;
      const double uy = -here.gy / norm;
      bool moved = false;
      double length = step;
      for (int h = 0; h <= kMaxHalvings; ++h, length *= 0.5) {
        const CellPoint next{q.x + length * ux, q.y + length * uy};
        if (clear(q, next)) {
          q = next;
          moved = true;
          break;
        }
      }
      if (!moved) {
        result.outcome = PlanOutcome::kLocalMinimum;
        result.stall_point = q;
        break;
      }
      result.trajectory.push_back(q);
      here = field.At(q);
      if (here.u < best_u - 1e-12 * std::max(1.0, std::abs(best_u))) {
        best_u = here.u;
        best_q = q;
        best_step = steps;
      }
    }
    result.expansions = steps;

    if (result.found()) {
      result.path = CellChain(grid, result.trajectory, request.cost, scratch);
      PATHD_RETURN_IF_ERROR(
          MeasureAssembledPath(grid, request.cost, "potential_field", &result));
    }
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakePotentialFieldPlanner() {
  return std::make_unique<PotentialFieldPlanner>();
}

}  // namespace pathd
