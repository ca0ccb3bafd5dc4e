// Implementation of the pathctl navigate session driver.
#include "client/pathctl/navigate_session.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/strip.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "client/pathctl/text.h"
#include "google/protobuf/util/json_util.h"
#include "grpcpp/client_context.h"

namespace pathd::pathctl {
namespace {

// "1 cell", "2 cells".
std::string Count(int64_t n, absl::string_view noun) {
  return absl::StrCat(n, " ", noun, n == 1 ? "" : "s");
}

using Stream =
    grpc::ClientReaderWriterInterface<v1::NavigateRequest, v1::NavigateResponse>;

std::string FormatCell(const v1::Cell& cell) {
  return absl::StrFormat("(%d,%d)", cell.x(), cell.y());
}

// "OPENED" for NAVIGATE_EVENT_OPENED.
std::string EventName(v1::NavigateEvent event) {
  absl::string_view name = v1::NavigateEvent_Name(event);
  absl::ConsumePrefix(&name, "NAVIGATE_EVENT_");
  return name.empty() ? absl::StrCat(static_cast<int>(event)) : std::string(name);
}

// A position of the open message, for the log.
std::string FormatPosition(const v1::Position& position) {
  switch (position.kind_case()) {
    case v1::Position::kCell:
      return FormatCell(position.cell());
    case v1::Position::kWorld:
      return absl::StrFormat("(%g, %g) m", position.world().x(), position.world().y());
    case v1::Position::kWorldPose:
      return absl::StrFormat("(%g, %g) m facing %g rad", position.world_pose().x(),
                             position.world_pose().y(), position.world_pose().yaw());
    case v1::Position::kCellPose:
      return absl::StrFormat("(%g, %g) facing %g rad", position.cell_pose().x(),
                             position.cell_pose().y(), position.cell_pose().yaw());
    case v1::Position::KIND_NOT_SET:
      break;
  }
  return "(unset)";
}

std::string FormatPose(const v1::CellPose& p) {
  return absl::StrFormat("(%.2f,%.2f,%.3f)", p.x(), p.y(), p.yaw());
}

// A kinematic session's answer carries its poses, its budget and the pose
// it planned from.
bool IsKinematicAnswer(const v1::NavigateResponse& response) {
  return response.replan_max_expansions() > 0;
}

// One response as two lines: what happened and the path (kinematic
// sessions: three, the poses too).
std::string FormatResponse(const v1::NavigateResponse& response, bool world) {
  const v1::PlanResponse& plan = response.plan();
  std::string text = absl::StrFormat(
      "[%s%s] seq %d, session %d, map version %d: ", EventName(response.event()),
      response.event() == v1::NAVIGATE_EVENT_MAP_CHANGED ||
              response.event() == v1::NAVIGATE_EVENT_FLEET
          ? ", unasked"
          : "",
      response.seq(), response.session_id(), plan.map_version());
  if (plan.found()) {
    absl::StrAppendFormat(&text, "found, cost %.6f, %d cells", plan.cost(),
                          plan.path_size());
  } else if (response.has_fleet()) {
    absl::StrAppend(&text, "waiting for the group's plan");
  } else if (response.kept_previous_path()) {
    absl::string_view outcome = v1::PlanOutcome_Name(plan.outcome());
    absl::ConsumePrefix(&outcome, "PLAN_OUTCOME_");
    absl::StrAppendFormat(&text, "replan stopped (%s), kept the previous path, %d cells",
                          outcome, plan.path_size());
  } else {
    absl::string_view outcome = v1::PlanOutcome_Name(plan.outcome());
    absl::ConsumePrefix(&outcome, "PLAN_OUTCOME_");
    absl::StrAppend(&text, "no path (", outcome,
                    plan.reason().empty() ? "" : ": ", plan.reason(), ")");
  }
  absl::StrAppendFormat(&text, ", %d expansions", plan.expansions());
  if (plan.cache_hit()) absl::StrAppend(&text, ", cache hit");
  if (plan.repaired_cells() > 0) {
    absl::StrAppend(&text, ", ", Count(plan.repaired_cells(), "cell"), " repaired");
  }
  if (response.applied_version() > 0) {
    absl::StrAppend(&text, ", observation applied as map version ",
                    response.applied_version());
  }
  const bool kinematic = IsKinematicAnswer(response);
  if (kinematic) {
    absl::StrAppendFormat(&text, ", budget %d, from %s", response.replan_max_expansions(),
                          FormatPose(response.robot_pose()));
    if (plan.found() && response.kept_previous_path()) {
      absl::StrAppend(&text, ", the previous path (no dearer than the replan's)");
    }
  }
  text.push_back('\n');
  if (response.has_fleet()) {
    const v1::FleetSessionPlan& fleet = response.fleet();
    absl::StrAppendFormat(&text, "  fleet plan %d, %d robot(s): ", fleet.epoch(),
                          fleet.robots());
    if (fleet.path().cells_size() > 0) {
      absl::StrAppendFormat(&text, "at step %d of %d, released to step %d",
                            fleet.progress(), fleet.path().cells_size() - 1, fleet.release());
    }
    if (!fleet.planned()) {
      absl::StrAppend(&text, fleet.path().cells_size() > 0 ? "; " : "",
                      "not planned: ", fleet.reason());
    }
    text.push_back('\n');
    if (fleet.path().cells_size() > 0) {
      absl::StrAppend(&text, "  timed path (", fleet.path().cells_size(),
                      " steps): ", FormatPath(fleet.path().cells()), "\n");
    }
  }
  if (plan.found()) {
    absl::StrAppend(&text, "  path (", plan.path_size(),
                    " cells): ", FormatPath(plan.path()), "\n");
  }
  if (kinematic && plan.poses_size() > 0) {
    std::vector<std::string> poses;
    poses.reserve(plan.poses_size());
    if (world) {
      for (const v1::WorldPose& p : plan.world_poses()) {
        poses.push_back(absl::StrFormat("(%.3f,%.3f,%.3f)", p.x(), p.y(), p.yaw()));
      }
    } else {
      for (const v1::CellPose& p : plan.poses()) poses.push_back(FormatPose(p));
    }
    absl::StrAppendFormat(&text, "  poses (%d, %g m, %s): %s\n", plan.poses_size(),
                          plan.length_m(), world ? "world x,y,yaw in m" : "cell x,y,yaw",
                          absl::StrJoin(poses, " "));
  }
  return text;
}

// One Navigate stream. The main thread writes (Write/WritesDone are never
// called concurrently with each other) while a reader thread reads and prints;
// gRPC allows one reader and one writer on a stream at the same time.
class Session {
 public:
  // `map`: the map `open` will name, which routes the stream.
  Session(const client::PathdClient& client, const std::string& map, bool json,
          std::ostream& out, bool world)
      : timeout_(client.timeout()),
        json_(json),
        world_(world),
        out_(out),
        stream_(client.Navigate(&context_, map)) {}

