// Request builders the gRPC tests share (in process and end to end): a
// position by cell or by world coordinates, and a Plan request between two
// cells.
#ifndef PATHD_TESTS_TESTING_REQUESTS_H_
#define PATHD_TESTS_TESTING_REQUESTS_H_

#include <string>

#include "pathd/v1/planner_service.pb.h"

namespace pathd::testing {

inline v1::Position CellPos(int x, int y) {
  v1::Position p;
  p.mutable_cell()->set_x(x);
  p.mutable_cell()->set_y(y);
  return p;
}

inline v1::Position WorldPos(double x, double y) {
  v1::Position p;
  p.mutable_world()->set_x(x);
  p.mutable_world()->set_y(y);
  return p;
}

// From cell (sx, sy) to cell (gx, gy) on `map`.
inline v1::PlanRequest PlanBetween(const std::string& map, int sx, int sy, int gx,
                                   int gy, v1::Planner planner = v1::PLANNER_ASTAR) {
  v1::PlanRequest request;
  request.set_map(map);
  request.set_planner(planner);
  *request.mutable_start() = CellPos(sx, sy);
  *request.mutable_goal() = CellPos(gx, gy);
  return request;
}

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_REQUESTS_H_
