// The order in which to visit stops (OSRM's `trip`), from a matrix of
// pairwise costs that need not be symmetric (pathd's step cost depends on
// the cell entered): exact by Held-Karp dynamic programming (Held & Karp
// 1962) up to kMaxExactStops, otherwise a nearest-neighbour tour improved by
// 2-opt (Croes 1958) and Or-opt (Or 1976) moves, with the assignment-problem
// lower bound (the Hungarian method, Kuhn 1955) to say how far from optimal
// it may be. Pure functions; thread-compatible.
#ifndef PATHD_CORE_FLEET_TRIP_H_
#define PATHD_CORE_FLEET_TRIP_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace pathd {

// Most stops Held-Karp solves: O(2^n n^2) time and O(2^n n) memory, about
// 0.6 M steps and 50 k entries at 12.
inline constexpr size_t kMaxExactStops = 12;

enum class TripEnd { kRoundTrip, kFixedLast, kAny };

// costs[i][j]: the cost from stop i to stop j, +infinity when j cannot be
// reached from i. Square, n >= 2; the diagonal is ignored.
using CostMatrix = std::vector<std::vector<double>>;

struct TripOrder {
  // Stop indices in visiting order, order[0] == 0; a round trip does not
  // repeat 0 at the end; kFixedLast ends with n - 1.
  std::vector<int32_t> order;
  // The sum of the order's legs (and the leg back to 0 for a round trip).
  double cost = 0.0;
  // A lower bound on every order's cost: the optimum when exact.
  double lower_bound = 0.0;
  bool exact = false;
  // "held_karp" or "2opt_oropt"; the bound's "held_karp" or "assignment".
  std::string method;
  std::string bound_method;
};

// The cost of `order` under `end` (the legs between consecutive stops, plus
// the one back to order[0] for a round trip); +infinity when a leg is.
double TourCost(const CostMatrix& costs, const std::vector<int32_t>& order, TripEnd end);

// The best order Held-Karp finds (n <= kMaxExactStops) or the local search
// reaches (above). FAILED_PRECONDITION naming two stops when no order has a
// finite cost (some stop cannot be reached, or cannot reach the rest);
// INVALID_ARGUMENT for a matrix that is not square or has fewer than 2 stops.
absl::StatusOr<TripOrder> SolveTrip(const CostMatrix& costs, TripEnd end);

// Exact, for any n the caller can afford (tests call it above the limit).
absl::StatusOr<TripOrder> HeldKarp(const CostMatrix& costs, TripEnd end);
// The heuristic alone, for any n >= 2.
absl::StatusOr<TripOrder> LocalSearchTrip(const CostMatrix& costs, TripEnd end);

// The assignment bound: the cheapest way to give every stop one successor
// and one predecessor (a cycle cover, the tour's relaxation), on the matrix
// the trip's end turns into a cycle (kFixedLast: the leg last -> first is
// free and forced; kAny: a dummy stop, free to enter from any stop, leads
// to the first). +infinity when no cycle cover is finite.
double AssignmentBound(const CostMatrix& costs, TripEnd end);

}  // namespace pathd

#endif  // PATHD_CORE_FLEET_TRIP_H_
