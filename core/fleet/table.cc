// Cost tables: forward Dijkstra searches or backward cost-to-go fields.
#include "core/fleet/table.h"

#include <bit>
#include <cmath>
#include <limits>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/search/radix_heap.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

TableMethod ChooseTableMethod(size_t sources, size_t destinations) {
  return destinations <= sources ? TableMethod::kBackward : TableMethod::kForward;
}

ForwardDijkstra::ForwardDijkstra(const Grid& grid, const CostParams& cost)
    : grid_(grid), moves_(MoveCount(cost.connectivity)) {
  stride_ = static_cast<size_t>(grid.width()) + 2;
  const size_t padded = stride_ * (static_cast<size_t>(grid.height()) + 2);
  factor_.assign(padded, 0.0);
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const uint8_t c = grid.cost(x, y);
      if (Traversable(c, cost.unknown_is_free)) {
        factor_[Padded(Cell{x, y})] = CellFactor(c, cost.cost_weight);
      }
    }
  }
  dist_.assign(padded, kInf);
  length_.assign(padded, kInf);
  settled_.assign(padded, 0);
  target_.assign(padded, 0);
  const auto stride = static_cast<int64_t>(stride_);
  for (int k = 0; k < moves_; ++k) {
    offset_[k] = kMoves[k].dx + kMoves[k].dy * stride;
    step_[k] = kMoves[k].length;
    // A diagonal's two side cells; a straight move's "sides" are its
    // target cell again, so one test serves both.
    const bool diagonal = kMoves[k].dx != 0 && kMoves[k].dy != 0;
    side_a_[k] = diagonal ? kMoves[k].dx : offset_[k];
    side_b_[k] = diagonal ? kMoves[k].dy * stride : offset_[k];
  }
}

PlanOutcome ForwardDijkstra::Run(Cell source, absl::Span<const Cell> targets,
                                 double max_cost, const StopCondition& stop,
                                 int64_t* expansions) {
  for (const uint32_t i : touched_) {
    dist_[i] = kInf;
    length_[i] = kInf;
    settled_[i] = 0;
    target_[i] = 0;
  }
  touched_.clear();
  size_t targets_left = 0;
  for (const Cell t : targets) {
    const size_t i = Padded(t);
    if (target_[i] == 0) {
      target_[i] = 1;
      touched_.push_back(static_cast<uint32_t>(i));
      ++targets_left;
    }
  }
  // Keys never decrease (every move costs at least 1), so a radix heap over
  // the bits of the non-negative double costs, which order like the values
  // (core/search/radix_heap.h): 0.7-0.8x a binary heap's time in Dijkstra.
  internal::RadixHeap<uint32_t> open;
  const size_t start = Padded(source);
  dist_[start] = 0.0;
  length_[start] = 0.0;
  touched_.push_back(static_cast<uint32_t>(start));
  open.Push(std::bit_cast<uint64_t>(0.0), static_cast<uint32_t>(start));
  int64_t settled = 0;
  PlanOutcome outcome = PlanOutcome::kFound;
  while (!open.empty()) {
    const auto entry = open.Pop();
    const double g = std::bit_cast<double>(entry.key);
    const uint32_t u = entry.value;
    if (g > dist_[u]) continue;  // a stale entry: u was reached cheaper
    if (g > max_cost) break;
    settled_[u] = 1;
    ++settled;
    if (const PlanOutcome o = stop.Check(settled, g); o != PlanOutcome::kFound) {
      outcome = o;
      break;
    }
    if (target_[u] != 0 && --targets_left == 0) break;
    for (int k = 0; k < moves_; ++k) {
      const size_t v = static_cast<size_t>(static_cast<int64_t>(u) + offset_[k]);
      const double f = factor_[v];
      // Blocked or outside; a diagonal also needs both side cells free.
      if (f == 0.0 || factor_[u + side_a_[k]] == 0.0 || factor_[u + side_b_[k]] == 0.0) {
        continue;
      }
      const double nv = g + step_[k] * f;
      if (nv < dist_[v]) {
        if (dist_[v] == kInf) touched_.push_back(static_cast<uint32_t>(v));
        dist_[v] = nv;
        length_[v] = length_[u] + step_[k];
        open.Push(std::bit_cast<uint64_t>(nv), static_cast<uint32_t>(v));
      }
    }
  }
  *expansions = settled;
  return outcome;
}

double ForwardDijkstra::cost(Cell c) const {
  const size_t i = Padded(c);
  return settled_[i] != 0 ? dist_[i] : kInf;
}

double ForwardDijkstra::length(Cell c) const {
  const size_t i = Padded(c);
  return settled_[i] != 0 ? length_[i] : kInf;
}

CostField DijkstraFrom(const Grid& grid, const CostParams& cost, Cell source,
                       absl::Span<const Cell> targets, double max_cost,
                       const StopCondition& stop) {
  ForwardDijkstra search(grid, cost);
  CostField out;
  out.outcome = search.Run(source, targets, max_cost, stop, &out.expansions);
  out.cost.resize(grid.size());
  out.length.resize(grid.size());
  for (size_t i = 0; i < grid.size(); ++i) {
    const Cell c = grid.CellAt(i);
    out.cost[i] = search.cost(c);
    out.length[i] = search.length(c);
  }
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
    ForwardDijkstra search(*grid, cost);
    for (size_t i = 0; i < sources.size(); ++i) {
      int64_t expansions = 0;
      const PlanOutcome outcome = search.Run(sources[i], destinations, kInf, stop, &expansions);
      table.expansions += expansions;
      if (outcome != PlanOutcome::kFound) {
        table.outcome = outcome;
        return table;
      }
      for (size_t j = 0; j < destinations.size(); ++j) {
        const double c = search.cost(destinations[j]);
        if (!std::isfinite(c)) continue;
        table.entries[i * table.columns + j] =
            TableCell{true, c, search.length(destinations[j])};
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
