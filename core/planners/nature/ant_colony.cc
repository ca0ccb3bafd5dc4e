// Ant Colony System on the grid graph (ant_colony.h).
//
// The model, per Dorigo & Gambardella (1997) with the grid as the graph:
//  - Edges are (cell, move) pairs, directed, each with a pheromone value
//    tau (one float per cell and move; kAntColonyMaxCells bounds the table).
//  - Desirability eta(i -> j) = 1 / (step cost(i -> j) + h(j)), h the octile
//    (4-connected: Manhattan) distance from j to the goal: a lower bound of
//    the cost-to-go, since no move costs less than its length.
//  - An ant at i takes, with probability q0, the move maximising
//    tau^alpha * eta^beta (exploitation), otherwise one drawn with
//    probability proportional to it (biased exploration). Moves follow the
//    map's rule (no corner cutting) and never enter a cell the ant has
//    visited (its tabu list); an ant with no such move, or out of steps,
//    dies.
//  - Local update on every move taken: tau = (1 - xi) tau + xi tau0.
//  - Global update after every iteration, on the best-so-far path's moves
//    only: tau = (1 - rho) tau + rho / L_best.
// Before the ants a flood fill from the start decides whether the goal is
// reachable at all, so an unreachable goal is reported as NO_PATH (proved)
// and a reachable goal no ant found as what it is: the budget of ants and
// iterations ran out (EXPANSION_LIMIT with PlanResult::reason saying so).
// Expansions count the flood fill's cells plus every ant move.
#include "core/planners/nature/ant_colony.h"

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
#include "core/planners/planners.h"
#include "core/search/grid_planner.h"
#include "core/search/grid_view.h"
#include "core/search/checked_path.h"
#include "core/status_macros.h"

namespace pathd {

absl::Status ValidateAntColonyParams(const AntColonyParams& p) {
  auto bad = [](std::string_view name, const std::string& value,
                std::string_view rule) {
    return absl::InvalidArgumentError(
        absl::StrFormat("ant_colony.%s %s must be %s", name, value, rule));
  };
  auto num = [](double v) { return absl::StrFormat("%g", v); };
  if (p.ants < 1 || p.ants > 4096) {
    return bad("ants", absl::StrFormat("%d", p.ants), "in [1, 4096]");
  }
  if (p.iterations < 1 || p.iterations > 1000000) {
    return bad("iterations", absl::StrFormat("%d", p.iterations),
               "in [1, 1000000]");
  }
  if (p.stall_iterations < 0) {
    return bad("stall_iterations", absl::StrFormat("%d", p.stall_iterations),
               ">= 0");
  }
  if (!(p.alpha >= 0.0 && p.alpha <= 16.0)) {
    return bad("alpha", num(p.alpha), "in [0, 16]");
  }
  if (!(p.beta >= 0.0 && p.beta <= 16.0)) {
    return bad("beta", num(p.beta), "in [0, 16]");
  }
  if (!(p.rho > 0.0 && p.rho <= 1.0)) return bad("rho", num(p.rho), "in (0, 1]");
  if (!(p.xi > 0.0 && p.xi <= 1.0)) return bad("xi", num(p.xi), "in (0, 1]");
  if (!(p.q0 >= 0.0 && p.q0 <= 1.0)) return bad("q0", num(p.q0), "in [0, 1]");
  if (!(std::isfinite(p.tau0) && p.tau0 >= 0.0)) {
    return bad("tau0", num(p.tau0), "finite and >= 0 (0: the default)");
  }
  if (p.max_steps < 0) {
    return bad("max_steps", absl::StrFormat("%d", p.max_steps), ">= 0");
  }
  return absl::OkStatus();
}

namespace {

// SplitMix64 (Steele, Lea & Flood 2014): a fixed, portable sequence per
// seed, so a seed gives the same answer whatever the standard library.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }

 private:
  uint64_t state_;
};

// x^e, without pow() for the common exponents 0, 1 and 2.
double Power(double x, double e) {
  if (e == 1.0) return x;
  if (e == 2.0) return x * x;
  if (e == 0.0) return 1.0;
  return std::pow(x, e);
}

class AntColonyPlanner final : public GridPlanner {
 public:
  AntColonyPlanner()
      : GridPlanner(
            "ant_colony",
            PlannerTraits{
                .complete = false,
                .description =
                    "Ant Colony System (Dorigo & Gambardella 1997): ants "
                    "with pheromone evaporation and deposit; heuristic, "
                    "reports the iteration that found its best path"}) {}

