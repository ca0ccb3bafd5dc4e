// reaction_diffusion: path planning with an autowave, after the
// reaction-diffusion planners of Vazquez-Otero, Faigl and Munuzuri (as the
// lecture "Path Planning" closes with): a travelling front of a bistable
// reaction-diffusion medium is propagated over the free cells from the goal,
// each cell's arrival time is recorded, and the path descends the arrival
// time from the start. The medium is the Nagumo equation
//   du/dt = D lap(u) + k u (1 - u) (u - a),
// the lecture's FitzHugh-Nagumo model with its recovery variable held at
// rest (only the leading front matters for arrival times), written with
// the stable states 0 (free space, SS-) and 1 (excited, SS+) and the
// excitation threshold a. Heuristic: the front is a continuum wave on a
// lattice, so its arrival time is neither the grid's octile cost nor exact;
// the result reports how far it is from Dijkstra's exact cost-to-go.
#ifndef PATHD_CORE_PLANNERS_NATURE_REACTION_DIFFUSION_H_
#define PATHD_CORE_PLANNERS_NATURE_REACTION_DIFFUSION_H_

#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"
#include "core/search/stop_condition.h"

namespace pathd {

// INVALID_ARGUMENT naming the first bad parameter as "reaction_diffusion.NAME
// VALUE ..." (the server prefixes "options."): diffusion and reaction_rate
// finite and > 0, threshold in (0, 0.5), time_step finite and > 0 with
// time_step * (4 diffusion + reaction_rate) <= 1 (the explicit update's
// stability bound for the 5- and 9-point Laplacians), max_steps >= 0.
absl::Status ValidateReactionDiffusionParams(const ReactionDiffusionParams& params);

// The plane-wave speed of the Nagumo front, sqrt(D k / 2) (1 - 2 a), in cells
// per unit time on cells of factor 1.
double NagumoFrontSpeed(const ReactionDiffusionParams& params);

// The propagation phase on its own: the front from request.goal until it
// passes request.start (or dies out, or runs out of steps).
struct Autowave {
  // Row-major arrival time of the front (u crossing 1/2) per cell; 0 at the
  // goal, +infinity where it never arrived.
  std::vector<double> arrival;
  int64_t steps = 0;
  int64_t reached_cells = 0;
  // Cell updates made (PlanResult::expansions).
  int64_t expansions = 0;
  // Cells still changing when it ended (0: the front died out or settled).
  int64_t band_cells = 0;
  // kFound when it ran to its end (reached the start, died out or ran out
  // of steps), else the stop condition's outcome.
  PlanOutcome outcome = PlanOutcome::kFound;
};

// Precondition: the request passed ValidateRequest and
// ValidateReactionDiffusionParams.
Autowave PropagateAutowave(const Grid& grid, const PlanRequest& request,
                           const StopCondition& stop);

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_NATURE_REACTION_DIFFUSION_H_
