// Trips: every end turned into one asymmetric travelling-salesman cycle over
// a "cycle matrix", then Held-Karp, or a nearest-neighbour tour with 2-opt and
// Or-opt moves, and the assignment bound.
#include "core/fleet/trip.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "absl/strings/str_format.h"

namespace pathd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The trip as a cycle through stop 0: kFixedLast forces last -> 0 at no cost,
// kAny adds a dummy stop m - 1 = n that any stop may enter free and that
// leads to 0 free. Infinite entries stay infinite.
CostMatrix CycleMatrix(const CostMatrix& costs, TripEnd end) {
  const size_t n = costs.size();
  const size_t m = end == TripEnd::kAny ? n + 1 : n;
  CostMatrix c(m, std::vector<double>(m, kInf));
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) {
      if (i != j) c[i][j] = costs[i][j];
    }
  }
  if (end == TripEnd::kFixedLast) {
    const size_t last = n - 1;
    for (size_t j = 0; j < n; ++j) c[last][j] = kInf;
    for (size_t i = 0; i < n; ++i) c[i][0] = kInf;
    c[last][0] = 0.0;
  } else if (end == TripEnd::kAny) {
    const size_t dummy = n;
    for (size_t i = 0; i < n; ++i) c[i][0] = kInf;
    for (size_t i = 1; i < n; ++i) c[i][dummy] = 0.0;
    c[dummy][0] = 0.0;
  }
  return c;
}

// The cycle's stops without the dummy of kAny.
std::vector<int32_t> StopsOnly(const std::vector<int32_t>& cycle, size_t n) {
  std::vector<int32_t> order;
  for (const int32_t s : cycle) {
    if (static_cast<size_t>(s) < n) order.push_back(s);
  }
  return order;
}

double CycleCost(const CostMatrix& c, const std::vector<int32_t>& cycle) {
  double sum = 0.0;
  for (size_t k = 0; k < cycle.size(); ++k) {
    sum += c[cycle[k]][cycle[(k + 1) % cycle.size()]];
  }
  return sum;
}

absl::Status CheckMatrix(const CostMatrix& costs) {
  if (costs.size() < 2) {
    return absl::InvalidArgumentError(
        absl::StrFormat("a trip needs at least 2 stops, not %d", costs.size()));
  }
  for (const auto& row : costs) {
    if (row.size() != costs.size()) {
      return absl::InvalidArgumentError("the cost matrix is not square");
    }
  }
  return absl::OkStatus();
}

// The first pair (i, j), i != j, with no finite cost, for the error.
absl::Status NoFiniteOrder(const CostMatrix& costs) {
  for (size_t i = 0; i < costs.size(); ++i) {
    for (size_t j = 0; j < costs.size(); ++j) {
      if (i != j && !std::isfinite(costs[i][j])) {
        return absl::FailedPreconditionError(absl::StrFormat(
            "no order visits every stop: stop %d cannot reach stop %d", i, j));
      }
    }
  }
  return absl::FailedPreconditionError("no order visits every stop at a finite cost");
}

// A finite stand-in for +infinity that no sum of finite entries reaches, so
// local search and the Hungarian method can compare infeasible choices.
double BigCost(const CostMatrix& c) {
  double sum = 0.0;
  for (const auto& row : c) {
    for (const double v : row) {
      if (std::isfinite(v)) sum += std::abs(v);
    }
  }
  return (sum + 1.0) * 4.0;
}

