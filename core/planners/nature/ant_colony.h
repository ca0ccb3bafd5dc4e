// ant_colony: Dorigo & Gambardella's Ant Colony System ("Ant colony system:
// a cooperative learning approach to the traveling salesman problem", IEEE
// Transactions on Evolutionary Computation, 1997) as a start-to-goal path
// search on the grid graph, as the lecture "Robot Navigation and collision
// avoidance" presents it. Heuristic: ants may miss a path that exists, and
// the best path found carries no bound on its excess over the optimum.
#ifndef PATHD_CORE_PLANNERS_NATURE_ANT_COLONY_H_
#define PATHD_CORE_PLANNERS_NATURE_ANT_COLONY_H_

#include <cstdint>

#include "absl/status/status.h"
#include "core/search/plan_types.h"

namespace pathd {

// The pheromone table holds one float per (cell, move): at most this many
// cells (64 MiB), larger maps are refused with FAILED_PRECONDITION.
inline constexpr int64_t kAntColonyMaxCells = int64_t{1} << 21;

// INVALID_ARGUMENT naming the first bad parameter as "ant_colony.NAME VALUE
// ..." (the server prefixes "options."): ants in [1, 4096], iterations in
// [1, 1000000], stall_iterations >= 0, alpha and beta finite in [0, 16], rho
// and xi in (0, 1], q0 in [0, 1], tau0 finite and >= 0, max_steps >= 0.
absl::Status ValidateAntColonyParams(const AntColonyParams& params);

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_NATURE_ANT_COLONY_H_