  absl::Status Run(const v1::NavigateOpen& open,
                   const std::vector<ScriptStep>& script) {
    reader_ = std::thread([this] { ReadLoop(); });
    absl::Status status = RunScript(open, script);
    if (status.ok()) status = Close();
    // A local failure leaves the stream open: cancelling ends it so the
    // reader stops and Finish() returns. A stream that already ended (the
    // reader will see it, if it has not yet) must not be cancelled, or
    // Finish() would report CANCELLED instead of the server's status.
    if (!status.ok() && !stream_lost_) {
      absl::MutexLock lock(&mu_);
      if (!ended_) context_.TryCancel();
    }
    reader_.join();
    const grpc::Status final_status = stream_->Finish();
    // The server's own error says more than "the stream ended".
    if (stream_lost_ && !final_status.ok()) {
      return client::FromGrpcStatus(final_status);
    }
    if (!status.ok()) return status;
    if (!final_status.ok()) return client::FromGrpcStatus(final_status);
    std::string summary;
    {
      absl::MutexLock lock(&mu_);
      summary = absl::StrCat("closed: ", Count(answers_, "answer"), ", ",
                             Count(pushes_total_, "unasked path"), "\n");
    }
    Log(summary);
    return absl::OkStatus();
  }

 private:
  absl::Status RunScript(const v1::NavigateOpen& open,
                         const std::vector<ScriptStep>& script) {
    robot_ = open.start().cell();
    robot_pose_.set_x(robot_.x() + 0.5);
    robot_pose_.set_y(robot_.y() + 0.5);
    if (open.start().has_cell_pose()) robot_pose_ = open.start().cell_pose();
    v1::NavigateRequest request;
    *request.mutable_open() = open;
    Log(absl::StrFormat("> open %s %s -> %s\n", open.map(), FormatPosition(open.start()),
                        FormatPosition(open.goal())));
    if (absl::Status s = Exchange(request, "open"); !s.ok()) return s;
    {
      // A kinematic session says where it put the robot (a world start is
      // in metres here, in cells there).
      absl::MutexLock lock(&mu_);
      if (last_kinematic_) robot_pose_ = last_robot_pose_;
      if (open.start().has_world() && last_plan_.path_size() > 0) robot_ = last_plan_.path(0);
    }
    for (const ScriptStep& step : script) {
      if (absl::Status s = RunStep(step); !s.ok()) return s;
    }
    return absl::OkStatus();
  }

