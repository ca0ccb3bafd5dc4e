// pathctl simulate SCENARIO.yaml: runs the scenario's robots as control
// sessions of a running pathd, one Navigate stream each, in lock step: every
// control period each robot sends its state, every answer's command is held
// for the period and integrated (unicycle, or omnidirectional) at the
// scenario's step, and the referee (simulate.h) watches every step. Prints
// collisions, arrivals, time to goal, minimum separation and deadlocks;
// writes the trajectories (CSV, JSON) and a picture of the run.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "absl/synchronization/notification.h"
#include "client/pathctl/command.h"
#include "client/pathctl/files.h"
#include "client/pathctl/map_source.h"
#include "client/pathctl/png_io.h"
#include "client/pathctl/render.h"
#include "client/pathctl/simulate.h"
#include "google/protobuf/struct.pb.h"
#include "google/protobuf/util/json_util.h"

namespace pathd::pathctl {
namespace {

using Stream = grpc::ClientReaderWriterInterface<v1::NavigateRequest, v1::NavigateResponse>;

// One robot's stream.
struct Session {
  std::unique_ptr<grpc::ClientContext> context = std::make_unique<grpc::ClientContext>();
  std::unique_ptr<Stream> stream;
  bool ended = false;
};

// Cancels every stream when a cycle takes longer than `timeout` (a server
// that stopped answering), so a blocked Read returns.
class Watchdog {
 public:
  Watchdog(std::vector<Session>& sessions, absl::Duration timeout)
      : sessions_(sessions), timeout_(timeout), thread_([this] { Run(); }) {}
  ~Watchdog() {
    {
      absl::MutexLock lock(&mu_);
      stop_ = true;
    }
    thread_.join();
  }
  // A cycle (or the opening) started: the timer starts again.
  void Kick() {
    absl::MutexLock lock(&mu_);
    deadline_ = absl::Now() + timeout_;
  }
  bool fired() const { return fired_.load(); }

 private:
  void Run() {
    absl::MutexLock lock(&mu_);
    while (!stop_) {
      mu_.AwaitWithTimeout(absl::Condition(&stop_), absl::Milliseconds(50));
      if (!stop_ && absl::Now() > deadline_ && !fired_.load()) {
        fired_.store(true);
        for (Session& s : sessions_) s.context->TryCancel();
      }
    }
  }

