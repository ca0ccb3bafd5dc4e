// The reaction-diffusion planner (reaction_diffusion.h).
//
// Discretisation: explicit Euler in time (step dt) and, in space, the
// isotropic 9-point Laplacian (Patra & Karttunen 2006: 2/3 for each straight
// neighbour, 1/6 for each diagonal; 4-connected: the 5-point one) written as
// fluxes along the map's legal moves, so blocked cells, the map's edge and
// a corner between two blocked cells are no-flux walls: the front goes
// around obstacles as a robot must. Cell costs slow the medium: on a cell of
// factor s (what a move into it pays per unit length) D and k are divided
// by s (the flux between two cells by the mean of their factors), so the
// front crosses it s times slower and arrival time tracks cost, not length.
//
// Propagation phase only (the lecture's first phase): the goal is held at
// the excited state, every other free cell starts at rest, and the front
// spreads until it passes the start. A cell's arrival time T is when its u
// crosses 1/2 (interpolated within the step). The path descends T from the
// start, each move to the neighbour with the steepest drop of T per unit of
// move cost, out of the lattice's shallow pits in T by the lowest unvisited
// neighbour (counted as escapes).
//
// Only the band around the front is updated: a cell wakes when a neighbour
// carries activator, and leaves the band when it and its neighbours are
// settled (all excited: frozen; all at rest: asleep), so a step costs the
// band's size, not the map's. Expansions count cell updates.
//
// The comparison with the exact wave front: Dijkstra's cost-to-go from the
// goal (cost_to_go.h) on the same costs, against front_speed * T, over the
// reached cells; and the path's cost against the optimum.
#include "core/planners/nature/reaction_diffusion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/map/cost_model.h"
#include "core/planners/cost_to_go.h"
#include "core/planners/planners.h"
#include "core/search/grid_planner.h"
#include "core/search/grid_view.h"
#include "core/search/checked_path.h"
#include "core/status_macros.h"

namespace pathd {

absl::Status ValidateReactionDiffusionParams(const ReactionDiffusionParams& p) {
  auto bad = [](std::string_view name, double value, std::string_view rule) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "reaction_diffusion.%s %g must be %s", name, value, rule));
  };
  if (!(std::isfinite(p.diffusion) && p.diffusion > 0.0)) {
    return bad("diffusion", p.diffusion, "finite and > 0");
  }
  if (!(std::isfinite(p.reaction_rate) && p.reaction_rate > 0.0)) {
    return bad("reaction_rate", p.reaction_rate, "finite and > 0");
  }
  if (!(p.threshold > 0.0 && p.threshold < 0.5)) {
    return bad("threshold", p.threshold,
               "in (0, 0.5) (at 0.5 and above the front does not advance)");
  }
  if (!(std::isfinite(p.time_step) && p.time_step > 0.0)) {
    return bad("time_step", p.time_step, "finite and > 0");
  }
  const double bound = 1.0 / (4.0 * p.diffusion + p.reaction_rate);
  if (p.time_step > bound) {
    return bad("time_step", p.time_step,
               absl::StrFormat("<= 1 / (4 diffusion + reaction_rate) = %g for "
                               "a stable explicit update",
                               bound));
  }
  if (p.max_steps < 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "reaction_diffusion.max_steps %d must be >= 0", p.max_steps));
  }
  return absl::OkStatus();
}

double NagumoFrontSpeed(const ReactionDiffusionParams& p) {
  return std::sqrt(p.diffusion * p.reaction_rate / 2.0) * (1.0 - 2.0 * p.threshold);
}

namespace {

// A cell leaves the band frozen when it and its neighbours are within this
// of the excited state, asleep when within kRest of rest. The activator ahead
// of the front decays like exp(-x / 2) at the defaults, so kRest sets how far
// ahead the band reaches: 1e-4 is 18 cells, 1e-9 was 41 for the same arrival
// times to three decimals (nature_bench) and 43% more cell updates.
constexpr double kExcited = 1.0 - 1e-4;
constexpr double kRest = 1e-4;

enum CellState : uint8_t { kDormant = 0, kActive = 1, kFrozen = 2 };

}  // namespace