  absl::Status RunStep(const ScriptStep& step) {
    Log(absl::StrCat("> ", step.text, "\n"));
    switch (step.kind) {
      case ScriptStep::Kind::kMove:
        return Move(step.cell, step.where);
      case ScriptStep::Kind::kPose: {
        v1::NavigateRequest request;
        *request.mutable_pose()->mutable_cell_pose() = step.pose;
        if (absl::Status s = Exchange(request, step.where); !s.ok()) return s;
        robot_pose_ = step.pose;
        return absl::OkStatus();
      }
      case ScriptStep::Kind::kFollow:
        return Follow(step);
      case ScriptStep::Kind::kObserve: {
        v1::NavigateRequest request;
        *request.mutable_observe() = step.observation;
        return Exchange(request, step.where);
      }
      case ScriptStep::Kind::kWait: {
        absl::MutexLock lock(&mu_);
        mu_.AwaitWithTimeout(absl::Condition(&ended_), step.duration);
        return ended_ ? Lost() : absl::OkStatus();
      }
      case ScriptStep::Kind::kExpectPush: {
        absl::MutexLock lock(&mu_);
        auto pushed_or_ended = [this]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
          return unclaimed_pushes_ > 0 || ended_;
        };
        mu_.AwaitWithTimeout(absl::Condition(&pushed_or_ended), step.duration);
        if (unclaimed_pushes_ > 0) {
          --unclaimed_pushes_;
          return absl::OkStatus();
        }
        if (ended_) return Lost();
        return absl::DeadlineExceededError(absl::StrCat(
            step.where, ": expect-push: no unasked MAP_CHANGED path or FLEET push within ",
            absl::FormatDuration(step.duration)));
      }
    }
    return absl::InternalError("unknown script step");
  }

  absl::Status Move(const v1::Cell& cell, absl::string_view where) {
    v1::NavigateRequest request;
    *request.mutable_pose()->mutable_cell() = cell;
    if (absl::Status s = Exchange(request, where); !s.ok()) return s;
    robot_ = cell;
    robot_pose_.set_x(cell.x() + 0.5);
    robot_pose_.set_y(cell.y() + 0.5);
    return absl::OkStatus();
  }

  // A kinematic session's path is poses: each step sends the pose after the
  // one nearest the robot's.
  absl::Status FollowPoses(const ScriptStep& step, int32_t i, const v1::PlanResponse& plan) {
    int nearest = 0;
    double best = std::numeric_limits<double>::infinity();
    for (int k = 0; k < plan.poses_size(); ++k) {
      const double d = std::hypot(plan.poses(k).x() - robot_pose_.x(),
                                  plan.poses(k).y() - robot_pose_.y());
      if (d < best) {
        best = d;
        nearest = k;
      }
    }
    if (nearest + 1 >= plan.poses_size()) {
      Log(absl::StrFormat("  at the goal %s after %d of %d steps\n", FormatPose(robot_pose_), i,
                          step.steps));
      return absl::OutOfRangeError("at the goal");
    }
    const v1::CellPose next = plan.poses(nearest + 1);
    Log(absl::StrFormat("> step %d/%d: pose %s\n", i + 1, step.steps, FormatPose(next)));
    v1::NavigateRequest request;
    *request.mutable_pose()->mutable_cell_pose() = next;
    if (absl::Status s = Exchange(request, step.where); !s.ok()) return s;
    robot_pose_ = next;
    return absl::OkStatus();
  }

  bool FleetSession() {
    absl::MutexLock lock(&mu_);
    return last_fleet_.has_value();
  }

