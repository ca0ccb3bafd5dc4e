// The last step of planners that assemble a path themselves (a descent, an
// ant's walk) rather than from a search's parent links: measure it and
// refuse an illegal move as the planner bug it would be.
#ifndef PATHD_CORE_SEARCH_CHECKED_PATH_H_
#define PATHD_CORE_SEARCH_CHECKED_PATH_H_

#include <string_view>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/path_measure.h"
#include "core/search/plan_types.h"

namespace pathd {

// Sets result->cost and result->length from MeasurePath(result->path);
// INTERNAL naming `planner` and the first bad cell when a move is illegal.
inline absl::Status MeasureAssembledPath(const Grid& grid, const CostParams& cost,
                                         std::string_view planner, PlanResult* result) {
  const PathMeasure measure = MeasurePath(grid, result->path, cost);
  if (!measure.valid) {
    return absl::InternalError(absl::StrFormat(
        "%s built an illegal move at path cell %d %s", planner, measure.first_invalid,
        CellToString(result->path[measure.first_invalid])));
  }
  result->cost = measure.cost;
  result->length = measure.length;
  return absl::OkStatus();
}

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_CHECKED_PATH_H_
