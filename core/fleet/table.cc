// Cost tables: forward Dijkstra searches or backward cost-to-go fields.
#include "core/fleet/table.h"

#include <cmath>
#include <limits>
#include <queue>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

TableMethod ChooseTableMethod(size_t sources, size_t destinations) {
  return destinations <= sources ? TableMethod::kBackward : TableMethod::kForward;
}

CostField DijkstraFrom(const Grid& grid, const CostParams& cost, Cell source,
                       absl::Span<const Cell> targets, double max_cost,
                       const StopCondition& stop, int64_t expansions_before) {
  CostField out;
  const size_t n = grid.size();
  out.cost.assign(n, kInf);
  out.length.assign(n, kInf);
  std::vector<uint8_t> state(n, 0);  // 0 unseen, 1 open, 2 settled, bit 2: target
  size_t targets_left = 0;
  for (const Cell t : targets) {
    uint8_t& s = state[grid.Index(t)];
    if ((s & 4) == 0) {
      s |= 4;
      ++targets_left;
    }
  }
  using Entry = std::pair<double, size_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  const size_t start = grid.Index(source);
  out.cost[start] = 0.0;
  out.length[start] = 0.0;
  open.push({0.0, start});
  const int moves = MoveCount(cost.connectivity);
  const bool unknown_free = cost.unknown_is_free;
  const int32_t w = grid.width();
  const int32_t h = grid.height();
  auto free_at = [&](int32_t x, int32_t y) {
    return x >= 0 && y >= 0 && x < w && y < h && Traversable(grid.cost(x, y), unknown_free);
  };
  int64_t expansions = expansions_before;
  while (!open.empty()) {
    const auto [g, u] = open.top();
    open.pop();
    if ((state[u] & 3) == 2 || g > out.cost[u]) continue;
    if (g > max_cost) break;
    state[u] = static_cast<uint8_t>((state[u] & 4) | 2);
    ++expansions;
    if (const PlanOutcome o = stop.Check(expansions, g); o != PlanOutcome::kFound) {
      out.outcome = o;
      break;
    }
    if ((state[u] & 4) != 0 && --targets_left == 0) break;
    const Cell c = grid.CellAt(u);
    for (int k = 0; k < moves; ++k) {
      const Move& m = kMoves[k];
      const int32_t x = c.x + m.dx;
      const int32_t y = c.y + m.dy;
      if (!free_at(x, y)) continue;
      // No corner cutting: both side cells of a diagonal must be free.
      if (m.dx != 0 && m.dy != 0 && (!free_at(c.x + m.dx, c.y) || !free_at(c.x, c.y + m.dy))) {
        continue;
      }
      const size_t v = grid.Index(x, y);
      if ((state[v] & 3) == 2) continue;
      const double nv = g + m.length * CellFactor(grid.cost(x, y), cost.cost_weight);
      if (nv < out.cost[v]) {
        out.cost[v] = nv;
        out.length[v] = out.length[u] + m.length;
        state[v] = static_cast<uint8_t>((state[v] & 4) | 1);
        open.push({nv, v});
      }
    }
  }
  // Cells reached but not settled may hold a cost above the optimum.
  for (size_t i = 0; i < n; ++i) {
    if ((state[i] & 3) != 2) {
      out.cost[i] = kInf;
      out.length[i] = kInf;
    }
  }
  out.expansions = expansions - expansions_before;
  return out;
}

absl::StatusOr<CostTable> ComputeTable(std::shared_ptr<const Grid> grid,
                                       const CostParams& cost,
                                       absl::Span<const Cell> sources,
                                       absl::Span<const Cell> destinations,
                                       TableMethod method, const FieldProvider& fields,
                                       const StopCondition& stop) {
  CostTable table;
  table.rows = sources.size();
  table.columns = destinations.size();
  table.entries.assign(table.rows * table.columns, TableCell{});
  table.method = method == TableMethod::kAuto
                     ? ChooseTableMethod(sources.size(), destinations.size())
                     : method;
  if (table.method == TableMethod::kForward) {
    for (size_t i = 0; i < sources.size(); ++i) {
      const CostField field =
          DijkstraFrom(*grid, cost, sources[i], destinations, kInf, stop);
      table.expansions += field.expansions;
      if (field.outcome != PlanOutcome::kFound) {
        table.outcome = field.outcome;
        return table;
      }
      for (size_t j = 0; j < destinations.size(); ++j) {
        const size_t k = grid->Index(destinations[j]);
        if (!std::isfinite(field.cost[k])) continue;
        table.entries[i * table.columns + j] =
            TableCell{true, field.cost[k], field.length[k]};
      }
    }
    return table;
  }
  for (size_t j = 0; j < destinations.size(); ++j) {
    FieldLookup lookup;
    if (fields) {
      PATHD_ASSIGN_OR_RETURN(lookup, fields(destinations[j], stop));
    } else {
      absl::StatusOr<std::unique_ptr<ShortestPathMap>> built =
          ShortestPathMap::Build(grid, destinations[j], cost, stop);
      if (!built.ok()) {
        if (absl::IsDeadlineExceeded(built.status())) {
          lookup.outcome = PlanOutcome::kTimeout;
        } else if (absl::IsCancelled(built.status())) {
          lookup.outcome = PlanOutcome::kCancelled;
        } else if (absl::IsResourceExhausted(built.status())) {
          lookup.outcome = PlanOutcome::kExpansionLimit;
        } else {
          return built.status();
        }
      } else {
        lookup.expansions = (*built)->last_stats().expansions;
        lookup.field = std::move(*built);
      }
    }
    table.expansions += lookup.expansions;
    if (lookup.outcome != PlanOutcome::kFound) {
      table.outcome = lookup.outcome;
      return table;
    }
    if (lookup.cached) ++table.fields_cached;
    const ShortestPathMap& field = *lookup.field;
    for (size_t i = 0; i < sources.size(); ++i) {
      const float c = field.CostToGo(sources[i]);
      if (!std::isfinite(c)) continue;
      PATHD_ASSIGN_OR_RETURN(const PlanResult path, field.PathFrom(sources[i]));
      if (path.outcome != PlanOutcome::kFound) {
        return absl::InternalError(absl::StrFormat(
            "the field of destination %s has a finite cost at %s but no path",
            CellToString(destinations[j]), CellToString(sources[i])));
      }
      table.entries[i * table.columns + j] = TableCell{true, path.cost, path.length};
    }
  }
  return table;
}

}  // namespace pathd