  // A fleet session's step: the next cell of its timed path up to its
  // release, waiting (up to the client timeout) for a push that releases
  // it; OutOfRange at the goal.
  absl::Status FollowFleet(const ScriptStep& step, int32_t i) {
    std::optional<v1::Cell> next;
    int64_t timed_step = 0;
    {
      absl::MutexLock lock(&mu_);
      for (;;) {
        const v1::FleetSessionPlan& fleet = *last_fleet_;
        const auto& cells = fleet.path().cells();
        if (fleet.planned() && fleet.progress() + 1 >= cells.size()) break;
        // Released cells are driven also while the group waits for a new
        // plan (planned false): it waits for the robots to finish them.
        for (int64_t t = fleet.progress() + 1; t <= fleet.release() && !next; ++t) {
          const v1::Cell& c = cells[static_cast<int>(t)];
          if (c.x() == robot_.x() && c.y() == robot_.y()) continue;
          next = c;
          timed_step = t;
        }
        if (next.has_value()) break;
        // Nothing released (or no plan yet): wait for the group's next push.
        const int64_t seen = fleet_updates_;
        auto pushed_or_ended = [this, seen]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
          return fleet_updates_ > seen || ended_;
        };
        if (!mu_.AwaitWithTimeout(absl::Condition(&pushed_or_ended), timeout_)) {
          return absl::DeadlineExceededError(
              absl::StrCat(step.where, ": follow: the fleet group released nothing within ",
                           absl::FormatDuration(timeout_)));
        }
        if (ended_) return Lost();
      }
    }
    if (!next.has_value()) {
      Log(absl::StrFormat("  at the goal %s after %d of %d steps\n", FormatCell(robot_), i,
                          step.steps));
      return absl::OutOfRangeError("at the goal");
    }
    Log(absl::StrFormat("> step %d/%d: pose %s (timed step %d)\n", i + 1, step.steps,
                        FormatCell(*next), timed_step));
    return Move(*next, step.where);
  }

  // Each step takes the cell after the robot's on the latest path, which may
  // be one the server pushed since the previous step.
  absl::Status Follow(const ScriptStep& step) {
    for (int32_t i = 0; i < step.steps; ++i) {
      v1::PlanResponse plan;
      bool last_kinematic;
      {
        absl::MutexLock lock(&mu_);
        plan = last_plan_;
        last_kinematic = last_kinematic_;
      }
      if (FleetSession()) {
        const absl::Status s = FollowFleet(step, i);
        if (absl::IsOutOfRange(s)) return absl::OkStatus();
        if (!s.ok()) return s;
        continue;
      }
      if (last_kinematic && plan.poses_size() > 0) {
        const absl::Status s = FollowPoses(step, i, plan);
        if (absl::IsOutOfRange(s)) return absl::OkStatus();
        if (!s.ok()) return s;
        continue;
      }
      if (!plan.found()) {
        return absl::FailedPreconditionError(
            absl::StrCat(step.where, ": follow: the last answer has no path to "
                                     "follow"));
      }
      const auto& path = plan.path();
      auto here = std::find_if(path.begin(), path.end(), [&](const v1::Cell& c) {
        return c.x() == robot_.x() && c.y() == robot_.y();
      });
      if (here == path.end()) {
        return absl::FailedPreconditionError(absl::StrCat(
            step.where, ": follow: the last path does not pass the robot's cell ",
            FormatCell(robot_)));
      }
      if (std::next(here) == path.end()) {
        Log(absl::StrFormat("  at the goal %s after %d of %d steps\n",
                            FormatCell(robot_), i, step.steps));
        return absl::OkStatus();
      }
      const v1::Cell next = *std::next(here);
      Log(absl::StrFormat("> step %d/%d: pose %s\n", i + 1, step.steps,
                          FormatCell(next)));
      if (absl::Status s = Move(next, step.where); !s.ok()) return s;
    }
    return absl::OkStatus();
  }

