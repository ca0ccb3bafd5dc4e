// The move rule on given paths and path measurement.
#include "core/search/path_measure.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "core/geometry/free_space.h"
#include "core/search/grid_view.h"
#include "core/search/line_of_sight.h"

namespace pathd {

PathMeasure MeasureAnyAnglePath(const Grid& grid, const std::vector<Cell>& path,
                                const CostParams& cost) {
  PathMeasure m;
  if (path.empty()) return m;
  if (!grid.InBounds(path[0]) ||
      !Traversable(grid.cost(path[0]), cost.unknown_is_free)) {
    m.first_invalid = 0;
    return m;
  }
  for (size_t i = 1; i < path.size(); ++i) {
    if (!grid.InBounds(path[i]) || !LineOfSight(grid, path[i - 1], path[i], cost)) {
      m.first_invalid = i;
      return m;
    }
    m.length += SegmentLength(path[i - 1], path[i]);
    m.cost += SegmentCost(grid, path[i - 1], path[i], cost);
  }
  m.valid = true;
  return m;
}

PathMeasure MeasurePolyline(const Grid& grid,
                            const std::vector<CellPoint>& polyline,
                            const CostParams& cost) {
  PathMeasure m;
  if (polyline.empty()) return m;
  const FreeSpace space(grid, cost.unknown_is_free);
  std::vector<LatticePoint> points;
  points.reserve(polyline.size());
  for (size_t i = 0; i < polyline.size(); ++i) {
    const std::optional<LatticePoint> p = ToLatticePoint(polyline[i]);
    if (!p || (i == 0 ? !space.PointFree(*p)
                      : !space.SegmentClear(points.back(), *p))) {
      m.first_invalid = i;
      return m;
    }
    if (i > 0) {
      const double length = Distance(points.back(), *p);
      double factor = 1.0;
      space.ForEachCellCrossed(points.back(), *p, [&](Cell c) {
        if (grid.InBounds(c)) {
          factor = std::max(factor, CellFactor(grid.cost(c), cost.cost_weight));
        }
      });
      m.length += length;
      m.cost += length * factor;
    }
    points.push_back(*p);
  }
  m.valid = true;
  return m;
}

PathMeasure MeasurePosePath(const Grid& grid, const std::vector<PathPose>& poses,
                            const std::vector<Cell>& path, const CostParams& cost,
                            const MotionPenalties& penalties) {
  PathMeasure m;
  if (poses.empty()) return m;
  for (size_t i = 1; i < poses.size(); ++i) {
    const Pose& p = poses[i].pose;
    const Pose& q = poses[i - 1].pose;
    if (std::hypot(p.x - q.x, p.y - q.y) > 1.0 + 1e-9) {
      m.first_invalid = i;
      return m;
    }
  }
  const std::vector<Cell> cells = PathCells(poses);
  for (size_t i = 0; i < cells.size(); ++i) {
    if (i >= path.size() || !(path[i] == cells[i]) || !grid.InBounds(cells[i]) ||
        !Traversable(grid.cost(cells[i]), cost.unknown_is_free)) {
      m.first_invalid = i;
      return m;
    }
  }
  if (path.size() != cells.size()) {
    m.first_invalid = cells.size();
    return m;
  }
  m.valid = true;
  m.length = PathLength(poses);
  m.cost = PathCost(grid, poses, penalties);
  return m;
}

PathMeasure MeasureResultPath(const Grid& grid, const PlanResult& result,
                              const CostParams& cost) {
  if (!result.polyline.empty()) return MeasurePolyline(grid, result.polyline, cost);
  if (!result.poses.empty()) {
    KinematicQuery defaults;
    defaults.cost_penalty = cost.cost_weight;
    return MeasurePosePath(grid, result.poses, result.path, cost, PenaltiesOf(defaults));
  }
  return result.any_angle ? MeasureAnyAnglePath(grid, result.path, cost)
                          : MeasurePath(grid, result.path, cost);
}

std::string_view MoveFaultName(MoveFault fault) {
  switch (fault) {
    case MoveFault::kNone:
      return "legal";
    case MoveFault::kNotAdjacent:
      return "not adjacent";
    case MoveFault::kDiagonalOnFourConnected:
      return "diagonal on a 4-connected grid";
    case MoveFault::kCornerCut:
      return "cuts a corner";
  }
  return "unknown";
}

MoveFault CheckMove(const Grid& grid, Cell a, Cell b, const CostParams& cost) {
  return internal::MoveRule::Check(
      a, b, cost.connectivity, [&](int32_t x, int32_t y) {
        return grid.InBounds(x, y) &&
               Traversable(grid.cost(x, y), cost.unknown_is_free);
      });
}

PathMeasure MeasurePath(const Grid& grid, const std::vector<Cell>& path,
                        const CostParams& cost) {
  PathMeasure m;
  if (path.empty()) return m;
  auto ok_cell = [&](Cell c) {
    return grid.InBounds(c) && Traversable(grid.cost(c), cost.unknown_is_free);
  };
  if (!ok_cell(path[0])) {
    m.first_invalid = 0;
    return m;
  }
  for (size_t i = 1; i < path.size(); ++i) {
    const Cell a = path[i - 1];
    const Cell b = path[i];
    if (!ok_cell(b) || CheckMove(grid, a, b, cost) != MoveFault::kNone) {
      m.first_invalid = i;
      return m;
    }
    const double len = (a.x != b.x && a.y != b.y) ? kSqrt2 : 1.0;
    m.length += len;
    m.cost += len * CellFactor(grid.cost(b), cost.cost_weight);
  }
  m.valid = true;
  return m;
}

}  // namespace pathd
