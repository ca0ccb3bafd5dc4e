// `pathctl simulate`: simulated robots driven by pathd's control sessions.
// This file holds what needs no server: the scenario file, the robots'
// motion, and the referee that watches the run (separation, contact with
// the map, arrivals, deadlocks). simulate_cmd.cc connects it to the real
// Navigate streams. The referee shares no code with the server's local
// planners: it judges their commands by the robots' integrated motion.
#ifndef PATHD_CLIENT_PATHCTL_SIMULATE_H_
#define PATHD_CLIENT_PATHCTL_SIMULATE_H_

#include <array>
#include <cstdint>
#include <map>
#include <utility>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/map/grid.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::pathctl {

// One simulated robot as the scenario describes it; metres, radians,
// seconds, map frame.
struct SimRobotSpec {
  std::string name;
  double start_x = 0.0;
  double start_y = 0.0;
  double start_yaw = 0.0;
  double goal_x = 0.0;
  double goal_y = 0.0;
  double radius = 0.25;
  // How close to its goal the robot stops (sent to the local planner as its
  // goal_tolerance).
  double goal_tolerance = 0.15;
  // The global path's inflation radius (Nav2's inflation costs keep it off
  // walls, so that the local planner has room beside it); not above the
  // radius: none.
  double inflation_radius = 0.0;
  v1::LocalPlanner local_planner = v1::LOCAL_PLANNER_ORCA;
  // Every limit explicit (the scenario's, else the simulator's defaults,
  // which are the server's documented ones), so the referee can check each
  // command against them.
  v1::VelocityLimits limits;
  std::map<std::string, double> local_options;
};

// A moving obstacle that is not a robot in a session (a person): a disc
// moving in a straight line at constant velocity, through walls too; it
// does not react. Robots see it within SimScenario::sensor_range.
struct SimObstacleSpec {
  double x = 0.0;
  double y = 0.0;
  double vx = 0.0;
  double vy = 0.0;
  double radius = 0.3;
};

struct SimScenario {
  std::string map;
  // A map file (.map, or map_server .yaml) to create the map from when the
  // server has no map of that name, relative to the scenario's folder; and
  // the metres per cell of a .map file.
  std::string map_file;
  double map_resolution = 1.0;
  // Integration step, and the control period (every robot's): the robots
  // send their state every period and hold the answer's command for it.
  double step = 0.02;
  double control_period = 0.1;
  // Simulated seconds at most.
  double duration = 120.0;
  // A robot that has not arrived and moved less than deadlock_distance over
  // the last deadlock_window seconds is stuck; the run ends early when every
  // robot has arrived, is stuck, or has no path.
  double deadlock_window = 10.0;
  double deadlock_distance = 0.25;
  double sensor_range = 5.0;
  std::vector<SimRobotSpec> robots;
  std::vector<SimObstacleSpec> obstacles;
};

// The scenario of a YAML document (docs/pathctl.md, "Simulating robots"
// lists the keys). INVALID_ARGUMENT "<source>: <key>: ..." naming the key
// (and the robot by index and name) for a missing, unknown or bad value.
absl::StatusOr<SimScenario> ParseScenario(const std::string& yaml_text,
                                          const std::string& source);

// A robot's pose and body-frame velocity, map frame, metres.
struct SimPose {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
};

// The pose after `seconds` at the body-frame velocity (v forward, vy left, w
// counter-clockwise), integrated exactly: an arc for a turning robot, a line
// otherwise (the omnidirectional case rotates (v, vy) with the heading).
SimPose IntegrateBody(const SimPose& pose, double v, double vy, double w,
                      double seconds);

// Why a command breaks the robot's limits (|v|, |vy|, |w| and the change
// from the previous command over one period, with 1e-6 of slack); empty
// when it does not.
std::string LimitViolation(const v1::VelocityLimits& limits, double v,
                           double vy, double w, double prev_v, double prev_vy,
                           double prev_w, double period);

// How a robot's run ended.
enum class SimEnd {
  kArrived,
  kUnreachable,  // the server found no global path to its goal
  kDeadlocked,   // stuck for deadlock_window at the end of the run
  kTimedOut,     // still moving when the duration ran out
};
const char* SimEndName(SimEnd end);

// One robot's record of the run.
struct SimRobotResult {
  SimEnd end = SimEnd::kTimedOut;
  double arrival_time = -1.0;  // seconds; -1 when it did not arrive
  double distance = 0.0;       // metres driven
  double path_length = 0.0;    // the global path's length at the start (m)
  double min_clearance = 1e300;  // smallest gap to another robot's disc (m)
  std::string detail;          // the reason for a non-arrival
  std::string limit_violation;  // the first command out of the limits
};

// Watches a run: called after every integration step with every robot's
// pose. Checks robot-robot separation (centres closer than the sum of radii
// is a collision), robot-map contact (a disc overlapping a lethal or
// unknown cell of `grid`) and robot-obstacle contact, and tracks progress
// for the deadlock rule. Independent of the local planners.
class SimReferee {
 public:
  SimReferee(const SimScenario& scenario, const Grid& grid);

  // Records the poses at time `t` (one per robot, then one point per moving
  // obstacle).
  void Observe(double t, const std::vector<SimPose>& robots,
               const std::vector<SimPose>& obstacles);
  // A robot reported arrival (the local planner said GOAL_REACHED) at `t`:
  // accepted when its centre is within its goal tolerance plus half a cell's
  // diagonal of its goal (the global path ends at the goal cell's centre).
  void ReportGoalReached(size_t robot, double t, const SimPose& pose);
  void SetUnreachable(size_t robot, const std::string& why);
  void SetPathLength(size_t robot, double metres);
  void CheckCommand(size_t robot, double v, double vy, double w);

  bool arrived(size_t robot) const { return results_[robot].arrival_time >= 0.0; }
  // Every robot has arrived, has no path, or is stuck now.
  bool AllSettled(double t) const;
  // Ends the run at `t`: classifies every robot that did not arrive.
  void Finish(double t);

  const std::vector<SimRobotResult>& results() const { return results_; }
  // Distinct collision events (a pair or a robot and the map/an obstacle
  // starting to touch); each listed once with its time.
  struct Contact {
    double t = 0.0;
    std::string what;
  };
  const std::vector<Contact>& contacts() const { return contacts_; }
  // Smallest centre distance minus radii between two robots over the run
  // (negative: overlap), and the pair and time.
  double min_separation() const { return min_separation_; }
  const std::string& min_separation_pair() const { return min_pair_; }
  double min_separation_time() const { return min_time_; }

 private:
  bool Stuck(size_t robot, double t) const;
  bool TouchesMap(const SimPose& pose, double radius) const;

  const SimScenario& scenario_;
  const Grid& grid_;
  std::vector<SimRobotResult> results_;
  std::vector<SimPose> last_;
  // Per robot: (t, x, y) once per control period, for the deadlock rule.
  struct Sample {
    double t, x, y;
  };
  std::vector<std::vector<Sample>> history_;
  std::vector<double> last_sample_t_;
  // Pairs (and robot-map, robot-obstacle) touching now, so a contact that
  // lasts is one event.
  std::map<std::pair<int64_t, int64_t>, bool> touching_;
  std::vector<Contact> contacts_;
  std::vector<std::array<double, 3>> prev_command_;
  double min_separation_ = 1e300;
  std::string min_pair_;
  double min_time_ = 0.0;
};

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_SIMULATE_H_