  std::vector<Session>& sessions_;
  const absl::Duration timeout_;
  absl::Mutex mu_;
  bool stop_ ABSL_GUARDED_BY(mu_) = false;
  absl::Time deadline_ ABSL_GUARDED_BY(mu_) = absl::InfiniteFuture();
  std::atomic<bool> fired_{false};
  std::thread thread_;
};

v1::NavigateOpen OpenMessage(const SimScenario& scenario, const SimRobotSpec& robot) {
  v1::NavigateOpen open;
  open.set_map(scenario.map);
  v1::WorldPose* start = open.mutable_start()->mutable_world_pose();
  start->set_x(robot.start_x);
  start->set_y(robot.start_y);
  start->set_yaw(robot.start_yaw);
  v1::WorldPoint* goal = open.mutable_goal()->mutable_world();
  goal->set_x(robot.goal_x);
  goal->set_y(robot.goal_y);
  open.mutable_options()->set_robot_radius_m(robot.radius);
  if (robot.inflation_radius > robot.radius) {
    open.mutable_options()->set_inflation_radius_m(robot.inflation_radius);
  }
  v1::ControlOptions* control = open.mutable_control();
  control->set_local_planner(robot.local_planner);
  *control->mutable_limits() = robot.limits;
  control->set_control_period(scenario.control_period);
  // Every robot's stamp is the simulated time: the server moves the others
  // on by stamp differences, not by its own clock (which runs much faster
  // than the simulation).
  control->set_shared_clock(true);
  for (const auto& [name, value] : robot.local_options) {
    (*control->mutable_local_options())[name] = value;
  }
  if (!robot.local_options.contains("goal_tolerance")) {
    (*control->mutable_local_options())["goal_tolerance"] = robot.goal_tolerance;
  }
  return open;
}

// Reads until the answer of the message just written (skipping pushed
// paths). False when the stream ended.
bool ReadAnswer(Stream& stream, v1::NavigateResponse* response) {
  while (stream.Read(response)) {
    if (response->event() != v1::NAVIGATE_EVENT_MAP_CHANGED) return true;
  }
  return false;
}

std::string RobotLabel(const SimScenario& scenario, size_t i) {
  return absl::StrCat("robots[", i, "] (", scenario.robots[i].name, ")");
}

// Ends every stream: half-close, drain, Finish. The first error naming its
// robot, if a stream ended with one (after the run: CANCELLED from the
// watchdog is reported by the caller).
absl::Status CloseAll(std::vector<Session>& sessions, const SimScenario& scenario) {
  absl::Status first;
  for (size_t i = 0; i < sessions.size(); ++i) {
    Session& s = sessions[i];
    if (!s.stream) continue;
    if (!s.ended) {
      s.stream->WritesDone();
      v1::NavigateResponse ignored;
      while (s.stream->Read(&ignored)) {
      }
    }
    const grpc::Status status = s.stream->Finish();
    if (!status.ok() && first.ok()) {
      first = absl::Status(static_cast<absl::StatusCode>(status.error_code()),
                           absl::StrCat(RobotLabel(scenario, i), ": ", status.error_message()));
    }
  }
  return first;
}

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t k = std::min(values.size() - 1,
                            static_cast<size_t>(std::ceil(q * static_cast<double>(values.size()))) -
                                (q > 0.0 ? 1 : 0));
  return values[k];
}

const char* OutcomeName(v1::LocalOutcome outcome) {
  switch (outcome) {
    case v1::LOCAL_OUTCOME_OK:
      return "ok";
    case v1::LOCAL_OUTCOME_BLOCKED:
      return "blocked";
    case v1::LOCAL_OUTCOME_LOCAL_MINIMUM:
      return "local_minimum";
    case v1::LOCAL_OUTCOME_GOAL_REACHED:
      return "goal_reached";
    case v1::LOCAL_OUTCOME_NO_PATH:
      return "no_path";
    default:
      return "unspecified";
  }
}

const char* PlannerLabel(v1::LocalPlanner planner) {
  switch (planner) {
    case v1::LOCAL_PLANNER_DWA:
      return "dwa";
    case v1::LOCAL_PLANNER_FIRAS:
      return "firas";
    default:
      return "orca";
  }
}

// One trajectory sample.
struct Sample {
  double t;
  SimPose pose;
  double v, vy, w;
  v1::LocalOutcome outcome;
};

// Records what an answer says about the robot's global path: its length the
// first time one is found (the global path's length at the start), the
// reason when there is none.
void NoteGlobalPath(const v1::NavigateResponse& answer, size_t robot, SimReferee& referee,
                    std::vector<std::string>& no_path) {
  if (!answer.has_plan()) return;
  if (answer.plan().found()) {
    if (referee.results()[robot].path_length == 0.0) {
      referee.SetPathLength(robot, answer.plan().length_m());
    }
  } else {
    no_path[robot] = answer.plan().reason().empty() ? std::string("no reason given")
                                                    : answer.plan().reason();
  }
  if (answer.has_command() && answer.command().outcome() == v1::LOCAL_OUTCOME_NO_PATH &&
      !answer.command().reason().empty()) {
    no_path[robot] = answer.command().reason();
  }
}

google::protobuf::Value NumberValue(double x) {
  google::protobuf::Value v;
  v.set_number_value(x);
  return v;
}
google::protobuf::Value StringValue(const std::string& s) {
  google::protobuf::Value v;
  v.set_string_value(s);
  return v;
}

int RunSimulate(CommandEnv& env, Args args) {
  if (args.size() != 1) return env.Usage("simulate takes one SCENARIO.yaml");
  const SimulateOptions& o = env.options().simulate;
  absl::StatusOr<std::string> text = ReadTextFile(args[0]);
  if (!text.ok()) return env.Fail(text.status());
  absl::StatusOr<SimScenario> parsed = ParseScenario(*text, args[0]);
  if (!parsed.ok()) return env.Usage(parsed.status().message());
  const SimScenario& scenario = *parsed;
  const size_t n = scenario.robots.size();

  absl::StatusOr<Grid> grid = FetchGrid(env, scenario.map);
  if (!grid.ok() && grid.status().code() == absl::StatusCode::kNotFound &&
      !scenario.map_file.empty()) {
    // The scenario brings its map: create it, then read it back.
    v1::CreateMapRequest create;
    create.set_name(scenario.map);
    create.set_resolution(scenario.map_resolution);
    if (absl::Status s = SetMapSourceFromFile(scenario.map_file, &create); !s.ok()) {
      return env.Fail(s);
    }
    absl::StatusOr<v1::CreateMapResponse> created = env.client().CreateMap(create);
    if (!created.ok()) return env.Fail(created.status());
    env.err() << "created map " << scenario.map << " from " << scenario.map_file << "\n";
    grid = FetchGrid(env, scenario.map);
  }
  if (!grid.ok()) return env.Fail(grid.status());
  if (grid->frame_yaw() != 0.0) {
    return env.Fail(absl::FailedPreconditionError(
        "simulate: the map's world frame is rotated (pathd --honour_origin_yaw); the "
        "simulator's referee works in the unrotated frame"));
  }

  const client::PathdClient& client = env.client();
  std::vector<Session> sessions(n);
  SimReferee referee(scenario, *grid);
  std::vector<SimPose> poses(n);
  std::vector<std::array<double, 3>> command(n, {0.0, 0.0, 0.0});
  std::vector<v1::LocalOutcome> outcome(n, v1::LOCAL_OUTCOME_UNSPECIFIED);
  std::vector<std::vector<Sample>> trails(n);
  // Why the server last said a robot has no global path.
  std::vector<std::string> no_path(n);
  int64_t messages = 0;
  std::vector<double> cycle_ms;
  const auto wall_start = std::chrono::steady_clock::now();

  absl::Status failure;
  double t = 0.0;
  {
    Watchdog watchdog(sessions, client.timeout());
    watchdog.Kick();
    // Open every session: the server plans each robot's global path.
    for (size_t i = 0; i < n && failure.ok(); ++i) {
      const SimRobotSpec& r = scenario.robots[i];
      poses[i] = {r.start_x, r.start_y, r.start_yaw};
      sessions[i].stream = client.Navigate(sessions[i].context.get(), scenario.map);
      v1::NavigateRequest open;
      open.set_seq(1);
      *open.mutable_open() = OpenMessage(scenario, r);
      v1::NavigateResponse answer;
      if (!sessions[i].stream->Write(open) || !ReadAnswer(*sessions[i].stream, &answer)) {
        sessions[i].ended = true;
        const grpc::Status status = sessions[i].stream->Finish();
        sessions[i].stream.reset();
        failure = absl::Status(
            static_cast<absl::StatusCode>(status.error_code()),
            absl::StrCat(RobotLabel(scenario, i), ": ",
                         watchdog.fired() ? "no answer within --timeout" : status.error_message()));
        break;
      }
      ++messages;
      NoteGlobalPath(answer, i, referee, no_path);
    }
    const int sub_steps =
        std::max(1, static_cast<int>(std::lround(scenario.control_period / scenario.step)));
    const double dt = scenario.control_period / sub_steps;
    std::vector<SimPose> obstacles(scenario.obstacles.size());
    for (size_t k = 0; k < obstacles.size(); ++k) {
      obstacles[k] = {scenario.obstacles[k].x, scenario.obstacles[k].y, 0.0};
    }
    referee.Observe(0.0, poses, obstacles);
    uint64_t seq = 1;
    while (failure.ok() && t < scenario.duration - 1e-9) {
      watchdog.Kick();
      const auto cycle_start = std::chrono::steady_clock::now();
      ++seq;
      // Every state first, so that the server works on all robots at once.
      for (size_t i = 0; i < n && failure.ok(); ++i) {
        v1::NavigateRequest message;
        message.set_seq(seq);
        v1::RobotState* state = message.mutable_state();
        v1::WorldPose* pose = state->mutable_pose()->mutable_world_pose();
        pose->set_x(poses[i].x);
        pose->set_y(poses[i].y);
        pose->set_yaw(poses[i].yaw);
        state->set_v(command[i][0]);
        state->set_vy(command[i][1]);
        state->set_w(command[i][2]);
        state->set_stamp(t);
        for (size_t k = 0; k < obstacles.size(); ++k) {
          if (std::hypot(obstacles[k].x - poses[i].x, obstacles[k].y - poses[i].y) >
              scenario.sensor_range) {
            continue;
          }
          v1::MovingObstacleReport* report = state->add_obstacles();
          report->mutable_position()->mutable_world()->set_x(obstacles[k].x);
          report->mutable_position()->mutable_world()->set_y(obstacles[k].y);
          report->set_vx(scenario.obstacles[k].vx);
          report->set_vy(scenario.obstacles[k].vy);
          report->set_radius(scenario.obstacles[k].radius);
        }
        if (!sessions[i].stream->Write(message)) {
          sessions[i].ended = true;
          failure = absl::UnavailableError(
              absl::StrCat(RobotLabel(scenario, i), ": the stream ended"));
        }
      }
      for (size_t i = 0; i < n && failure.ok(); ++i) {
        v1::NavigateResponse answer;
        if (!ReadAnswer(*sessions[i].stream, &answer)) {
          sessions[i].ended = true;
          const grpc::Status status = sessions[i].stream->Finish();
          sessions[i].stream.reset();
          failure = absl::Status(
              static_cast<absl::StatusCode>(status.error_code()),
              absl::StrFormat("%s at t = %.2f s: %s", RobotLabel(scenario, i), t,
                              watchdog.fired() ? "no answer within --timeout"
                                               : status.error_message()));
          break;
        }
        ++messages;
        NoteGlobalPath(answer, i, referee, no_path);
        const v1::VelocityCommand& c = answer.command();
        command[i] = {c.v(), c.vy(), c.w()};
        outcome[i] = c.outcome();
        referee.CheckCommand(i, c.v(), c.vy(), c.w());
        if (c.outcome() == v1::LOCAL_OUTCOME_GOAL_REACHED) {
          referee.ReportGoalReached(i, t, poses[i]);
        }
        trails[i].push_back({t, poses[i], c.v(), c.vy(), c.w(), c.outcome()});
      }
      if (!failure.ok()) break;
      cycle_ms.push_back(std::chrono::duration<double, std::milli>(
                             std::chrono::steady_clock::now() - cycle_start)
                             .count());
      for (int s = 0; s < sub_steps; ++s) {
        for (size_t i = 0; i < n; ++i) {
          poses[i] = IntegrateBody(poses[i], command[i][0], command[i][1], command[i][2], dt);
        }
        for (size_t k = 0; k < obstacles.size(); ++k) {
          obstacles[k].x += scenario.obstacles[k].vx * dt;
          obstacles[k].y += scenario.obstacles[k].vy * dt;
        }
        t += dt;
        referee.Observe(t, poses, obstacles);
      }
      if (referee.AllSettled(t)) break;
    }
    absl::Status closed = CloseAll(sessions, scenario);
    if (failure.ok() && !closed.ok() && closed.code() != absl::StatusCode::kCancelled) {
      failure = closed;
    }
  }
  if (!failure.ok()) return env.Fail(failure);
  // A robot whose last command said there is no global path is unreachable
  // (a goal that became reachable later is not: the robot drove on).
  for (size_t i = 0; i < n; ++i) {
    if (!referee.arrived(i) && outcome[i] == v1::LOCAL_OUTCOME_NO_PATH) {
      referee.SetUnreachable(i, absl::StrCat("no global path: ", no_path[i]));
    }
  }
  referee.Finish(t);
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  // Trajectories.
  if (!o.trajectory.empty()) {
    Table table({"t", "robot", "x", "y", "yaw", "v", "vy", "w", "outcome"});
    for (size_t i = 0; i < n; ++i) {
      for (const Sample& s : trails[i]) {
        table.AddRow({absl::StrFormat("%.3f", s.t), scenario.robots[i].name,
                      absl::StrFormat("%.4f", s.pose.x), absl::StrFormat("%.4f", s.pose.y),
                      absl::StrFormat("%.4f", s.pose.yaw), absl::StrFormat("%.4f", s.v),
                      absl::StrFormat("%.4f", s.vy), absl::StrFormat("%.4f", s.w),
                      OutcomeName(s.outcome)});
      }
    }
    if (absl::Status s = WriteTextFile(o.trajectory, table.Csv()); !s.ok()) return env.Fail(s);
  }

  // The summary as a JSON-able Struct (protobuf's JSON printer writes it).
  const std::vector<SimRobotResult>& results = referee.results();
  google::protobuf::Struct summary;
  auto& f = *summary.mutable_fields();
  f["map"] = StringValue(scenario.map);
  f["simulated_s"] = NumberValue(t);
  f["wall_s"] = NumberValue(wall_s);
  f["messages"] = NumberValue(static_cast<double>(messages));
  f["cycle_ms_p50"] = NumberValue(Percentile(cycle_ms, 0.5));
  f["cycle_ms_p99"] = NumberValue(Percentile(cycle_ms, 0.99));
  int arrived = 0, violations = 0;
  double sum_arrival = 0.0, max_arrival = 0.0;
  google::protobuf::ListValue* robots_json = f["robots"].mutable_list_value();
  for (size_t i = 0; i < n; ++i) {
    const SimRobotResult& r = results[i];
    if (r.end == SimEnd::kArrived) {
      ++arrived;
      sum_arrival += r.arrival_time;
      max_arrival = std::max(max_arrival, r.arrival_time);
    }
    if (!r.limit_violation.empty()) ++violations;
    google::protobuf::Struct robot;
    auto& rf = *robot.mutable_fields();
    rf["name"] = StringValue(scenario.robots[i].name);
    rf["local_planner"] = StringValue(PlannerLabel(scenario.robots[i].local_planner));
    rf["end"] = StringValue(SimEndName(r.end));
    rf["arrival_s"] = NumberValue(r.arrival_time);
    rf["driven_m"] = NumberValue(r.distance);
    rf["path_m"] = NumberValue(r.path_length);
    rf["min_clearance_m"] = NumberValue(n > 1 ? r.min_clearance : 0.0);
    rf["detail"] = StringValue(r.detail);
    rf["limit_violation"] = StringValue(r.limit_violation);
    rf["last_outcome"] = StringValue(OutcomeName(outcome[i]));
    *robots_json->add_values()->mutable_struct_value() = std::move(robot);
  }
  f["arrived"] = NumberValue(arrived);
  f["collisions"] = NumberValue(static_cast<double>(referee.contacts().size()));
  google::protobuf::ListValue* contacts_json = f["contacts"].mutable_list_value();
  for (const SimReferee::Contact& c : referee.contacts()) {
    contacts_json->add_values()->set_string_value(absl::StrFormat("t=%.2f s: %s", c.t, c.what));
  }
  f["min_separation_m"] = NumberValue(n > 1 ? referee.min_separation() : 0.0);
  f["min_separation_pair"] = StringValue(referee.min_separation_pair());
  f["limit_violations"] = NumberValue(violations);

  if (!o.log_json.empty()) {
    google::protobuf::Struct log = summary;
    google::protobuf::ListValue* robots = (*log.mutable_fields())["trajectories"].mutable_list_value();
    for (size_t i = 0; i < n; ++i) {
      google::protobuf::Struct robot;
      (*robot.mutable_fields())["name"] = StringValue(scenario.robots[i].name);
      google::protobuf::ListValue* samples =
          (*robot.mutable_fields())["samples"].mutable_list_value();
      for (const Sample& s : trails[i]) {
        google::protobuf::ListValue* row = samples->add_values()->mutable_list_value();
        for (double x : {s.t, s.pose.x, s.pose.y, s.pose.yaw, s.v, s.vy, s.w}) {
          row->add_values()->set_number_value(x);
        }
      }
      *robots->add_values()->mutable_struct_value() = std::move(robot);
    }
    std::string json;
    if (!google::protobuf::util::MessageToJsonString(log, &json).ok()) {
      return env.Fail(absl::InternalError("simulate: the trajectory log did not print as JSON"));
    }
    if (absl::Status s = WriteTextFile(o.log_json, json + "\n"); !s.ok()) return env.Fail(s);
  }

  // The picture: each robot's trail in its colour over the map.
  if (!env.options().render.out.empty()) {
    PlanOverlay overlay;
    for (size_t i = 0; i < n; ++i) {
      SimTrail trail;
      trail.radius = scenario.robots[i].radius / grid->resolution();
      for (const Sample& s : trails[i]) {
        trail.points.push_back(grid->WorldToCellPoint({s.pose.x, s.pose.y}));
      }
      trail.points.push_back(grid->WorldToCellPoint({poses[i].x, poses[i].y}));
      trail.goal = grid->WorldToCellPoint({scenario.robots[i].goal_x, scenario.robots[i].goal_y});
      overlay.trails.push_back(std::move(trail));
    }
    RenderOptions render_options;
    render_options.scale = env.options().render.scale;
    render_options.y_up = env.options().render.y_up;
    absl::StatusOr<Image> image = RenderImage(*grid, overlay, render_options);
    if (!image.ok()) return env.Usage(image.status().message());
    if (absl::Status s = WritePngFile(*image, env.options().render.out); !s.ok()) {
      return env.Fail(s);
    }
  }

  const int code = referee.contacts().empty() && arrived == static_cast<int>(n)
                       ? kExitOk
                       : kExitSimulationFailed;
  if (env.json()) {
    const int printed = env.PrintJson(summary);
    return printed != kExitOk ? printed : code;
  }
  std::ostream& out = env.out();
  out << absl::StrFormat("map %s, %d robots, %d moving obstacles\n", scenario.map, n,
                         scenario.obstacles.size());
  out << absl::StrFormat(
      "simulated:      %.1f s in %.1f s wall (%d messages; a control cycle of all robots "
      "p50 %.2f ms, p99 %.2f ms)\n",
      t, wall_s, messages, Percentile(cycle_ms, 0.5), Percentile(cycle_ms, 0.99));
  out << absl::StrFormat("arrived:        %d / %d", arrived, n);
  if (arrived > 0) {
    out << absl::StrFormat(" (time to goal mean %.1f s, max %.1f s)", sum_arrival / arrived,
                           max_arrival);
  }
  out << absl::StrFormat("\ncollisions:     %d\n", referee.contacts().size());
  for (const SimReferee::Contact& c : referee.contacts()) {
    out << absl::StrFormat("  t = %.2f s: %s\n", c.t, c.what);
  }
  if (n > 1) {
    out << absl::StrFormat("min separation: %.3f m (%s at %.2f s)\n", referee.min_separation(),
                           referee.min_separation_pair(), referee.min_separation_time());
  }
  int not_arrived = 0;
  for (size_t i = 0; i < n; ++i) not_arrived += results[i].end != SimEnd::kArrived;
  out << absl::StrFormat("not arrived:    %d\n", not_arrived);
  for (size_t i = 0; i < n; ++i) {
    if (results[i].end == SimEnd::kArrived) continue;
    out << absl::StrFormat("  %s: %s: %s\n", scenario.robots[i].name, SimEndName(results[i].end),
                           results[i].detail);
  }
  if (violations > 0) {
    out << absl::StrFormat("commands beyond the robot's limits: %d robots\n", violations);
    for (size_t i = 0; i < n; ++i) {
      if (results[i].limit_violation.empty()) continue;
      out << absl::StrFormat("  %s: %s\n", scenario.robots[i].name, results[i].limit_violation);
    }
  }
  Table table({"robot", "local", "end", "time (s)", "driven (m)", "path (m)", "driven/path",
               "min gap (m)"});
  for (size_t i = 0; i < n; ++i) {
    const SimRobotResult& r = results[i];
    table.AddRow({scenario.robots[i].name, PlannerLabel(scenario.robots[i].local_planner),
                  SimEndName(r.end),
                  r.arrival_time >= 0.0 ? absl::StrFormat("%.1f", r.arrival_time) : "-",
                  absl::StrFormat("%.2f", r.distance),
                  r.path_length > 0.0 ? absl::StrFormat("%.2f", r.path_length) : "-",
                  r.path_length > 0.0 ? absl::StrFormat("%.2f", r.distance / r.path_length) : "-",
                  n > 1 ? absl::StrFormat("%.3f", r.min_clearance) : "-"});
  }
  out << "\n" << table.Aligned();
  if (!o.trajectory.empty()) out << "wrote " << o.trajectory << "\n";
  if (!o.log_json.empty()) out << "wrote " << o.log_json << "\n";
  if (!env.options().render.out.empty()) out << "wrote " << env.options().render.out << "\n";
  return code;
}

constexpr absl::string_view kSimulateFlags[] = {"trajectory", "log_json", "out", "o",
                                                "scale",      "y_up"};

}  // namespace

const Command kSimulateCommand = {
    .name = "simulate",
    .synopsis = "SCENARIO.yaml [--trajectory FILE.csv] [--log_json FILE.json]\n"
                " [-o FILE.png [--scale N] [--y_up]]",
    .help = "Runs the robots of SCENARIO.yaml as control sessions of the server (one\n"
            "Navigate stream each, local planner dwa, orca or firas) in simulated time:\n"
            "every control period each robot sends its state and holds the command it\n"
            "gets, integrated as a unicycle (drive: diff) or an omnidirectional robot.\n"
            "Prints arrivals, time to goal, collisions (robots closer than the sum of\n"
            "their radii, a robot over an obstacle cell), the minimum separation and\n"
            "every robot that did not arrive with why (deadlock, unreachable, timed\n"
            "out). --trajectory writes one CSV row per robot and control period,\n"
            "--log_json the summary and trajectories, -o a picture of the run.\n"
            "Exit code 9 when a robot collided or did not arrive.",
    .flags = kSimulateFlags,
    .run = RunSimulate,
    .file_first = true,
};

}  // namespace pathd::pathctl