// The minimum-cost assignment (Kuhn's Hungarian method with potentials, in
// O(m^3)) of `a`, every entry finite.
double MinAssignment(const CostMatrix& a) {
  const size_t m = a.size();
  std::vector<double> u(m + 1, 0.0), v(m + 1, 0.0);
  std::vector<size_t> p(m + 1, 0), way(m + 1, 0);
  for (size_t i = 1; i <= m; ++i) {
    p[0] = i;
    size_t j0 = 0;
    std::vector<double> minv(m + 1, kInf);
    std::vector<bool> used(m + 1, false);
    do {
      used[j0] = true;
      const size_t i0 = p[j0];
      double delta = kInf;
      size_t j1 = 0;
      for (size_t j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double cur = a[i0 - 1][j - 1] - u[i0] - v[j];
        if (cur < minv[j]) {
          minv[j] = cur;
          way[j] = j0;
        }
        if (minv[j] < delta) {
          delta = minv[j];
          j1 = j;
        }
      }
      for (size_t j = 0; j <= m; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const size_t j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  double total = 0.0;
  for (size_t j = 1; j <= m; ++j) total += a[p[j] - 1][j - 1];
  return total;
}

}  // namespace

double TourCost(const CostMatrix& costs, const std::vector<int32_t>& order, TripEnd end) {
  double sum = 0.0;
  for (size_t k = 0; k + 1 < order.size(); ++k) sum += costs[order[k]][order[k + 1]];
  if (end == TripEnd::kRoundTrip && order.size() > 1) {
    sum += costs[order.back()][order.front()];
  }
  return sum;
}

double AssignmentBound(const CostMatrix& costs, TripEnd end) {
  CostMatrix c = CycleMatrix(costs, end);
  const double big = BigCost(c);
  for (auto& row : c) {
    for (double& v : row) {
      if (!std::isfinite(v)) v = big;
    }
  }
  const double bound = MinAssignment(c);
  return bound >= big ? kInf : bound;
}

absl::StatusOr<TripOrder> HeldKarp(const CostMatrix& costs, TripEnd end) {
  if (absl::Status s = CheckMatrix(costs); !s.ok()) return s;
  const size_t n = costs.size();
  const CostMatrix c = CycleMatrix(costs, end);
  const size_t m = c.size();
  if (m > 24) return absl::InvalidArgumentError("Held-Karp is limited to 24 stops");
  // dp[S][j]: cheapest path from 0 through the stops of S (bit k: stop k + 1)
  // ending at stop j + 1.
  const size_t k = m - 1;
  const size_t subsets = size_t{1} << k;
  std::vector<double> dp(subsets * k, kInf);
  std::vector<int8_t> parent(subsets * k, -1);
  for (size_t j = 0; j < k; ++j) dp[(size_t{1} << j) * k + j] = c[0][j + 1];
  for (size_t s = 1; s < subsets; ++s) {
    for (size_t j = 0; j < k; ++j) {
      if ((s & (size_t{1} << j)) == 0) continue;
      const double here = dp[s * k + j];
      if (!std::isfinite(here)) continue;
      for (size_t t = 0; t < k; ++t) {
        if ((s & (size_t{1} << t)) != 0) continue;
        const size_t next = s | (size_t{1} << t);
        const double cand = here + c[j + 1][t + 1];
        if (cand < dp[next * k + t]) {
          dp[next * k + t] = cand;
          parent[next * k + t] = static_cast<int8_t>(j);
        }
      }
    }
  }
  const size_t all = subsets - 1;
  double best = kInf;
  size_t best_j = 0;
  for (size_t j = 0; j < k; ++j) {
    const double cand = dp[all * k + j] + c[j + 1][0];
    if (cand < best) {
      best = cand;
      best_j = j;
    }
  }
  if (!std::isfinite(best)) return NoFiniteOrder(costs);
  std::vector<int32_t> cycle;
  size_t s = all;
  int j = static_cast<int>(best_j);
  while (j >= 0) {
    cycle.push_back(j + 1);
    const int pj = parent[s * k + static_cast<size_t>(j)];
    s &= ~(size_t{1} << j);
    j = pj;
  }
  cycle.push_back(0);
  std::reverse(cycle.begin(), cycle.end());
  TripOrder out;
  out.order = StopsOnly(cycle, n);
  out.cost = TourCost(costs, out.order, end);
  out.lower_bound = out.cost;
  out.exact = true;
  out.method = "held_karp";
  out.bound_method = "held_karp";
  return out;
}

absl::StatusOr<TripOrder> LocalSearchTrip(const CostMatrix& costs, TripEnd end) {
  if (absl::Status s = CheckMatrix(costs); !s.ok()) return s;
  const size_t n = costs.size();
  CostMatrix c = CycleMatrix(costs, end);
  const size_t m = c.size();
  const double big = BigCost(c);
  for (auto& row : c) {
    for (double& v : row) {
      if (!std::isfinite(v)) v = big;
    }
  }
  // Nearest neighbour from 0.
  std::vector<int32_t> tour{0};
  std::vector<bool> used(m, false);
  used[0] = true;
  for (size_t step = 1; step < m; ++step) {
    const int32_t from = tour.back();
    int32_t best = -1;
    for (size_t j = 0; j < m; ++j) {
      if (!used[j] && (best < 0 || c[from][j] < c[from][best])) best = static_cast<int32_t>(j);
    }
    used[best] = true;
    tour.push_back(best);
  }
  // Improve until no 2-opt or Or-opt move pays (first improvement), or a
  // generous cap on rounds.
  const auto at = [&](size_t pos) { return tour[pos % m]; };
  constexpr double kEps = 1e-9;
  for (int round = 0; round < 1000; ++round) {
    bool improved = false;
    // Prefix sums of the tour's edges forwards and backwards, so a reversed
    // segment's cost is O(1).
    std::vector<double> fwd(m, 0.0), bwd(m, 0.0);
    for (size_t t = 0; t + 1 < m; ++t) {
      fwd[t + 1] = fwd[t] + c[tour[t]][tour[t + 1]];
      bwd[t + 1] = bwd[t] + c[tour[t + 1]][tour[t]];
    }
    // 2-opt: reverse tour[i..j] (tour[0] stays first).
    for (size_t i = 1; i + 1 < m && !improved; ++i) {
      for (size_t j = i + 1; j < m; ++j) {
        const int32_t a = tour[i - 1], ti = tour[i], tj = tour[j], b = at(j + 1);
        const double before = c[a][ti] + (fwd[j] - fwd[i]) + c[tj][b];
        const double after = c[a][tj] + (bwd[j] - bwd[i]) + c[ti][b];
        if (after < before - kEps) {
          std::reverse(tour.begin() + static_cast<std::ptrdiff_t>(i),
                       tour.begin() + static_cast<std::ptrdiff_t>(j) + 1);
          improved = true;
          break;
        }
      }
    }
    if (improved) continue;
    // Or-opt: move a run of 1 to 3 stops elsewhere, keeping its direction.
    for (size_t len = 1; len <= 3 && !improved; ++len) {
      for (size_t i = 1; i + len <= m && !improved; ++i) {
        const size_t e = i + len - 1;
        const int32_t prev = tour[i - 1], s0 = tour[i], se = tour[e], next = at(e + 1);
        const double removed = c[prev][s0] + c[se][next] - c[prev][next];
        for (size_t p = 0; p < m; ++p) {
          if (p + 1 >= i && p <= e) continue;  // edges touching the run
          const int32_t x = tour[p], y = at(p + 1);
          const double added = c[x][s0] + c[se][y] - c[x][y];
          if (added < removed - kEps) {
            std::vector<int32_t> run(tour.begin() + static_cast<std::ptrdiff_t>(i),
                                     tour.begin() + static_cast<std::ptrdiff_t>(e) + 1);
            std::vector<int32_t> rest;
            rest.reserve(m);
            for (size_t t = 0; t < m; ++t) {
              if (t < i || t > e) rest.push_back(tour[t]);
            }
            // x's place in `rest`, then the run after it.
            const auto where = std::find(rest.begin(), rest.end(), x);
            rest.insert(where + 1, run.begin(), run.end());
            tour = std::move(rest);
            improved = true;
            break;
          }
        }
      }
    }
    if (!improved) break;
  }
  if (CycleCost(c, tour) >= big) return NoFiniteOrder(costs);
  TripOrder out;
  out.order = StopsOnly(tour, n);
  out.cost = TourCost(costs, out.order, end);
  out.lower_bound = AssignmentBound(costs, end);
  out.exact = false;
  out.method = "2opt_oropt";
  out.bound_method = "assignment";
  return out;
}

absl::StatusOr<TripOrder> SolveTrip(const CostMatrix& costs, TripEnd end) {
  if (costs.size() <= kMaxExactStops) return HeldKarp(costs, end);
  return LocalSearchTrip(costs, end);
}

}  // namespace pathd
