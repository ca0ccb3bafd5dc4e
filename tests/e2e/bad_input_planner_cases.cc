// bad_input_test's PlannerService and Health rows: Plan (and the same through
// PlanStream and PlanBatch), Navigate, IsPathValid, CostToGo, Health and
// GetCacheStats.
#include <utility>

#include "tests/e2e/bad_input_fixture.h"

namespace pathd::bad_input_test {

void BadInputTest::AddPlannerCases(std::vector<Case>& cases) {
  // ---- Plan, and the same through PlanStream and PlanBatch ----
  const auto plan_case = [&](const std::string& what,
                             std::function<void(v1::PlanRequest&)> change,
                             StatusCode code, const std::string& message) {
    v1::PlanRequest request = GoodPlan();
    change(request);
    cases.push_back(
        {"Plan", what, [=, this] { return Plan(request); }, code, message});
    cases.push_back({"PlanStream", what,
                     [=, this] { return PlanStream(request); }, code, message});
    cases.push_back({"PlanBatch", what,
                     [=, this] { return PlanBatchItem(request); }, code,
                     message});
  };
  using P = v1::PlanRequest;
  plan_case(
      "start unset", [](P& r) { r.clear_start(); },
      StatusCode::INVALID_ARGUMENT, "start is not set");
  plan_case(
      "goal unset", [](P& r) { r.clear_goal(); }, StatusCode::INVALID_ARGUMENT,
      "goal is not set");
  plan_case(
      "start cell (-1, 3)", [](P& r) { *r.mutable_start() = CellPos(-1, 3); },
      StatusCode::INVALID_ARGUMENT, "start");
  plan_case(
      "goal cell (INT32_MAX, INT32_MIN)",
      [](P& r) { *r.mutable_goal() = CellPos(kIntMax, kIntMin); },
      StatusCode::INVALID_ARGUMENT, "goal");
  plan_case(
      "start on a blocked cell",
      [](P& r) { *r.mutable_start() = CellPos(5, 5); },
      StatusCode::INVALID_ARGUMENT, "start");
  plan_case(
      "NaN start world point",
      [](P& r) { *r.mutable_start() = WorldPos(kNaN, 1); },
      StatusCode::INVALID_ARGUMENT, "start world point (nan, 1) is not finite");
  plan_case(
      "infinite goal world point",
      [](P& r) { *r.mutable_goal() = WorldPos(1, -kInf); },
      StatusCode::INVALID_ARGUMENT, "goal world point (1, -inf) is not finite");
  plan_case(
      "goal world point 1e300 off the map",
      [](P& r) { *r.mutable_goal() = WorldPos(1e300, 1e300); },
      StatusCode::INVALID_ARGUMENT, "is outside the map");
  plan_case(
      "unknown planner 99",
      [](P& r) { r.set_planner(static_cast<v1::Planner>(99)); },
      StatusCode::INVALID_ARGUMENT, "unknown planner 99");
  plan_case(
      "unknown planner -1",
      [](P& r) { r.set_planner(static_cast<v1::Planner>(-1)); },
      StatusCode::INVALID_ARGUMENT, "unknown planner -1");
  plan_case(
      "unknown connectivity 6",
      [](P& r) {
        r.mutable_options()->set_connectivity(static_cast<v1::Connectivity>(6));
      },
      StatusCode::INVALID_ARGUMENT, "unknown connectivity 6");
  plan_case(
      "unknown attractive potential 9",
      [](P& r) {
        r.mutable_options()->mutable_potential_field()->set_attractive(
            static_cast<v1::AttractivePotential>(9));
      },
      StatusCode::INVALID_ARGUMENT, "unknown shape 9");
  plan_case(
      "NaN cost_weight",
      [](P& r) { r.mutable_options()->set_cost_weight(kNaN); },
      StatusCode::INVALID_ARGUMENT, "options.cost_weight nan");
  plan_case(
      "negative cost_weight",
      [](P& r) { r.mutable_options()->set_cost_weight(-1); },
      StatusCode::INVALID_ARGUMENT, "options.cost_weight");
  plan_case(
      "heuristic_weight 0.5",
      [](P& r) { r.mutable_options()->set_heuristic_weight(0.5); },
      StatusCode::INVALID_ARGUMENT, "options.heuristic_weight");
  plan_case(
      "infinite heuristic_weight",
      [](P& r) { r.mutable_options()->set_heuristic_weight(kInf); },
      StatusCode::INVALID_ARGUMENT, "options.heuristic_weight");
  plan_case(
      "negative max_expansions",
      [](P& r) { r.mutable_options()->set_max_expansions(-5); },
      StatusCode::INVALID_ARGUMENT, "options.max_expansions");
  plan_case(
      "negative lookahead",
      [](P& r) { r.mutable_options()->set_lookahead(-1); },
      StatusCode::INVALID_ARGUMENT, "options.lookahead");
  plan_case(
      "NaN robot_radius_m",
      [](P& r) { r.mutable_options()->set_robot_radius_m(kNaN); },
      StatusCode::INVALID_ARGUMENT, "options.robot_radius_m");
  plan_case(
      "infinite robot_radius_cells",
      [](P& r) { r.mutable_options()->set_robot_radius_cells(kInf); },
      StatusCode::INVALID_ARGUMENT, "options.robot_radius_cells");
  plan_case(
      "NaN min_clearance_m",
      [](P& r) { r.mutable_options()->set_min_clearance_m(kNaN); },
      StatusCode::INVALID_ARGUMENT, "options.min_clearance_m");
  plan_case(
      "negative min_clearance_cells",
      [](P& r) { r.mutable_options()->set_min_clearance_cells(-3); },
      StatusCode::INVALID_ARGUMENT, "options.min_clearance_cells");
  plan_case(
      "footprint polygon crossing itself",
      [](P& r) {
        for (const auto& [x, y] : {std::pair{0.0, 0.0}, {1.0, 1.0}, {1.0, 0.0}, {0.0, 1.0}}) {
          v1::WorldPoint* p = r.mutable_options()->mutable_footprint()->add_polygon_m();
          p->set_x(x);
          p->set_y(y);
        }
      },
      StatusCode::INVALID_ARGUMENT, "options.footprint: footprint edges 0 and 2 cross");
  plan_case(
      "footprint vertex NaN",
      [](P& r) {
        for (const auto& [x, y] : {std::pair{0.0, 0.0}, {1.0, kNaN}, {1.0, 0.0}}) {
          v1::WorldPoint* p = r.mutable_options()->mutable_footprint()->add_polygon_m();
          p->set_x(x);
          p->set_y(y);
        }
      },
      StatusCode::INVALID_ARGUMENT, "footprint vertex 1 is not a finite point");
  plan_case(
      "footprint radius 1e300 m",
      [](P& r) { r.mutable_options()->mutable_footprint()->set_radius_m(1e300); },
      StatusCode::INVALID_ARGUMENT, "more than the map's diagonal");
  plan_case(
      "start world pose with infinite yaw",
      [](P& r) {
        r.mutable_start()->mutable_world_pose()->set_x(1);
        r.mutable_start()->mutable_world_pose()->set_y(1);
        r.mutable_start()->mutable_world_pose()->set_yaw(kInf);
      },
      StatusCode::INVALID_ARGUMENT, "start world pose (1, 1, inf) is not finite");
  plan_case(
      "goal cell pose off the map",
      [](P& r) {
        r.mutable_goal()->mutable_cell_pose()->set_x(-5);
        r.mutable_goal()->mutable_cell_pose()->set_y(1);
      },
      StatusCode::INVALID_ARGUMENT, "goal (-5, 1) in cell coordinates is outside");
  plan_case(
      "NaN inflation_radius_m",
      [](P& r) { r.mutable_options()->set_inflation_radius_m(kNaN); },
      StatusCode::INVALID_ARGUMENT, "options.inflation_radius_m");
  plan_case(
      "negative inflation_radius_cells",
      [](P& r) { r.mutable_options()->set_inflation_radius_cells(-2); },
      StatusCode::INVALID_ARGUMENT, "options.inflation_radius_cells");
  plan_case(
      "inflation_radius_cells smaller than the robot radius",
      [](P& r) {
        r.mutable_options()->set_robot_radius_cells(3);
        r.mutable_options()->set_inflation_radius_cells(2);
      },
      StatusCode::INVALID_ARGUMENT, "options.inflation_radius_cells 2 is smaller");
  plan_case(
      "inflation_radius_cells under a footprint's inscribed radius",
      [](P& r) {
        v1::Footprint* f = r.mutable_options()->mutable_footprint();
        constexpr double kSquare[4][2] = {{-2, -2}, {2, -2}, {2, 2}, {-2, 2}};
        for (const auto& corner : kSquare) {
          v1::CellPoint* p = f->add_polygon_cells();
          p->set_x(corner[0]);
          p->set_y(corner[1]);
        }
        r.mutable_options()->set_inflation_radius_cells(1);
      },
      StatusCode::INVALID_ARGUMENT, "footprint's inscribed radius");
  plan_case(
      "cost_scaling_factor 0",
      [](P& r) {
        r.mutable_options()->set_inflation_radius_cells(4);
        r.mutable_options()->set_cost_scaling_factor(0);
      },
      StatusCode::INVALID_ARGUMENT, "options.cost_scaling_factor");
  plan_case(
      "infinite cost_scaling_factor",
      [](P& r) { r.mutable_options()->set_cost_scaling_factor(kInf); },
      StatusCode::INVALID_ARGUMENT, "options.cost_scaling_factor");
  plan_case(
      "goal_tolerance_cells 1e9",
      [](P& r) { r.mutable_options()->set_goal_tolerance_cells(1e9); },
      StatusCode::INVALID_ARGUMENT, "the limit is 1024 cells");
  plan_case(
      "NaN goal_tolerance_m",
      [](P& r) { r.mutable_options()->set_goal_tolerance_m(kNaN); },
      StatusCode::INVALID_ARGUMENT, "options.goal_tolerance_m");
  plan_case(
      "NaN potential step_size",
      [](P& r) {
        r.mutable_options()->mutable_potential_field()->set_step_size(kNaN);
      },
      StatusCode::INVALID_ARGUMENT, "options.potential_field.step_size");
  plan_case(
      "negative potential max_steps",
      [](P& r) {
        r.mutable_options()->mutable_potential_field()->set_max_steps(-1);
      },
      StatusCode::INVALID_ARGUMENT, "options.potential_field.max_steps");
  plan_case(
      "ant_colony rho above 1",
      [](P& r) {
        r.set_planner(v1::PLANNER_ANT_COLONY);
        r.mutable_options()->mutable_ant_colony()->set_rho(1.5);
      },
      StatusCode::INVALID_ARGUMENT, "options.ant_colony.rho 1.5");
  plan_case(
      "ant_colony zero ants",
      [](P& r) {
        r.set_planner(v1::PLANNER_ANT_COLONY);
        r.mutable_options()->mutable_ant_colony()->set_ants(0);
      },
      StatusCode::INVALID_ARGUMENT, "options.ant_colony.ants 0");
  plan_case(
      "ant_colony NaN alpha",
      [](P& r) {
        r.set_planner(v1::PLANNER_ANT_COLONY);
        r.mutable_options()->mutable_ant_colony()->set_alpha(kNaN);
      },
      StatusCode::INVALID_ARGUMENT, "options.ant_colony.alpha");
  plan_case(
      "ant_colony q0 above 1",
      [](P& r) {
        r.set_planner(v1::PLANNER_ANT_COLONY);
        r.mutable_options()->mutable_ant_colony()->set_q0(2);
      },
      StatusCode::INVALID_ARGUMENT, "options.ant_colony.q0");
  plan_case(
      "reaction_diffusion threshold 0.5",
      [](P& r) {
        r.set_planner(v1::PLANNER_REACTION_DIFFUSION);
        r.mutable_options()->mutable_reaction_diffusion()->set_threshold(0.5);
      },
      StatusCode::INVALID_ARGUMENT, "options.reaction_diffusion.threshold 0.5");
  plan_case(
      "reaction_diffusion unstable time_step",
      [](P& r) {
        r.set_planner(v1::PLANNER_REACTION_DIFFUSION);
        r.mutable_options()->mutable_reaction_diffusion()->set_time_step(1.0);
      },
      StatusCode::INVALID_ARGUMENT, "options.reaction_diffusion.time_step 1");
  plan_case(
      "reaction_diffusion negative diffusion",
      [](P& r) {
        r.set_planner(v1::PLANNER_REACTION_DIFFUSION);
        r.mutable_options()->mutable_reaction_diffusion()->set_diffusion(-1);
      },
      StatusCode::INVALID_ARGUMENT, "options.reaction_diffusion.diffusion");
  plan_case(
      "via off the map", [](P& r) { *r.add_via() = CellPos(3, 99); },
      StatusCode::INVALID_ARGUMENT, "via[0]");
  plan_case(
      "via unset", [](P& r) { r.add_via(); }, StatusCode::INVALID_ARGUMENT,
      "via[0] is not set");
  plan_case(
      "NaN via world point", [](P& r) { *r.add_via() = WorldPos(kNaN, kNaN); },
      StatusCode::INVALID_ARGUMENT, "via[0] world point");
  plan_case(
      "257 via points",
      [](P& r) {
        for (int i = 0; i < 257; ++i) *r.add_via() = CellPos(2, 2);
      },
      StatusCode::INVALID_ARGUMENT, "at most 256");
  plan_case(
      "200000 unset via points",
      [](P& r) {
        for (int i = 0; i < 200000; ++i) r.add_via();
      },
      StatusCode::INVALID_ARGUMENT, "at most 256");
  plan_case(
      "via with spm",
      [](P& r) {
        r.set_planner(v1::PLANNER_SPM);
        *r.add_via() = CellPos(2, 2);
      },
      StatusCode::INVALID_ARGUMENT, "via");
  plan_case(
      "cost-to-go field of a map over --max_cost_to_go_cells",
      [](P& r) {
        r.set_map("big");
        r.set_planner(v1::PLANNER_DISTANCE_TRANSFORM);
        r.mutable_options()->set_return_cost_to_go(true);
      },
      StatusCode::INVALID_ARGUMENT, "--max_cost_to_go_cells");
  // PlanBatch items of their own.
  cases.push_back({"PlanBatch", "empty batch", [this] { return PlanBatch({}); },
                   StatusCode::OK, "answers=0"});
  cases.push_back({"PlanBatch", "empty request_id",
                   [this] {
                     v1::PlanBatchRequest item;
                     *item.mutable_request() = GoodPlan();
                     std::vector<v1::PlanBatchRequest> items = {item};
                     // The answer carries the empty id; find it by renaming.
                     auto context = Context();
                     auto stream = planner_->PlanBatch(context.get());
                     stream->Write(item);
                     stream->WritesDone();
                     v1::PlanBatchResponse answer;
                     grpc::Status item_status = grpc::Status::OK;
                     while (stream->Read(&answer)) {
                       if (answer.has_error()) {
                         item_status = grpc::Status(
                             static_cast<StatusCode>(answer.error().code()),
                             answer.error().message());
                       }
                     }
                     const grpc::Status status = stream->Finish();
                     return status.ok() ? item_status : status;
                   },
                   StatusCode::INVALID_ARGUMENT, "request_id"});
  cases.push_back({"PlanBatch", "item without a request",
                   [this] { return PlanBatchItem(v1::PlanRequest()); },
                   StatusCode::INVALID_ARGUMENT, "map name is empty"});
  cases.push_back({"PlanBatch", "1 MiB request_id",
                   [this] {
                     v1::PlanRequest request = GoodPlan();
                     request.set_planner(static_cast<v1::Planner>(77));
                     return PlanBatchItem(request,
                                          std::string(size_t{1} << 20, 'r'));
                   },
                   StatusCode::OK, "answers=2"});

  // ---- Navigate ----
  const auto nav = [&](const std::string& what,
                       std::function<grpc::Status()> call, StatusCode code,
                       const std::string& message) {
    cases.push_back({"Navigate", what, std::move(call), code, message});
  };
  nav(
      "no messages", [this] { return Navigate({}); }, StatusCode::OK, "");
  nav(
      "pose before open",
      [this] {
        v1::NavigateRequest pose;
        *pose.mutable_pose() = CellPos(1, 1);
        return Navigate({pose});
      },
      StatusCode::INVALID_ARGUMENT,
      "the first message of a session must be 'open'");
  nav(
      "message with no kind",
      [this] { return Navigate({v1::NavigateRequest()}); },
      StatusCode::INVALID_ARGUMENT, "sets none of open, pose, observe");
  nav(
      "open twice", [this] { return NavigateThen(NavigateOpen(GoodPlan())); },
      StatusCode::INVALID_ARGUMENT, "already open");
  {
    v1::PlanRequest p = GoodPlan();
    *p.mutable_start() = WorldPos(kInf, 0);
    nav(
        "open with infinite start",
        [=, this] { return Navigate({NavigateOpen(p)}); },
        StatusCode::INVALID_ARGUMENT,
        "start world point (inf, 0) is not finite");
    p = GoodPlan();
    *p.mutable_goal() = CellPos(16, 16);
    nav(
        "open with goal off the map",
        [=, this] { return Navigate({NavigateOpen(p)}); },
        StatusCode::INVALID_ARGUMENT, "goal");
    p = GoodPlan();
    p.mutable_options()->set_connectivity(static_cast<v1::Connectivity>(3));
    nav(
        "open with unknown connectivity",
        [=, this] { return Navigate({NavigateOpen(p)}); },
        StatusCode::INVALID_ARGUMENT, "unknown connectivity 3");
    p = GoodPlan();
    p.mutable_options()->set_robot_radius_m(2.0);
    p.mutable_options()->set_inflation_radius_m(1.0);
    nav(
        "open with an inflation radius under the robot radius",
        [=, this] { return Navigate({NavigateOpen(p)}); },
        StatusCode::INVALID_ARGUMENT, "options.inflation_radius_m 1 is smaller");
  }
  {
    // A kinematic session for a 2 x 1 cell robot on "room", whose (5, 5)
    // is blocked.
    const auto kinematic = [](double sx, double sy, double gx, double gy) {
      v1::PlanRequest p = GoodPlan();
      p.set_planner(v1::PLANNER_HYBRID_ASTAR);
      p.mutable_start()->mutable_cell_pose()->set_x(sx);
      p.mutable_start()->mutable_cell_pose()->set_y(sy);
      p.mutable_goal()->mutable_cell_pose()->set_x(gx);
      p.mutable_goal()->mutable_cell_pose()->set_y(gy);
      for (const auto& [x, y] : {std::pair{1.0, 0.5}, {1.0, -0.5}, {-1.0, -0.5}, {-1.0, 0.5}}) {
        v1::CellPoint* c = p.mutable_options()->mutable_footprint()->add_polygon_cells();
        c->set_x(x);
        c->set_y(y);
      }
      p.mutable_options()->set_min_turning_radius_cells(2.0);
      return p;
    };
    // The start cell (4, 5) is free; the robot's front overlaps (5, 5).
    const v1::PlanRequest start_collides = kinematic(4.5, 5.5, 12.5, 12.5);
    nav(
        "kinematic open with a start pose whose footprint collides",
        [=, this] { return Navigate({NavigateOpen(start_collides)}); },
        StatusCode::INVALID_ARGUMENT, "open.start: start pose (4.5, 5.5, 0 rad) collides");
    const v1::PlanRequest goal_collides = kinematic(2.5, 2.5, 6.5, 5.5);
    nav(
        "kinematic open with a goal pose whose footprint collides",
        [=, this] { return Navigate({NavigateOpen(goal_collides)}); },
        StatusCode::INVALID_ARGUMENT, "open.goal: goal pose (6.5, 5.5, 0 rad) collides");
    v1::PlanRequest two_vertices = kinematic(2.5, 2.5, 12.5, 12.5);
    two_vertices.mutable_options()->mutable_footprint()->mutable_polygon_cells()->DeleteSubrange(
        0, 2);
    nav(
        "kinematic open with a two-vertex footprint",
        [=, this] { return Navigate({NavigateOpen(two_vertices)}); },
        StatusCode::INVALID_ARGUMENT, "options.footprint");
    const v1::PlanRequest good = kinematic(2.5, 2.5, 12.5, 12.5);
    nav(
        "kinematic open with a negative replan budget",
        [=, this] {
          v1::NavigateRequest open = NavigateOpen(good);
          open.mutable_open()->set_replan_max_expansions(-1);
          return Navigate({open});
        },
        StatusCode::INVALID_ARGUMENT, "open.replan_max_expansions -1 must be >= 0");
    nav(
        "kinematic pose with a NaN heading",
        [=, this] {
          v1::NavigateRequest pose;
          pose.set_seq(2);
          pose.mutable_pose()->mutable_cell_pose()->set_x(3.5);
          pose.mutable_pose()->mutable_cell_pose()->set_y(2.5);
          pose.mutable_pose()->mutable_cell_pose()->set_yaw(kNaN);
          return Navigate({NavigateOpen(good), pose});
        },
        StatusCode::INVALID_ARGUMENT, "pose cell pose (3.5, 2.5, nan) is not finite");
    v1::PlanRequest differential = kinematic(2.5, 2.5, 12.5, 12.5);
    differential.mutable_options()->set_motion_model(v1::MOTION_MODEL_DIFFERENTIAL);
    nav(
        "kinematic open with a motion model the planner does not drive",
        [=, this] { return Navigate({NavigateOpen(differential)}); },
        StatusCode::INVALID_ARGUMENT,
        "hybrid_astar plans dubins or reeds_shepp motion, not differential");
    v1::PlanRequest astar = GoodPlan();
    astar.set_planner(v1::PLANNER_ASTAR);
    nav(
        "open with a planner that is not incremental or kinematic",
        [=, this] { return Navigate({NavigateOpen(astar)}); },
        StatusCode::INVALID_ARGUMENT, "open.planner: a Navigate session plans with dstar_lite");
  }
  nav(
      "pose off the map",
      [this] {
        v1::NavigateRequest pose;
        *pose.mutable_pose() = CellPos(-7, 2);
        return NavigateThen(pose);
      },
      StatusCode::INVALID_ARGUMENT, "pose (-7, 2) is outside");
  nav(
      "NaN pose",
      [this] {
        v1::NavigateRequest pose;
        *pose.mutable_pose() = WorldPos(kNaN, 0);
        return NavigateThen(pose);
      },
      StatusCode::INVALID_ARGUMENT, "pose world point (nan, 0) is not finite");
  nav(
      "unset pose",
      [this] {
        v1::NavigateRequest pose;
        pose.mutable_pose();
        return NavigateThen(pose);
      },
      StatusCode::INVALID_ARGUMENT, "pose is not set");
  nav(
      "empty observation",
      [this] {
        v1::NavigateRequest observe;
        observe.mutable_observe();
        return NavigateThen(observe);
      },
      StatusCode::INVALID_ARGUMENT, "observation has no changes");
  for (const bool session_only : {false, true}) {
    const std::string where = session_only ? " (session only)" : "";
    nav(
        "observation off the map" + where,
        [=, this] {
          v1::NavigateRequest observe;
          observe.mutable_observe()->set_session_only(session_only);
          v1::CellChange* c = observe.mutable_observe()->add_changes();
          *c->mutable_cell() = CellPos(3, 16).cell();
          return NavigateThen(observe);
        },
        StatusCode::INVALID_ARGUMENT, "change 0: cell (3, 16) is outside");
    nav(
        "observation cost 300" + where,
        [=, this] {
          v1::NavigateRequest observe;
          observe.mutable_observe()->set_session_only(session_only);
          v1::CellChange* c = observe.mutable_observe()->add_changes();
          *c->mutable_cell() = CellPos(3, 3).cell();
          c->set_cost(300);
          return NavigateThen(observe);
        },
        StatusCode::INVALID_ARGUMENT, "cost 300 is out of range");
    nav(
        "100000 overlapping whole-map rects" + where,
        [=, this] {
          v1::NavigateRequest observe;
          observe.mutable_observe()->set_session_only(session_only);
          for (int i = 0; i < 100000; ++i) {
            v1::CellChange* c = observe.mutable_observe()->add_changes();
            c->mutable_rect()->set_x_max(15);
            c->mutable_rect()->set_y_max(15);
            c->set_cost(i % 2 == 0 ? 0 : 100);
          }
          return NavigateThen(observe);
        },
        StatusCode::RESOURCE_EXHAUSTED, "cells in total");
  }

  // ---- IsPathValid ----
  const auto check = [&](const std::string& what,
                         v1::IsPathValidRequest request, StatusCode code,
                         const std::string& message) {
    cases.push_back({"IsPathValid", what,
                     [=, this] { return IsPathValid(request); }, code,
                     message});
  };
  check("empty path", PathCheck({}), StatusCode::INVALID_ARGUMENT,
        "path is empty");
  check("unset pose", PathCheck({CellPos(1, 1), v1::Position()}),
        StatusCode::INVALID_ARGUMENT, "path[1]");
  check("NaN pose", PathCheck({CellPos(1, 1), WorldPos(kNaN, 2)}),
        StatusCode::INVALID_ARGUMENT, "path[1]");
  check("infinite pose", PathCheck({WorldPos(-kInf, kInf)}),
        StatusCode::INVALID_ARGUMENT, "path[0]");
  {
    std::vector<v1::Position> many(kMaxPathPoints + 1, CellPos(1, 1));
    check("path over --max_path_points", PathCheck(many),
          StatusCode::INVALID_ARGUMENT, "--max_path_points");
    v1::IsPathValidRequest request = PathCheck({CellPos(1, 1)});
    request.mutable_options()->set_connectivity(
        static_cast<v1::Connectivity>(-8));
    check("unknown connectivity -8", request, StatusCode::INVALID_ARGUMENT,
          "unknown connectivity -8");
    request = PathCheck({CellPos(1, 1)});
    request.mutable_options()->set_robot_radius_cells(-2);
    check("negative robot radius", request, StatusCode::INVALID_ARGUMENT,
          "options.robot_radius_cells");
  }
  // Off-map poses are a verdict (valid = false), not an error.
  check("poses off the map",
        PathCheck({CellPos(-1, -1), CellPos(kIntMax, kIntMax)}), StatusCode::OK,
        "");

  // ---- CostToGo ----
  const auto field = [&](const std::string& what, v1::CostToGoRequest request,
                         StatusCode code, const std::string& message) {
    cases.push_back({"CostToGo", what, [=, this] { return CostToGo(request); },
                     code, message});
  };
  {
    v1::CostToGoRequest request = Field();
    request.clear_goal();
    field("goal unset", request, StatusCode::INVALID_ARGUMENT,
          "goal is not set");
    request = Field();
    *request.mutable_goal() = WorldPos(kNaN, kInf);
    field("NaN goal", request, StatusCode::INVALID_ARGUMENT, "not finite");
    request = Field();
    *request.mutable_goal() = CellPos(16, 0);
    field("goal off the map", request, StatusCode::INVALID_ARGUMENT, "goal");
    request = Field();
    request.mutable_options()->set_connectivity(
        static_cast<v1::Connectivity>(5));
    field("unknown connectivity 5", request, StatusCode::INVALID_ARGUMENT,
          "unknown connectivity 5");
    request = Field();
    request.mutable_options()->set_inflation_radius_m(-0.5);
    field("negative inflation_radius_m", request, StatusCode::INVALID_ARGUMENT,
          "options.inflation_radius_m");
    request = Field();
    request.mutable_options()->set_inflation_radius_cells(3);
    request.mutable_options()->set_cost_scaling_factor(kNaN);
    field("NaN cost_scaling_factor", request, StatusCode::INVALID_ARGUMENT,
          "options.cost_scaling_factor");
    request = Field();
    request.mutable_options()->set_inflation_radius_cells(3);
    request.mutable_options()->set_cost_weight(0);
    field("inflation costs with cost_weight 0", request, StatusCode::INVALID_ARGUMENT,
          "options.inflation_radius_m/_cells");
  }
  field("window width 0", Window(0, 0, 0, 4), StatusCode::INVALID_ARGUMENT,
        "window.width 0 must be > 0");
  field("window height -3", Window(0, 0, 4, -3), StatusCode::INVALID_ARGUMENT,
        "window.height -3 must be > 0");
  field("window x -1", Window(-1, 0, 4, 4), StatusCode::INVALID_ARGUMENT,
        "window.x -1");
  field("window x + width overflowing int32", Window(kIntMax, 0, kIntMax, 4),
        StatusCode::INVALID_ARGUMENT, "reaches outside");
  field("window beyond the map", Window(10, 10, 7, 1),
        StatusCode::INVALID_ARGUMENT, "reaches outside");
  field("whole field over --max_cost_to_go_cells", Field("big"),
        StatusCode::RESOURCE_EXHAUSTED, "--max_cost_to_go_cells");

  // ---- Health ----
  cases.push_back({"Health.Check", "unknown service",
                   [this] { return HealthCheck("pathd.v1.NoSuchService"); },
                   StatusCode::NOT_FOUND, ""});
  // gRPC's health service refuses service names over 200 bytes.
  cases.push_back(
      {"Health.Check", "1 MiB service name",
       [this] { return HealthCheck(std::string(size_t{1} << 20, 's')); },
       StatusCode::INVALID_ARGUMENT, "could not parse request"});

  // GetCacheStats and ListMaps take no fields, so unknown fields are all a
  // client can add: ignored, as proto3 requires.
  cases.push_back({"GetCacheStats", "unknown fields",
                   [this] {
                     grpc::Slice slice(
                         std::string("\x08\x01\x12\x03"
                                     "abc",
                                     7));
                     return Raw("/pathd.v1.PlannerService/GetCacheStats",
                                grpc::ByteBuffer(&slice, 1));
                   },
                   StatusCode::OK, ""});
}

}  // namespace pathd::bad_input_test