Autowave PropagateAutowave(const Grid& grid, const PlanRequest& request,
                           const StopCondition& stop) {
  const ReactionDiffusionParams& p = request.reaction_diffusion;
  const internal::GridView view(grid, request.cost);
  const bool eight = request.cost.connectivity == Connectivity::kEight;
  const double w_straight = eight ? 2.0 / 3.0 : 1.0;
  const double w_diagonal = 1.0 / 6.0;
  const uint32_t start = view.Index(request.start.x, request.start.y);
  const uint32_t goal = view.Index(request.goal.x, request.goal.y);
  const double speed = NagumoFrontSpeed(p);
  const double dt = p.time_step;
  const double inf = std::numeric_limits<double>::infinity();
  const size_t n = grid.size();

  Autowave wave;
  std::vector<double>& arrival = wave.arrival;
  arrival.assign(n, inf);
  std::vector<double> u(n, 0.0);
  std::vector<uint8_t> state(n, kDormant);
  std::vector<uint32_t> band;
  std::vector<uint32_t> next_band;
  std::vector<double> next_u;
  if (const PlanOutcome why = stop.Check(0); why != PlanOutcome::kFound) {
    wave.outcome = why;
    return wave;
  }
  // The source: held excited (SS+) for the whole run.
  u[goal] = 1.0;
  arrival[goal] = 0.0;
  state[goal] = kFrozen;
  wave.reached_cells = 1;
  auto wake_around = [&](uint32_t at, std::vector<uint32_t>& into) {
    const Cell c = view.CellOf(at);
    view.ForEachNeighbor(c.x, c.y, [&](uint32_t j, int32_t, int32_t, double) {
      if (state[j] != kDormant) return;
      state[j] = kActive;
      into.push_back(j);
    });
  };
  wake_around(goal, band);

  int64_t max_steps = p.max_steps;
  if (max_steps == 0) {
    // Time for the front to cover every free cell one after another (the
    // longest corridor there can be) at its slowest, four times over.
    double free_cells = 0.0;
    double slowest = 1.0;
    for (uint32_t i = 0; i < n; ++i) {
      if (!view.PassableAt(i)) continue;
      free_cells += 1.0;
      slowest = std::max(slowest, view.Factor(i));
    }
    const double steps = std::ceil(4.0 * (free_cells + grid.width() + grid.height()) *
                                   slowest / (speed * dt));
    max_steps = steps >= 9e18 ? std::numeric_limits<int64_t>::max()
                              : static_cast<int64_t>(steps);
  }

  while (!band.empty() && arrival[start] == inf && wave.steps < max_steps) {
    ++wave.steps;
    next_u.resize(band.size());
    for (size_t b = 0; b < band.size(); ++b) {
      if (const PlanOutcome why = stop.Check(++wave.expansions);
          why != PlanOutcome::kFound) {
        wave.outcome = why;
        wave.band_cells = static_cast<int64_t>(band.size());
        return wave;
      }
      const uint32_t i = band[b];
      const Cell c = view.CellOf(i);
      const double ui = u[i];
      const double si = view.Factor(i);
      double flux = 0.0;
      view.ForEachNeighbor(c.x, c.y, [&](uint32_t j, int32_t, int32_t, double length) {
        const double w = length == 1.0 ? w_straight : w_diagonal;
        flux += w * 2.0 / (si + view.Factor(j)) * (u[j] - ui);
      });
      const double reaction = p.reaction_rate / si * ui * (1.0 - ui) * (ui - p.threshold);
      next_u[b] = ui + dt * (p.diffusion * flux + reaction);
    }
    const double t_before = static_cast<double>(wave.steps - 1) * dt;
    for (size_t b = 0; b < band.size(); ++b) {
      const uint32_t i = band[b];
      const double before = u[i];
      u[i] = next_u[b];
      if (arrival[i] == inf && before < 0.5 && u[i] >= 0.5) {
        arrival[i] = t_before + dt * (0.5 - before) / (u[i] - before);
        ++wave.reached_cells;
      }
    }
    next_band.clear();
    for (const uint32_t i : band) {
      const Cell c = view.CellOf(i);
      bool all_excited = u[i] >= kExcited;
      bool all_rest = u[i] < kRest;
      view.ForEachNeighbor(c.x, c.y, [&](uint32_t j, int32_t, int32_t, double) {
        all_excited = all_excited && u[j] >= kExcited;
        all_rest = all_rest && u[j] < kRest;
      });
      if (all_excited) {
        state[i] = kFrozen;
      } else if (all_rest) {
        state[i] = kDormant;
      } else {
        next_band.push_back(i);
      }
    }
    // Wake after every cell has been judged, so a cell woken here (u = 0)
    // is judged next step with its fresh neighbours.
    const size_t kept = next_band.size();
    for (size_t b = 0; b < kept; ++b) {
      if (u[next_band[b]] >= kRest) wake_around(next_band[b], next_band);
    }
    band.swap(next_band);
  }
  wave.band_cells = static_cast<int64_t>(band.size());
  return wave;
}

namespace {

class ReactionDiffusionPlanner final : public GridPlanner {
 public:
  ReactionDiffusionPlanner()
      : GridPlanner(
            "reaction_diffusion",
            PlannerTraits{
                .complete = false,
                .description =
                    "autowave of a bistable reaction-diffusion medium (Nagumo) "
                    "from the goal, path down its arrival time; heuristic, "
                    "reports its deviation from the exact wave front"}) {}

 protected:
  absl::Status Validate(const Grid& grid,
                        const PlanRequest& request) const override {
    PATHD_RETURN_IF_ERROR(GridPlanner::Validate(grid, request));
    return ValidateReactionDiffusionParams(request.reaction_diffusion);
  }

