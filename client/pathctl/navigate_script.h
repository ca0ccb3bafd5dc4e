// The script `pathctl navigate --script FILE` replays: a scripted robot run of
// moves, sensed cell changes, waits and expectations, parsed in full before
// anything is sent so a typo never leaves half a run on the server.
#ifndef PATHD_CLIENT_PATHCTL_NAVIGATE_SCRIPT_H_
#define PATHD_CLIENT_PATHCTL_NAVIGATE_SCRIPT_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::pathctl {

// How long `expect-push` waits when the line gives no time.
inline constexpr absl::Duration kDefaultExpectPushWait = absl::Milliseconds(1000);

// The script format, for --help and error messages.
inline constexpr char kNavigateScriptHelp[] =
    R"(navigate scripts: one command per line; '#' starts a comment, blank lines
are ignored; X Y are cells (x = column, y = row), COST as for maps set:
  move X Y             the robot is now at (X, Y): send a pose (kinematic
                       sessions keep the robot's heading)
  pose X Y YAW         the robot is at (X, Y) in cell coordinates (fractions
                       allowed) facing YAW radians: send a cell pose
  follow N             drive N steps along the last received path, one pose
                       per step (stops early at the goal); kinematic
                       sessions step from pose to pose of the path; fleet
                       sessions (--fleet) step along the timed path only as
                       far as released, waiting for the pushes that release
                       more
  block X Y            the sensors saw an obstacle (cost 254) at (X, Y)
  free X Y             ... saw (X, Y) free (cost 0)
  cost X Y COST        ... saw (X, Y) at COST
  rect X0 Y0 X1 Y1 COST  ... saw the rectangle with these corners at COST
  private block|free|cost|rect ...
                       the same, applied to this session only (session_only);
                       without 'private' the change also updates the shared
                       map, as 'maps set' would
  wait MS              sleep MS milliseconds, printing pushed paths meanwhile
  expect-push [MS]     fail (exit 1) unless an unasked MAP_CHANGED path (or a
                       fleet session's FLEET push) arrived since the previous
                       expect-push or arrives within MS milliseconds
                       (default 1000)
)";

// One script command.
struct ScriptStep {
  enum class Kind {
    kMove,        // cell
    kPose,        // pose
    kFollow,      // steps
    kObserve,     // observation
    kWait,        // duration
    kExpectPush,  // duration
  };
  Kind kind = Kind::kMove;
  // Where the step came from, "FILE:LINE", for messages.
  std::string where;
  // The line without its comment, for the run's log.
  std::string text;
  v1::Cell cell;
  v1::CellPose pose;
  int32_t steps = 0;
  v1::NavigateObservation observation;
  absl::Duration duration;
};

// Parses a whole script. `source_name` names it in messages (the file path).
// INVALID_ARGUMENT "SOURCE:LINE: <problem>" for the first bad line.
absl::StatusOr<std::vector<ScriptStep>> ParseNavigateScript(
    absl::string_view text, absl::string_view source_name);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_NAVIGATE_SCRIPT_H_