  // Sends `request` with the next seq and waits for its answer.
  absl::Status Exchange(v1::NavigateRequest& request, absl::string_view where) {
    const uint64_t seq = ++last_seq_;
    request.set_seq(seq);
    if (!stream_->Write(request)) return Lost();
    absl::MutexLock lock(&mu_);
    auto answered_or_ended = [this, seq]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
      return answered_seq_ >= seq || ended_;
    };
    if (!mu_.AwaitWithTimeout(absl::Condition(&answered_or_ended), timeout_)) {
      return absl::DeadlineExceededError(
          absl::StrCat(where, ": no answer to message ", seq, " within ",
                       absl::FormatDuration(timeout_)));
    }
    return answered_seq_ >= seq ? absl::OkStatus() : Lost();
  }

  // Closes the client side and waits for the server to end the stream.
  absl::Status Close() {
    if (!stream_->WritesDone()) return Lost();
    absl::MutexLock lock(&mu_);
    if (!mu_.AwaitWithTimeout(absl::Condition(&ended_), timeout_)) {
      return absl::DeadlineExceededError(
          absl::StrCat("the server did not end the session within ",
                       absl::FormatDuration(timeout_), " of the script's end"));
    }
    return absl::OkStatus();
  }

  // The stream ended before the script did; Run() reports the server's status
  // instead when it has one.
  absl::Status Lost() {
    stream_lost_ = true;
    return absl::UnavailableError(
        "the server ended the session before the script finished");
  }

  void ReadLoop() {
    v1::NavigateResponse response;
    while (stream_->Read(&response)) {
      absl::MutexLock lock(&mu_);
      PrintLocked(response);
      if (response.event() == v1::NAVIGATE_EVENT_MAP_CHANGED ||
          response.event() == v1::NAVIGATE_EVENT_FLEET) {
        ++unclaimed_pushes_;
        ++pushes_total_;
      } else {
        ++answers_;
        answered_seq_ = std::max(answered_seq_, response.seq());
      }
      last_plan_ = response.plan();
      if (response.has_fleet()) {
        last_fleet_ = response.fleet();
        ++fleet_updates_;
      }
      last_kinematic_ = IsKinematicAnswer(response);
      if (last_kinematic_) last_robot_pose_ = response.robot_pose();
    }
    absl::MutexLock lock(&mu_);
    ended_ = true;
  }

  void PrintLocked(const v1::NavigateResponse& response)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (!json_) {
      out_ << FormatResponse(response, world_) << std::flush;
      return;
    }
    google::protobuf::util::JsonPrintOptions options;
    options.always_print_primitive_fields = true;
    std::string line;
    if (google::protobuf::util::MessageToJsonString(response, &line, options)
            .ok()) {
      out_ << line << "\n" << std::flush;
    }
  }

  // Script progress lines; JSON output carries responses only.
  void Log(const std::string& text) {
    if (json_) return;
    absl::MutexLock lock(&mu_);
    out_ << text << std::flush;
  }

  const absl::Duration timeout_;
  const bool json_;
  const bool world_;
  grpc::ClientContext context_;
  std::ostream& out_;  // guarded by mu_ once the reader runs
  std::unique_ptr<Stream> stream_;
  std::thread reader_;

  // Main thread only.
  uint64_t last_seq_ = 0;
  v1::Cell robot_;
  // Kinematic sessions: the pose last sent (cell coordinates).
  v1::CellPose robot_pose_;
  bool stream_lost_ = false;

  absl::Mutex mu_;
  bool ended_ ABSL_GUARDED_BY(mu_) = false;
  uint64_t answered_seq_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t answers_ ABSL_GUARDED_BY(mu_) = 0;
  // MAP_CHANGED pushes not yet claimed by an expect-push.
  int64_t unclaimed_pushes_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t pushes_total_ ABSL_GUARDED_BY(mu_) = 0;
  v1::PlanResponse last_plan_ ABSL_GUARDED_BY(mu_);
  bool last_kinematic_ ABSL_GUARDED_BY(mu_) = false;
  // The pose a kinematic answer planned from (cell coordinates).
  v1::CellPose last_robot_pose_ ABSL_GUARDED_BY(mu_);
  // Fleet sessions: the latest fleet state, and how many have arrived.
  std::optional<v1::FleetSessionPlan> last_fleet_ ABSL_GUARDED_BY(mu_);
  int64_t fleet_updates_ ABSL_GUARDED_BY(mu_) = 0;
};

}  // namespace

absl::Status RunNavigateSession(const client::PathdClient& client,
                                const v1::NavigateOpen& open,
                                const std::vector<ScriptStep>& script, bool json,
                                std::ostream& out, bool world) {
  Session session(client, open.map(), json, out, world);
  return session.Run(open, script);
}

}  // namespace pathd::pathctl