 protected:
  absl::Status Validate(const Grid& grid,
                        const PlanRequest& request) const override {
    PATHD_RETURN_IF_ERROR(GridPlanner::Validate(grid, request));
    PATHD_RETURN_IF_ERROR(ValidateAntColonyParams(request.ant_colony));
    if (static_cast<int64_t>(grid.size()) > kAntColonyMaxCells) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "ant_colony keeps a pheromone value per cell and move: a map of %d "
          "cells needs %d MiB, above its cap of %d cells (64 MiB)",
          grid.size(), static_cast<int64_t>(grid.size()) * 32 / (1 << 20),
          kAntColonyMaxCells));
    }
    return absl::OkStatus();
  }

  absl::StatusOr<PlanResult> Search(const GridQuery& query) const override {
    const Grid& grid = query.grid;
    const PlanRequest& request = query.request;
    const StopCondition& stop = query.stop;
    const AntColonyParams& p = request.ant_colony;
    const internal::GridView view(grid, request.cost);
    const uint32_t start = view.Index(request.start.x, request.start.y);
    const uint32_t goal = view.Index(request.goal.x, request.goal.y);

    PlanResult result;
    AntColonyStats& stats = result.ant_colony.emplace();
    stats.best_cost = std::numeric_limits<double>::infinity();
    int64_t expansions = 0;
    auto finish_stopped = [&](PlanOutcome why) {
      result.outcome = why;
      result.expansions = expansions;
      stats.stopped_by = std::string(PlanOutcomeName(why));
      return result;
    };
    if (const PlanOutcome why = stop.Check(expansions); why != PlanOutcome::kFound) {
      return finish_stopped(why);
    }
    if (start == goal) {
      result.outcome = PlanOutcome::kFound;
      result.path = {request.start};
      stats.best_cost = 0.0;
      stats.stopped_by = "start is the goal";
      return result;
    }

    // The legal moves out of a cell (GridView's, so the map's move rule),
    // each with its pheromone slot 0..7 from its direction.
    struct Step {
      uint32_t to;
      int slot;
      double cost;
    };
    auto for_each_move = [&](uint32_t at, auto&& visit) {
      const Cell c = view.CellOf(at);
      view.ForEachNeighbor(c.x, c.y, [&](uint32_t to, int32_t nx, int32_t ny,
                                         double length) {
        const int slot = (ny - c.y + 1) * 3 + (nx - c.x + 1);  // 0..8, not 4
        visit(Step{to, slot < 4 ? slot : slot - 1, length * view.Factor(to)});
      });
    };

    // Reachability first (a flood fill over the same moves), so that "no
    // ant found it" is never mistaken for "there is none".
    {
      std::vector<uint8_t> seen(grid.size(), 0);
      std::vector<uint32_t> queue = {start};
      seen[start] = 1;
      bool reached = false;
      for (size_t head = 0; head < queue.size() && !reached; ++head) {
        if (const PlanOutcome why = stop.Check(++expansions);
            why != PlanOutcome::kFound) {
          return finish_stopped(why);
        }
        for_each_move(queue[head], [&](const Step& mv) {
          if (seen[mv.to]) return;
          seen[mv.to] = 1;
          if (mv.to == goal) reached = true;
          queue.push_back(mv.to);
        });
      }
      if (!reached) {
        result.outcome = PlanOutcome::kNoPath;
        result.expansions = expansions;
        stats.stopped_by = "goal unreachable (flood fill)";
        return result;
      }
    }

    const double h_start = GridDistance(request.start, request.goal,
                                        request.cost.connectivity);
    const double tau0 =
        p.tau0 > 0.0 ? p.tau0 : 1.0 / (p.ants * std::max(1.0, h_start));
    const int64_t max_steps =
        p.max_steps > 0 ? p.max_steps
                        : 4 * (int64_t{grid.width()} + grid.height());
    std::vector<float> tau(grid.size() * 8, static_cast<float>(tau0));
    // visited[c] == the current ant's number: c is on its tabu list.
    std::vector<uint32_t> visited(grid.size(), 0);
    uint32_t ant_number = 0;
    Random random(p.seed);

    std::vector<uint32_t> best_cells;
    std::vector<uint8_t> best_moves;
    std::vector<uint32_t> cells;
    std::vector<uint8_t> taken;
    std::vector<Step> options;
    std::vector<double> weights;
    int32_t since_improvement = 0;
    bool stopped = false;
    stats.stopped_by = "iterations";
    for (int32_t iteration = 1; iteration <= p.iterations; ++iteration) {
      stats.iterations_run = iteration;
      double iteration_best = std::numeric_limits<double>::infinity();
      std::vector<uint32_t> iteration_cells;
      std::vector<uint8_t> iteration_moves;
      for (int32_t ant = 0; ant < p.ants; ++ant) {
        if (++ant_number == 0) {
          // 2^32 ants (4096 x 1000000 is more): restart the stamps.
          std::fill(visited.begin(), visited.end(), 0);
          ant_number = 1;
        }
        cells.assign(1, start);
        taken.clear();
        visited[start] = ant_number;
        uint32_t at = start;
        double cost = 0.0;
        bool arrived = false;
        for (int64_t step = 0; step < max_steps; ++step) {
          if (const PlanOutcome why = stop.Check(++expansions);
              why != PlanOutcome::kFound) {
            // An anytime answer: the best path so far stands when there is
            // one; stopped_by says the search was cut short.
            if (best_cells.empty()) return finish_stopped(why);
            stats.stopped_by = std::string(PlanOutcomeName(why));
            stopped = true;
            break;
          }
          options.clear();
          weights.clear();
          for_each_move(at, [&](const Step& mv) {
            if (visited[mv.to] == ant_number) return;
            options.push_back(mv);
            const Cell to = view.CellOf(mv.to);
            const double h =
                GridDistance(to, request.goal, request.cost.connectivity);
            const double eta = 1.0 / (mv.cost + h);
            weights.push_back(Power(tau[size_t{at} * 8 + mv.slot], p.alpha) *
                              Power(eta, p.beta));
          });
          if (options.empty()) break;  // a dead end: the ant dies
          size_t pick = 0;
          if (random.Uniform() < p.q0) {
            for (size_t i = 1; i < options.size(); ++i) {
              if (weights[i] > weights[pick]) pick = i;
            }
          } else {
            double total = 0.0;
            for (double w : weights) total += w;
            double r = random.Uniform() * total;
            pick = options.size() - 1;  // rounding lands on the last
            for (size_t i = 0; i < options.size(); ++i) {
              r -= weights[i];
              if (r < 0.0) {
                pick = i;
                break;
              }
            }
          }
          const Step& mv = options[pick];
          float& edge = tau[size_t{at} * 8 + mv.slot];
          edge = static_cast<float>((1.0 - p.xi) * edge + p.xi * tau0);
          cost += mv.cost;
          taken.push_back(static_cast<uint8_t>(mv.slot));
          cells.push_back(mv.to);
          visited[mv.to] = ant_number;
          at = mv.to;
          if (at == goal) {
            arrived = true;
            break;
          }
        }
        if (stopped) break;  // cut short: not a death
        if (!arrived) {
          ++stats.ants_died;
          continue;
        }
        ++stats.ants_reached_goal;
        if (cost < iteration_best) {
          iteration_best = cost;
          iteration_cells = cells;
          iteration_moves = taken;
        }
      }
      if (iteration_best < stats.best_cost) {
        stats.best_cost = iteration_best;
        stats.best_iteration = iteration;
        best_cells = std::move(iteration_cells);
        best_moves = std::move(iteration_moves);
        since_improvement = 0;
      } else {
        ++since_improvement;
      }
      if (!best_cells.empty()) {
        const double deposit = 1.0 / stats.best_cost;
        for (size_t i = 0; i < best_moves.size(); ++i) {
          float& edge = tau[size_t{best_cells[i]} * 8 + best_moves[i]];
          edge = static_cast<float>((1.0 - p.rho) * edge + p.rho * deposit);
        }
      }
      if (stopped) break;
      if (p.stall_iterations > 0 && !best_cells.empty() &&
          since_improvement >= p.stall_iterations) {
        stats.stopped_by = "stalled";
        break;
      }
    }
    result.expansions = expansions;
    if (best_cells.empty()) {
      result.outcome = PlanOutcome::kExpansionLimit;
      result.reason = absl::StrFormat(
          "ant_colony: none of the %d ants of %d iterations reached the goal "
          "(%d died at dead ends or after %d steps); the goal is reachable "
          "(a flood fill from the start reaches it): more ants, iterations "
          "or max_steps may find it",
          p.ants, stats.iterations_run, stats.ants_died, max_steps);
      return result;
    }
    result.outcome = PlanOutcome::kFound;
    result.path.reserve(best_cells.size());
    for (uint32_t c : best_cells) result.path.push_back(view.CellOf(c));
    PATHD_RETURN_IF_ERROR(MeasureAssembledPath(grid, request.cost, "ant_colony", &result));
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeAntColonyPlanner() {
  return std::make_unique<AntColonyPlanner>();
}

}  // namespace pathd