  absl::StatusOr<PlanResult> Search(const GridQuery& query) const override {
    const Grid& grid = query.grid;
    const PlanRequest& request = query.request;
    const StopCondition& stop = query.stop;
    const ReactionDiffusionParams& p = request.reaction_diffusion;
    const internal::GridView view(grid, request.cost);
    const uint32_t start = view.Index(request.start.x, request.start.y);
    const uint32_t goal = view.Index(request.goal.x, request.goal.y);
    const double speed = NagumoFrontSpeed(p);
    const double inf = std::numeric_limits<double>::infinity();
    const size_t n = grid.size();

    PlanResult result;
    ReactionDiffusionStats& stats = result.reaction_diffusion.emplace();
    stats.front_speed = speed;
    const Autowave wave = PropagateAutowave(grid, request, stop);
    const std::vector<double>& arrival = wave.arrival;
    stats.steps = wave.steps;
    stats.reached_cells = wave.reached_cells;
    result.expansions = wave.expansions;
    if (wave.outcome != PlanOutcome::kFound) {
      result.outcome = wave.outcome;
      return result;
    }

    // The exact wave front on the same costs. It is the yardstick, not part
    // of the search: its work is not counted and the expansion budget does
    // not apply to it; the deadline and cancellation do.
    const CostToGoField exact = DijkstraCostToGo(
        grid, request.goal, request.cost, stop.WithMaxExpansions(0), query.scratch);
    if (exact.outcome != PlanOutcome::kFound) {
      result.outcome = exact.outcome;
      return result;
    }
    stats.optimal_cost = exact.values[start];
    double error_sum = 0.0;
    int64_t error_count = 0;
    for (uint32_t i = 0; i < n; ++i) {
      if (i == goal || arrival[i] == inf) continue;
      const double d = exact.values[i];
      const double e = std::abs(speed * arrival[i] - d) / d;
      stats.max_relative_error = std::max(stats.max_relative_error, e);
      error_sum += e;
      ++error_count;
    }
    if (error_count > 0) stats.mean_relative_error = error_sum / error_count;

    if (arrival[start] == inf) {
      if (stats.optimal_cost == inf) {
        result.outcome = PlanOutcome::kNoPath;
      } else {
        result.outcome = PlanOutcome::kExpansionLimit;
        result.reason = absl::StrFormat(
            "reaction_diffusion: the front %s after %d steps and %d cells "
            "without reaching the start, which is reachable (optimal cost "
            "%.6g): %s",
            wave.band_cells == 0 ? "died out" : "was still travelling", stats.steps,
            stats.reached_cells, stats.optimal_cost,
            wave.band_cells == 0 ? "a lower threshold or a larger diffusion "
                           "coefficient keeps it going"
                         : "raise max_steps");
      }
      return result;
    }

    // Descent of the arrival time, never re-entering a cell. The lattice
    // leaves shallow pits in T (a cell in a corner, with fewer neighbours to
    // share activator with, fires a little before the cell the front came
    // through); from one the descent steps to the lowest unvisited reached
    // neighbour, climbing out over the pit's rim, and counts the step in
    // stats.escapes. Only a cell with no unvisited reached neighbour ends it.
    std::vector<Cell> path = {request.start};
    std::vector<uint8_t> visited(n, 0);
    uint32_t at = start;
    visited[at] = 1;
    while (at != goal) {
      const Cell c = view.CellOf(at);
      uint32_t best = at;
      double best_slope = 0.0;
      uint32_t lowest = at;
      view.ForEachNeighbor(c.x, c.y, [&](uint32_t j, int32_t, int32_t, double length) {
        if (visited[j] || arrival[j] == inf) return;
        if (lowest == at || arrival[j] < arrival[lowest]) lowest = j;
        if (!(arrival[j] < arrival[at])) return;
        const double slope = (arrival[at] - arrival[j]) / (length * view.Factor(j));
        if (slope > best_slope) {
          best_slope = slope;
          best = j;
        }
      });
      if (best == at) {
        if (lowest == at) {
          result.outcome = PlanOutcome::kLocalMinimum;
          result.stall_point = CellPoint{c.x + 0.5, c.y + 0.5};
          result.reason = absl::StrFormat(
              "reaction_diffusion: the arrival-time descent is stuck at %s (every "
              "neighbour reached by the front is on the path already)",
              CellToString(c));
          return result;
        }
        best = lowest;
        ++stats.escapes;
      }
      at = best;
      visited[at] = 1;
      path.push_back(view.CellOf(at));
    }
    result.outcome = PlanOutcome::kFound;
    result.path = std::move(path);
    PATHD_RETURN_IF_ERROR(
        MeasureAssembledPath(grid, request.cost, "reaction_diffusion", &result));
    stats.cost_ratio =
        stats.optimal_cost > 0.0 ? result.cost / stats.optimal_cost : 1.0;
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeReactionDiffusionPlanner() {
  return std::make_unique<ReactionDiffusionPlanner>();
}

}  // namespace pathd
