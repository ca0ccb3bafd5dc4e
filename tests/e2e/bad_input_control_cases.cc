// bad_input_test's rows for control sessions (issue 20): every
// ControlOptions field, local_options by name, the robot's size, the
// planner, and every RobotState field. Each names the field.
#include <string>
#include <utility>

#include "tests/e2e/bad_input_fixture.h"

namespace pathd::bad_input_test {
namespace {

// A control session's open on "room" (1 m cells) for a 0.4 m robot.
v1::NavigateRequest ControlOpen(const v1::PlanRequest& plan) {
  v1::NavigateRequest open;
  open.set_seq(1);
  open.mutable_open()->set_map(plan.map());
  *open.mutable_open()->mutable_start() = plan.start();
  *open.mutable_open()->mutable_goal() = plan.goal();
  *open.mutable_open()->mutable_options() = plan.options();
  open.mutable_open()->mutable_options()->set_robot_radius_m(0.4);
  open.mutable_open()->set_planner(plan.planner());
  open.mutable_open()->mutable_control();
  return open;
}

v1::NavigateRequest GoodState() {
  v1::NavigateRequest state;
  state.set_seq(2);
  state.mutable_state()->mutable_pose()->mutable_world_pose()->set_x(1.5);
  state.mutable_state()->mutable_pose()->mutable_world_pose()->set_y(1.5);
  return state;
}

}  // namespace

void BadInputTest::AddControlCases(std::vector<Case>& cases) {
  const auto open_case = [&](const std::string& what,
                             std::function<void(v1::NavigateRequest&)> edit,
                             const std::string& message) {
    v1::NavigateRequest open = ControlOpen(GoodPlan());
    edit(open);
    cases.push_back({"Navigate", "control: " + what,
                     [open, this] { return Navigate({open}); },
                     StatusCode::INVALID_ARGUMENT, message});
  };
  const auto control = [](v1::NavigateRequest& r) { return r.mutable_open()->mutable_control(); };
  const auto limits = [control](v1::NavigateRequest& r) {
    return control(r)->mutable_limits();
  };
  open_case("unknown local planner",
            [&](auto& r) { control(r)->set_local_planner(static_cast<v1::LocalPlanner>(9)); },
            "open.control.local_planner 9 is not a LocalPlanner value");
  open_case("negative max_v", [&](auto& r) { limits(r)->set_max_v(-1); },
            "open.control.limits.max_v -1 must be finite and >= 0");
  open_case("NaN max_v", [&](auto& r) { limits(r)->set_max_v(kNaN); },
            "open.control.limits.max_v nan");
  open_case("min_v above max_v", [&](auto& r) { limits(r)->set_min_v(2); },
            "open.control.limits.min_v 2 must be finite and at most max_v (0.5)");
  open_case("infinite min_v", [&](auto& r) { limits(r)->set_min_v(-kInf); },
            "open.control.limits.min_v -inf");
  open_case("max_vy without holonomic", [&](auto& r) { limits(r)->set_max_vy(0.3); },
            "open.control.limits.max_vy 0.3 is for a holonomic robot");
  open_case("negative max_vy",
            [&](auto& r) {
              limits(r)->set_holonomic(true);
              limits(r)->set_max_vy(-0.3);
            },
            "open.control.limits.max_vy -0.3 must be finite and >= 0");
  open_case("infinite max_w", [&](auto& r) { limits(r)->set_max_w(kInf); },
            "open.control.limits.max_w inf");
  open_case("negative acc_v", [&](auto& r) { limits(r)->set_acc_v(-1); },
            "open.control.limits.acc_v -1");
  open_case("NaN acc_vy",
            [&](auto& r) {
              limits(r)->set_holonomic(true);
              limits(r)->set_acc_vy(kNaN);
            },
            "open.control.limits.acc_vy nan");
  open_case("negative acc_w", [&](auto& r) { limits(r)->set_acc_w(-2); },
            "open.control.limits.acc_w -2");
  open_case("control_period too long", [&](auto& r) { control(r)->set_control_period(5); },
            "open.control.control_period 5 must be in [0.01, 2] seconds");
  open_case("control_period too short", [&](auto& r) { control(r)->set_control_period(0.001); },
            "open.control.control_period 0.001");
  open_case("NaN control_period", [&](auto& r) { control(r)->set_control_period(kNaN); },
            "open.control.control_period nan");
  open_case("negative stale_after", [&](auto& r) { control(r)->set_stale_after(-1); },
            "open.control.stale_after -1");
  open_case("infinite forget_after", [&](auto& r) { control(r)->set_forget_after(kInf); },
            "open.control.forget_after inf");
  open_case("forget_after before stale_after",
            [&](auto& r) {
              control(r)->set_stale_after(5);
              control(r)->set_forget_after(2);
            },
            "open.control.forget_after 2 must be at least stale_after (5)");
  open_case("unknown local option",
            [&](auto& r) { (*control(r)->mutable_local_options())["speed"] = 1; },
            "open.control.local_options[\"speed\"] is not an option of orca (it has: "
            "time_horizon");
  open_case("DWA option for ORCA",
            [&](auto& r) { (*control(r)->mutable_local_options())["v_samples"] = 5; },
            "open.control.local_options[\"v_samples\"] is not an option of orca");
  open_case("negative ORCA time_horizon",
            [&](auto& r) { (*control(r)->mutable_local_options())["time_horizon"] = -1; },
            "open.control.local_options[\"time_horizon\"] -1 must be positive");
  open_case("NaN ORCA neighbour_range",
            [&](auto& r) { (*control(r)->mutable_local_options())["neighbour_range"] = kNaN; },
            "open.control.local_options[\"neighbour_range\"] nan must be finite");
  open_case("ORCA keep_right of a radian",
            [&](auto& r) { (*control(r)->mutable_local_options())["keep_right"] = 1.5; },
            "open.control.local_options[\"keep_right\"] 1.5 must be in (-1, 1) radians");
  open_case("ORCA max_neighbours not whole",
            [&](auto& r) { (*control(r)->mutable_local_options())["max_neighbours"] = 2.5; },
            "open.control.local_options[\"max_neighbours\"] 2.5 must be a whole number");
  open_case("DWA v_samples zero",
            [&](auto& r) {
              control(r)->set_local_planner(v1::LOCAL_PLANNER_DWA);
              (*control(r)->mutable_local_options())["v_samples"] = 0;
            },
            "open.control.local_options[\"v_samples\"] 0 must be a whole number in 1..1000");
  open_case("DWA negative obstacle_weight",
            [&](auto& r) {
              control(r)->set_local_planner(v1::LOCAL_PLANNER_DWA);
              (*control(r)->mutable_local_options())["obstacle_weight"] = -0.5;
            },
            "open.control.local_options[\"obstacle_weight\"] -0.5 must be >= 0");
  open_case("FIRAS infinite influence",
            [&](auto& r) {
              control(r)->set_local_planner(v1::LOCAL_PLANNER_FIRAS);
              (*control(r)->mutable_local_options())["influence"] = kInf;
            },
            "open.control.local_options[\"influence\"] inf must be finite");
  open_case("FIRAS option for DWA",
            [&](auto& r) {
              control(r)->set_local_planner(v1::LOCAL_PLANNER_DWA);
              (*control(r)->mutable_local_options())["repulsion"] = 1;
            },
            "open.control.local_options[\"repulsion\"] is not an option of dwa");
  open_case("no robot size",
            [&](auto& r) { r.mutable_open()->mutable_options()->clear_robot_radius_m(); },
            "open.options.robot_radius: a control session needs the robot's size");
  open_case("kinematic planner",
            [&](auto& r) { r.mutable_open()->set_planner(v1::PLANNER_HYBRID_ASTAR); },
            "open.control: a control session follows a dstar_lite path");
  open_case("negative replan_max_expansions",
            [&](auto& r) { r.mutable_open()->set_replan_max_expansions(-1); },
            "open.replan_max_expansions -1 must be >= 0");

  // ---- RobotState ----
  const auto state_case = [&](const std::string& what,
                              std::function<void(v1::RobotState&)> edit,
                              const std::string& message) {
    v1::NavigateRequest state = GoodState();
    edit(*state.mutable_state());
    const v1::NavigateRequest open = ControlOpen(GoodPlan());
    cases.push_back({"Navigate", "state: " + what,
                     [open, state, this] { return Navigate({open, state}); },
                     StatusCode::INVALID_ARGUMENT, message});
  };
  cases.push_back({"Navigate", "state: before open",
                   [this] { return Navigate({GoodState()}); }, StatusCode::INVALID_ARGUMENT,
                   "the first message of a session must be 'open'"});
  cases.push_back({"Navigate", "state: in a session without control",
                   [this] { return NavigateThen(GoodState()); },
                   StatusCode::INVALID_ARGUMENT,
                   "state is only for control sessions (open.control)"});
  state_case("pose unset", [](v1::RobotState& s) { s.clear_pose(); }, "state.pose is not set");
  state_case("infinite pose", [](v1::RobotState& s) {
    s.mutable_pose()->mutable_world_pose()->set_x(kInf);
  }, "state.pose world pose (inf");
  state_case("pose off the map", [](v1::RobotState& s) {
    s.mutable_pose()->mutable_world_pose()->set_x(100);
  }, "state.pose");
  state_case("NaN v", [](v1::RobotState& s) { s.set_v(kNaN); }, "state.v nan must be finite");
  state_case("vy of a differential robot", [](v1::RobotState& s) { s.set_vy(0.2); },
             "state.vy 0.2: the robot is not holonomic");
  state_case("infinite w", [](v1::RobotState& s) { s.set_w(-kInf); },
             "state.w -inf must be finite");
  state_case("NaN stamp", [](v1::RobotState& s) { s.set_stamp(kNaN); },
             "state.stamp nan must be finite");
  state_case("obstacle without a position", [](v1::RobotState& s) { s.add_obstacles(); },
             "state.obstacles[0].position is not set");
  state_case("obstacle with NaN velocity", [](v1::RobotState& s) {
    v1::MovingObstacleReport* o = s.add_obstacles();
    o->mutable_position()->mutable_world()->set_x(3);
    o->mutable_position()->mutable_world()->set_y(3);
    o->set_vx(kNaN);
  }, "state.obstacles[0].vx, vy (nan, 0) must be finite");
  state_case("second obstacle with a negative radius", [](v1::RobotState& s) {
    for (int i = 0; i < 2; ++i) {
      v1::MovingObstacleReport* o = s.add_obstacles();
      o->mutable_position()->mutable_world()->set_x(3);
      o->mutable_position()->mutable_world()->set_y(3);
      o->set_radius(i == 0 ? 0.3 : -0.3);
    }
  }, "state.obstacles[1].radius -0.3 must be finite and >= 0 (metres)");
}

}  // namespace pathd::bad_input_test
