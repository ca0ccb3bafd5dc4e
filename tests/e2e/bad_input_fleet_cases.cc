// bad_input_test's rows for the fleet map queries: Table, Nearest, Trip and
// Isochrone, Plan's snap_start options, PlanFleet and fleet sessions. pathd
// runs with --max_table_entries=kMaxTableEntries, --max_trip_stops=
// kMaxTripStops and --max_fleet_robots=kMaxFleetRobots.
#include <utility>

#include "tests/e2e/bad_input_fixture.h"

namespace pathd::bad_input_test {

void BadInputTest::AddFleetCases(std::vector<Case>& cases) {
  const auto table_case = [&](const std::string& what,
                              std::function<void(v1::TableRequest&)> change, StatusCode code,
                              const std::string& message) {
    v1::TableRequest request;
    request.set_map("room");
    *request.add_sources() = CellPos(1, 1);
    *request.add_sources() = CellPos(2, 1);
    *request.add_destinations() = CellPos(14, 14);
    change(request);
    cases.push_back({"Table", what,
                     [=, this] {
                       v1::TableResponse response;
                       return planner_->Table(Context().get(), request, &response);
                     },
                     code, message});
  };
  using T = v1::TableRequest;
  table_case("no sources", [](T& r) { r.clear_sources(); }, StatusCode::INVALID_ARGUMENT,
             "sources: give at least one");
  table_case("no destinations", [](T& r) { r.clear_destinations(); },
             StatusCode::INVALID_ARGUMENT, "destinations: give at least one");
  table_case(
      "too many sources",
      [](T& r) {
        for (int i = 0; i < kMaxTableEntries; ++i) *r.add_sources() = CellPos(1, 1);
      },
      StatusCode::RESOURCE_EXHAUSTED, "--max_table_entries");
  table_case(
      "source off the map",
      [](T& r) {
        *r.add_sources() = CellPos(3, 1);
        *r.add_sources() = CellPos(99, 1);
      },
      StatusCode::INVALID_ARGUMENT, "sources[3]");
  table_case("source unset", [](T& r) { r.add_sources(); }, StatusCode::INVALID_ARGUMENT,
             "sources[2] is not set");
  table_case("destination on a blocked cell",
             [](T& r) { *r.add_destinations() = CellPos(5, 5); }, StatusCode::INVALID_ARGUMENT,
             "destinations[1] (5, 5) is on a blocked cell");
  table_case("NaN world source", [](T& r) { *r.mutable_sources(0) = WorldPos(kNaN, 1); },
             StatusCode::INVALID_ARGUMENT, "sources[0] world point (nan, 1) is not finite");
  table_case("negative cost weight",
             [](T& r) { r.mutable_options()->set_cost_weight(-1); },
             StatusCode::INVALID_ARGUMENT, "cost_weight");
  table_case("negative robot radius",
             [](T& r) { r.mutable_options()->set_robot_radius_m(-1); },
             StatusCode::INVALID_ARGUMENT, "robot_radius_m");

  const auto nearest_case = [&](const std::string& what,
                                std::function<void(v1::NearestRequest&)> change,
                                StatusCode code, const std::string& message) {
    v1::NearestRequest request;
    request.set_map("room");
    *request.mutable_point() = CellPos(5, 5);
    change(request);
    cases.push_back({"Nearest", what,
                     [=, this] {
                       v1::NearestResponse response;
                       return planner_->Nearest(Context().get(), request, &response);
                     },
                     code, message});
  };
  using N = v1::NearestRequest;
  nearest_case("point unset", [](N& r) { r.clear_point(); }, StatusCode::INVALID_ARGUMENT,
               "point is not set");
  nearest_case("infinite point", [](N& r) { *r.mutable_point() = WorldPos(kInf, 1); },
               StatusCode::INVALID_ARGUMENT, "point");
  nearest_case("negative max distance", [](N& r) { r.set_max_distance_m(-2); },
               StatusCode::INVALID_ARGUMENT, "max_distance_m -2 must be finite and >= 0");
  nearest_case("max distance over the limit", [](N& r) { r.set_max_distance_cells(5000); },
               StatusCode::INVALID_ARGUMENT, "max_distance_cells 5000 is 5000 cells");

  const auto trip_case = [&](const std::string& what,
                             std::function<void(v1::TripRequest&)> change, StatusCode code,
                             const std::string& message) {
    v1::TripRequest request;
    request.set_map("room");
    *request.add_waypoints() = CellPos(1, 1);
    *request.add_waypoints() = CellPos(14, 14);
    *request.add_waypoints() = CellPos(1, 14);
    change(request);
    cases.push_back({"Trip", what,
                     [=, this] {
                       v1::TripResponse response;
                       return planner_->Trip(Context().get(), request, &response);
                     },
                     code, message});
  };
  using R = v1::TripRequest;
  trip_case(
      "one waypoint", [](R& r) { r.mutable_waypoints()->DeleteSubrange(1, 2); },
      StatusCode::INVALID_ARGUMENT, "a trip needs at least 2, not 1");
  trip_case(
      "too many waypoints",
      [](R& r) {
        for (int i = 0; i < kMaxTripStops; ++i) *r.add_waypoints() = CellPos(1, 1);
      },
      StatusCode::RESOURCE_EXHAUSTED, "--max_trip_stops");
  trip_case("waypoint on a blocked cell", [](R& r) { *r.mutable_waypoints(1) = CellPos(5, 5); },
            StatusCode::INVALID_ARGUMENT, "waypoints[1] (5, 5) is on a blocked cell");
  trip_case("spm legs", [](R& r) { r.set_planner(v1::PLANNER_SPM); },
            StatusCode::INVALID_ARGUMENT, "planner: the legs are planned through via points");
  trip_case("kinematic legs", [](R& r) { r.set_planner(v1::PLANNER_HYBRID_ASTAR); },
            StatusCode::INVALID_ARGUMENT, "plans between poses");
  trip_case("unknown planner", [](R& r) { r.set_planner(static_cast<v1::Planner>(999)); },
            StatusCode::INVALID_ARGUMENT, "unknown planner 999");

  const auto iso_case = [&](const std::string& what,
                            std::function<void(v1::IsochroneRequest&)> change,
                            StatusCode code, const std::string& message) {
    v1::IsochroneRequest request;
    request.set_map("room");
    *request.mutable_start() = CellPos(1, 1);
    request.set_budget_m(5);
    change(request);
    cases.push_back({"Isochrone", what,
                     [=, this] {
                       v1::IsochroneResponse response;
                       return planner_->Isochrone(Context().get(), request, &response);
                     },
                     code, message});
  };
  using I = v1::IsochroneRequest;
  iso_case("negative budget", [](I& r) { r.set_budget_m(-1); }, StatusCode::INVALID_ARGUMENT,
           "budget_m -1 must be finite and >= 0");
  iso_case("NaN budget", [](I& r) { r.set_budget_cells(kNaN); },
           StatusCode::INVALID_ARGUMENT, "budget_cells nan must be finite and >= 0");
  iso_case("budget unset", [](I& r) { r.clear_budget(); }, StatusCode::INVALID_ARGUMENT,
           "budget_m or budget_cells is required");
  iso_case("start blocked", [](I& r) { *r.mutable_start() = CellPos(5, 5); },
           StatusCode::INVALID_ARGUMENT, "start (5, 5) is on a blocked cell");
  iso_case("start inscribed by the robot radius",
           [](I& r) {
             *r.mutable_start() = CellPos(4, 4);
             r.mutable_options()->set_robot_radius_cells(1.5);
           },
           StatusCode::INVALID_ARGUMENT, "start (4, 4) is within the robot radius");
  trip_case("waypoint inscribed by the robot radius",
            [](R& r) {
              *r.mutable_waypoints(2) = CellPos(4, 4);
              r.mutable_options()->set_robot_radius_cells(1.5);
            },
            StatusCode::INVALID_ARGUMENT, "waypoints[2] (4, 4) is within the robot radius");
  iso_case("start off the map", [](I& r) { *r.mutable_start() = CellPos(-4, 1); },
           StatusCode::INVALID_ARGUMENT, "start");

  // ---- Plan: snap_start ----
  const auto snap_case = [&](const std::string& what,
                             std::function<void(v1::PlanRequest&)> change, StatusCode code,
                             const std::string& message) {
    v1::PlanRequest request = GoodPlan();
    request.mutable_options()->set_snap_start(true);
    change(request);
    cases.push_back({"Plan", what, [=, this] { return Plan(request); }, code, message});
  };
  using P = v1::PlanRequest;
  snap_case("negative snap_start_max",
            [](P& r) { r.mutable_options()->set_snap_start_max_m(-1); },
            StatusCode::INVALID_ARGUMENT, "options.snap_start_max_m -1 must be finite and >= 0");
  snap_case("snap_start_max over the limit",
            [](P& r) { r.mutable_options()->set_snap_start_max_cells(2000); },
            StatusCode::INVALID_ARGUMENT, "options.snap_start_max_cells 2000 is 2000 cells");
  snap_case("snap_start with no free cell near",
            [](P& r) {
              *r.mutable_start() = CellPos(5, 5);
              r.mutable_options()->set_snap_start_max_cells(0.5);
            },
            StatusCode::INVALID_ARGUMENT, "options.snap_start found no cell within");
  snap_case("snap_start with a kinematic planner",
            [](P& r) { r.set_planner(v1::PLANNER_HYBRID_ASTAR); },
            StatusCode::INVALID_ARGUMENT, "options.snap_start: planner hybrid_astar");

  // ---- PlanFleet ----
  const auto fleet_case = [&](const std::string& what,
                              std::function<void(v1::PlanFleetRequest&)> change,
                              StatusCode code, const std::string& message) {
    v1::PlanFleetRequest request;
    request.set_map("room");
    for (const auto& [s, g] : {std::pair{CellPos(1, 1), CellPos(14, 14)},
                               std::pair{CellPos(14, 1), CellPos(1, 14)}}) {
      v1::FleetRobot* robot = request.add_robots();
      *robot->mutable_start() = s;
      *robot->mutable_goal() = g;
    }
    change(request);
    cases.push_back({"PlanFleet", what,
                     [=, this] {
                       v1::PlanFleetResponse response;
                       return planner_->PlanFleet(Context().get(), request, &response);
                     },
                     code, message});
  };
  using F = v1::PlanFleetRequest;
  fleet_case("no robots", [](F& r) { r.clear_robots(); }, StatusCode::INVALID_ARGUMENT,
             "robots: give at least one");
  fleet_case(
      "too many robots",
      [](F& r) {
        for (int i = 0; i < kMaxFleetRobots; ++i) *r.add_robots() = r.robots(0);
      },
      StatusCode::RESOURCE_EXHAUSTED, "--max_fleet_robots");
  fleet_case("start off the map", [](F& r) { *r.mutable_robots(1)->mutable_start() = CellPos(16, 1); },
             StatusCode::INVALID_ARGUMENT, "robots[1].start");
  fleet_case("goal unset", [](F& r) { r.mutable_robots(0)->clear_goal(); },
             StatusCode::INVALID_ARGUMENT, "robots[0].goal is not set");
  fleet_case("goal on a blocked cell, named",
             [](F& r) {
               r.mutable_robots(1)->set_name("forklift-2");
               *r.mutable_robots(1)->mutable_goal() = CellPos(5, 5);
             },
             StatusCode::INVALID_ARGUMENT,
             "robots[1] ('forklift-2').goal (5, 5) is on a blocked cell");
  fleet_case("two robots on one start",
             [](F& r) { *r.mutable_robots(1)->mutable_start() = CellPos(1, 1); },
             StatusCode::INVALID_ARGUMENT,
             "robots[1].start (1, 1) is the start of robots[0] too");
  fleet_case("two robots on one goal",
             [](F& r) { *r.mutable_robots(0)->mutable_goal() = CellPos(1, 14); },
             StatusCode::INVALID_ARGUMENT, "robots[1].goal (1, 14) is the goal of robots[0] too");
  fleet_case("negative radius", [](F& r) { r.mutable_robots(0)->set_radius_m(-0.5); },
             StatusCode::INVALID_ARGUMENT, "robots[0].radius_m -0.5 must be finite and >= 0");
  fleet_case("goal inscribed by the robot's radius",
             [](F& r) {
               *r.mutable_robots(0)->mutable_goal() = CellPos(4, 4);
               r.mutable_robots(0)->set_radius_m(1.5);
             },
             StatusCode::INVALID_ARGUMENT, "robots[0].goal (4, 4) is within the robot radius");
  fleet_case("suboptimality below 1", [](F& r) { r.set_suboptimality(0.5); },
             StatusCode::INVALID_ARGUMENT, "suboptimality 0.5 must be 0 (optimal)");
  fleet_case("negative restarts", [](F& r) { r.set_restarts(-1); },
             StatusCode::INVALID_ARGUMENT, "restarts -1 must be >= 0");
  fleet_case("negative time limit", [](F& r) { r.set_time_limit_ms(-5); },
             StatusCode::INVALID_ARGUMENT, "time_limit_ms -5 must be >= 0");
  fleet_case("negative max_steps", [](F& r) { r.set_max_steps(-1); },
             StatusCode::INVALID_ARGUMENT, "max_steps -1 must be >= 0");
  fleet_case("unknown map", [](F& r) { r.set_map("nowhere"); }, StatusCode::NOT_FOUND,
             "nowhere");
  fleet_case("unknown solver", [](F& r) { r.set_solver(static_cast<v1::FleetSolver>(9)); },
             StatusCode::INVALID_ARGUMENT, "solver 9 is not a FleetSolver value");

  // ---- fleet sessions (Navigate with open.fleet) ----
  const auto session_case = [&](const std::string& what,
                                std::function<void(v1::NavigateRequest&)> change,
                                const std::string& message,
                                std::vector<v1::NavigateRequest> then = {}) {
    v1::NavigateRequest open;
    open.set_seq(1);
    open.mutable_open()->set_map("room");
    *open.mutable_open()->mutable_start() = CellPos(1, 1);
    *open.mutable_open()->mutable_goal() = CellPos(14, 14);
    open.mutable_open()->mutable_fleet()->set_group("bad");
    change(open);
    std::vector<v1::NavigateRequest> messages = {open};
    messages.insert(messages.end(), then.begin(), then.end());
    cases.push_back({"Navigate", "fleet: " + what,
                     [messages, this] { return Navigate(messages); },
                     StatusCode::INVALID_ARGUMENT, message});
  };
  using Nav = v1::NavigateRequest;
  const auto fleet_options = [](Nav& r) { return r.mutable_open()->mutable_fleet(); };
  session_case("unknown solver",
               [&](Nav& r) { fleet_options(r)->set_solver(static_cast<v1::FleetSolver>(7)); },
               "open.fleet.solver 7 is not a FleetSolver value");
  session_case("negative time limit", [&](Nav& r) { fleet_options(r)->set_time_limit_ms(-1); },
               "open.fleet.time_limit_ms -1 must be in [0, 60000]");
  session_case("time limit over a minute",
               [&](Nav& r) { fleet_options(r)->set_time_limit_ms(60001); },
               "open.fleet.time_limit_ms 60001 must be in [0, 60000]");
  session_case("with control", [](Nav& r) { r.mutable_open()->mutable_control(); },
               "open.fleet: a fleet session's robot follows its timed path");
  session_case("with a planner", [](Nav& r) { r.mutable_open()->set_planner(v1::PLANNER_ASTAR); },
               "open.planner: a fleet session is planned by its group's multi-robot solver");
  session_case("goal on a blocked cell",
               [](Nav& r) { *r.mutable_open()->mutable_goal() = CellPos(5, 5); }, "(5, 5)");
  v1::NavigateRequest private_observation;
  private_observation.set_seq(2);
  private_observation.mutable_observe()->set_session_only(true);
  v1::CellChange* change = private_observation.mutable_observe()->add_changes();
  *change->mutable_cell() = CellPos(2, 2).cell();
  change->set_cost(254);
  session_case("session_only observation", [](Nav&) {}, "session_only is not for fleet sessions",
               {private_observation});
}

}  // namespace pathd::bad_input_test
