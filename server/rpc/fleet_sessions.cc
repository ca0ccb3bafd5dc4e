// FleetGroups (fleet_sessions.h): groups of fleet sessions, their joint
// plans and the releases along them.
#include "server/rpc/fleet_sessions.h"

#include <algorithm>
#include <optional>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/fleet/execution.h"
#include "core/search/endpoints.h"
#include "core/search/stop_condition.h"
#include "core/status_macros.h"
#include "server/convert.h"
#include "server/rpc/fleet_common.h"

namespace pathd::server {

struct FleetGroups::Group {
  struct Member {
    uint64_t id = 0;
    // Where it stands: its last reported cell (its start before that).
    Cell at;
    Cell goal;
    GridShape shape;
    // Its planning grid on `snapshot`.
    std::shared_ptr<const Grid> grid;
    Push push;
    // Its index in `schedule`; -1 before its first plan.
    int robot = -1;
    // The release last told: it only grows within a plan.
    int64_t granted = 0;
    // Its session ended; dropped at the next plan.
    bool gone = false;
  };

  std::string map;
  std::string name;
  FleetSolver solver = FleetSolver::kLacam;
  absl::Duration time_limit = kDefaultTimeLimit;
  CostParams cost;

  absl::Mutex mu;
  // Erased from the registry (no robot left): Add looks again.
  bool closed ABSL_GUARDED_BY(mu) = false;
  std::shared_ptr<const MapSnapshot> snapshot ABSL_GUARDED_BY(mu);
  std::vector<Member> members ABSL_GUARDED_BY(mu);
  std::optional<FleetSchedule> schedule ABSL_GUARDED_BY(mu);
  uint64_t epoch ABSL_GUARDED_BY(mu) = 0;
  // Frozen: plan again once every robot has finished its released moves.
  bool replan_wanted ABSL_GUARDED_BY(mu) = false;
  // Why the last plan failed; empty when it did not.
  std::string failure ABSL_GUARDED_BY(mu);

  Member* Find(uint64_t id) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    for (Member& m : members) {
      if (m.id == id && !m.gone) return &m;
    }
    return nullptr;
  }
  int Live() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return static_cast<int>(
        std::count_if(members.begin(), members.end(),
                      [](const Member& m) { return !m.gone; }));
  }
  // Robots still driving towards the end of a stretch they were released for.
  // A robot whose released stretch past its progress only waits where it
  // stands has nothing left to drive: it counts as settled.
  int Unsettled() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    if (!schedule.has_value()) return 0;
    int n = 0;
    for (const Member& m : members) {
      if (m.gone || m.robot < 0) continue;
      const std::vector<Cell>& path = schedule->path(m.robot);
      const int64_t progress = schedule->progress(m.robot);
      for (int64_t t = progress + 1; t <= m.granted; ++t) {
        if (path[t] != path[progress]) {
          ++n;
          break;
        }
      }
    }
    return n;
  }
};

namespace {

using Group = FleetGroups::Group;
using Member = Group::Member;

// The key of a group.
std::pair<std::string, std::string> KeyOf(std::string_view map,
                                          std::string_view group) {
  return {std::string(map), std::string(group)};
}


// The member's part of an answer or push: the fleet state and, in plan,
// found, the version and the rest of its path (waits folded).
void Fill(const Group& g, const Member& m, v1::NavigateResponse* out)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(g.mu) {
  v1::FleetSessionPlan& fleet = *out->mutable_fleet();
  fleet.set_epoch(g.epoch);
  fleet.set_robots(g.Live());
  const bool planned =
      g.schedule.has_value() && m.robot >= 0 && !g.replan_wanted;
  fleet.set_planned(planned);
  v1::PlanResponse& plan = *out->mutable_plan();
  const Grid& stored = *g.snapshot->grid;
  plan.set_map_version(g.snapshot->version);
  plan.set_frame_id(kFrameId);
  plan.set_planner("fleet");
  if (g.replan_wanted) {
    const int unsettled = g.Unsettled();
    fleet.set_reason(unsettled > 0
                         ? absl::StrFormat("the group is planned again once %d "
                                           "robot(s) have finished the "
                                           "moves they were released for",
                                           unsettled)
                         : std::string("the group is being planned again"));
  } else if (!g.failure.empty()) {
    fleet.set_reason(g.failure);
  }
  plan.set_found(planned);
  if (!planned) {
    plan.set_reason(fleet.reason());
    *plan.mutable_start() = ToProto(m.at);
    *plan.mutable_goal() = ToProto(m.goal);
  }
  if (!g.schedule.has_value() || m.robot < 0) return;
  const std::vector<Cell>& cells = g.schedule->path(m.robot);
  v1::FleetPath& path = *fleet.mutable_path();
  FillFleetPath(cells, stored, &path);
  path.set_radius_m(m.shape.robot_radius_cells * stored.resolution());
  const int64_t progress = g.schedule->progress(m.robot);
  fleet.set_progress(progress);
  fleet.set_release(m.granted);
  if (!planned) return;
  *plan.mutable_start() = ToProto(cells[progress]);
  *plan.mutable_goal() = ToProto(cells.back());
  std::vector<Cell> rest;
  for (size_t t = static_cast<size_t>(progress); t < cells.size(); ++t) {
    if (rest.empty() || rest.back() != cells[t]) rest.push_back(cells[t]);
  }
  for (const Cell c : rest) {
    *plan.add_path() = ToProto(c);
    const WorldPoint w = stored.CellCenter(c);
    v1::WorldPoint* p = plan.add_world_path();
    p->set_x(w.x);
    p->set_y(w.y);
  }
  const double rest_length = StepsLength(rest);
  plan.set_cost(rest_length);
  plan.set_length(rest_length);
  plan.set_length_m(rest_length * stored.resolution());
}

void PushTo(const Group& g, const Member& m)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(g.mu) {
  if (m.gone) return;
  v1::NavigateResponse push;
  push.set_event(v1::NAVIGATE_EVENT_FLEET);
  Fill(g, m, &push);
  m.push(std::move(push));
}

// The member's release now: as far as the schedule allows, at most
// kReleaseHorizon steps past its progress. Waits where it stands count as
// done first (the robot need not report its own cell again to pass them,
// and a wait ends no visit, so no other robot's release changes).
int64_t ReleaseOf(Group& g, const Member& m)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(g.mu) {
  FleetSchedule& schedule = *g.schedule;
  schedule.Report(m.robot, schedule.path(m.robot)[schedule.progress(m.robot)]);
  return std::min(schedule.Release(m.robot),
                  schedule.progress(m.robot) + FleetGroups::kReleaseHorizon);
}

// Raises every release the schedule allows (not while frozen); the members
// whose release grew, except `quiet`, are pushed.
void GrantAndPush(Group& g, uint64_t quiet)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(g.mu) {
  if (!g.schedule.has_value() || g.replan_wanted) return;
  for (Member& m : g.members) {
    if (m.gone || m.robot < 0) continue;
    const int64_t release = ReleaseOf(g, m);
    if (release <= m.granted) continue;
    m.granted = release;
    if (m.id != quiet) PushTo(g, m);
  }
}

// The member's planning grid on the group's snapshot.
absl::StatusOr<std::shared_ptr<const Grid>> GridFor(InflationCache& inflation,
                                                    const Group& g,
                                                    const GridShape& shape)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(g.mu) {
  if (!shape.shaped()) return g.snapshot->grid;
  return inflation.Get(*g.snapshot, shape);
}

// Plans the group from where its robots stand; pushes every robot but
// `quiet` (whose answer carries it).
void PlanGroup(Group& g, uint64_t quiet) ABSL_EXCLUSIVE_LOCKS_REQUIRED(g.mu) {
  g.members.erase(std::remove_if(g.members.begin(), g.members.end(),
                                 [](const Member& m) { return m.gone; }),
                  g.members.end());
  g.replan_wanted = false;
  g.failure.clear();
  g.schedule.reset();
  ++g.epoch;
  FleetProblem problem;
  problem.connectivity = g.cost.connectivity;
  problem.unknown_is_free = g.cost.unknown_is_free;
  std::vector<const Grid*> grids;
  for (Member& m : g.members) {
    m.robot = -1;
    m.granted = 0;
    auto it = std::find(grids.begin(), grids.end(), m.grid.get());
    if (it == grids.end()) it = grids.insert(grids.end(), m.grid.get());
    problem.robots.push_back(
        FleetRobot{m.at, m.goal, static_cast<int32_t>(it - grids.begin())});
  }
  problem.grids = grids;
  if (!g.members.empty()) {
    FleetOptions options;
    options.solver = g.solver;
    const StopCondition stop(absl::Now() + g.time_limit, nullptr,
                             /*max_expansions=*/0);
    absl::StatusOr<FleetPlan> plan = PlanFleet(problem, options, stop);
    if (!plan.ok()) {
      g.failure = std::string(plan.status().message());
    } else if (!plan->complete || plan->paths.size() != g.members.size()) {
      g.failure =
          plan->outcome == PlanOutcome::kTimeout
              ? absl::StrFormat(
                    "no conflict-free plan for the group's %d robots within %d "
                    "ms",
                    g.members.size(), absl::ToInt64Milliseconds(g.time_limit))
              : absl::StrFormat(
                    "no conflict-free plan for the group's %d robots (%s): a "
                    "goal is "
                    "unreachable, or the robots cannot all reach their goals",
                    g.members.size(), FleetSolverName(g.solver));
    } else {
      g.schedule.emplace(plan->paths, g.snapshot->grid->width());
      for (size_t i = 0; i < g.members.size(); ++i) {
        g.members[i].robot = static_cast<int>(i);
        g.members[i].granted = ReleaseOf(g, g.members[i]);
      }
    }
  }
  for (const Member& m : g.members) {
    if (m.id != quiet) PushTo(g, m);
  }
}

// Plans the group when it waits for a plan and every robot has finished its
// released moves.
void PlanIfSettled(Group& g, uint64_t quiet)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(g.mu) {
  if (g.replan_wanted && g.Unsettled() == 0) PlanGroup(g, quiet);
}

// The group needs a plan: plans it now if it can, else freezes it and tells
// every robot but `quiet` (whose answer says so) that its release will not
// grow until then.
void Freeze(Group& g, uint64_t quiet) ABSL_EXCLUSIVE_LOCKS_REQUIRED(g.mu) {
  const bool was_frozen = g.replan_wanted;
  g.replan_wanted = true;
  PlanIfSettled(g, quiet);
  if (!g.replan_wanted || was_frozen) return;
  for (const Member& m : g.members) {
    if (m.id != quiet) PushTo(g, m);
  }
}

}  // namespace

FleetGroups::FleetGroups(MapStore& store, InflationCache& inflation,
                         WorkerPool& pool)
    : store_(store), inflation_(inflation), pool_(pool) {
  store_.AddListener(
      [this](std::string_view name,
             const std::shared_ptr<const MapSnapshot>& snapshot) {
        OnMapChanged(name, snapshot);
      });
}

absl::Status FleetGroups::AddLocked(Join& join, const std::string& group_name,
                                    Group& group,
                                    v1::NavigateResponse* answer) {
  Group* g = &group;
  absl::MutexLock lock(&g->mu);
  if (g->closed) return absl::OkStatus();  // the caller looks again
  const std::string& map = join.snapshot->name;
  const std::string where =
      absl::StrFormat("fleet group '%s' on map '%s'", group_name, map);
  if (join.solver.has_value() && *join.solver != g->solver) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "open.fleet.solver: %s plans with %s, not %s", where,
        FleetSolverName(g->solver), FleetSolverName(*join.solver)));
  }
  if (join.time_limit.has_value() && *join.time_limit != g->time_limit) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "open.fleet.time_limit_ms: %s plans within %d ms, not %d", where,
        absl::ToInt64Milliseconds(g->time_limit),
        absl::ToInt64Milliseconds(*join.time_limit)));
  }
  if (join.cost.connectivity != g->cost.connectivity ||
      join.cost.unknown_is_free != g->cost.unknown_is_free) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "open.options: %s plans %d-connected with unknown_is_free %s; give the "
        "same",
        where, g->cost.connectivity == Connectivity::kFour ? 4 : 8,
        g->cost.unknown_is_free ? "true" : "false"));
  }
  for (const Member& m : g->members) {
    if (m.gone) continue;
    if (m.goal == join.goal) {
      return absl::InvalidArgumentError(
          absl::StrFormat("open.goal %s is the goal of session %d in %s: "
                          "robots need distinct goals",
                          CellToString(join.goal), m.id, where));
    }
    bool in_the_way = m.at == join.start;
    if (g->schedule.has_value() && m.robot >= 0) {
      const std::vector<Cell>& path = g->schedule->path(m.robot);
      // Every cell its released moves sweep: both ends and, diagonally,
      // the two side cells.
      for (int64_t t = g->schedule->progress(m.robot); t <= m.granted; ++t) {
        in_the_way = in_the_way || path[t] == join.start;
        if (t == m.granted) break;
        const Cell a = path[t];
        const Cell b = path[t + 1];
        if (a.x != b.x && a.y != b.y) {
          in_the_way = in_the_way || Cell{a.x, b.y} == join.start ||
                       Cell{b.x, a.y} == join.start;
        }
      }
    }
    if (in_the_way) {
      return absl::InvalidArgumentError(
          absl::StrFormat("open.start %s is where session %d in %s stands or "
                          "may drive now; start from "
                          "another cell or open once it has passed",
                          CellToString(join.start), m.id, where));
    }
  }
  if (join.snapshot->version > g->snapshot->version)
    g->snapshot = join.snapshot;
  PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> grid,
                         GridFor(inflation_, *g, join.shape));
  if (join.shape.robot_radius_cells > 0.0) {
    PATHD_RETURN_IF_ERROR(CheckRadiusEndpoints(
        *g->snapshot->grid, *grid, join.shape.robot_radius_cells,
        {{join.start, "start"}, {join.goal, "goal"}}));
  }
  Member member;
  member.id = join.session_id;
  member.at = join.start;
  member.goal = join.goal;
  member.shape = join.shape;
  member.grid = std::move(grid);
  member.push = std::move(join.push);
  g->members.push_back(std::move(member));
  Freeze(*g, join.session_id);
  answer->set_event(v1::NAVIGATE_EVENT_OPENED);
  const Member& joined = *g->Find(join.session_id);
  Fill(*g, joined, answer);
  joined.push(*answer);
  return absl::OkStatus();
}

absl::Status FleetGroups::Add(Join join, v1::NavigateResponse* answer) {
  const std::string group_name =
      join.group.empty() ? std::string("default") : join.group;
  const std::string& map = join.snapshot->name;
  for (;;) {
    std::shared_ptr<Group> g;
    {
      absl::MutexLock lock(&mu_);
      if (by_session_.count(join.session_id) > 0) {
        return absl::InternalError("this session is already in a fleet group");
      }
      std::shared_ptr<Group>& slot = groups_[KeyOf(map, group_name)];
      if (slot == nullptr) {
        slot = std::make_shared<Group>();
        slot->map = map;
        slot->name = group_name;
        slot->solver = join.solver.value_or(FleetSolver::kLacam);
        slot->time_limit = join.time_limit.value_or(kDefaultTimeLimit);
        slot->cost = join.cost;
        absl::MutexLock group_lock(&slot->mu);
        slot->snapshot = join.snapshot;
      }
      g = slot;
    }
    absl::Status status = AddLocked(join, group_name, *g, answer);
    bool retry = false;
    bool abandoned = false;
    {
      absl::MutexLock lock(&g->mu);
      retry = g->closed;
      abandoned = !retry && !status.ok() && g->Live() == 0;
      if (abandoned) g->closed = true;
    }
    if (retry) continue;  // emptied meanwhile: a new group
    absl::MutexLock registry(&mu_);
    if (abandoned) {
      auto it = groups_.find(KeyOf(map, group_name));
      if (it != groups_.end() && it->second == g) groups_.erase(it);
    }
    if (status.ok()) by_session_[join.session_id] = g;
    return status;
  }
}

absl::Status FleetGroups::Report(uint64_t id, Cell cell,
                                 v1::NavigateResponse* answer) {
  std::shared_ptr<Group> g;
  {
    absl::MutexLock lock(&mu_);
    auto it = by_session_.find(id);
    if (it == by_session_.end())
      return absl::InternalError("session not in a fleet group");
    g = it->second;
  }
  absl::MutexLock lock(&g->mu);
  Member* m = g->Find(id);
  if (m == nullptr)
    return absl::InternalError("session not in its fleet group");
  if (!g->schedule.has_value() || m->robot < 0) {
    m->at = cell;
  } else if (g->schedule->Report(m->robot, cell)) {
    const int64_t progress = g->schedule->progress(m->robot);
    m->at = g->schedule->path(m->robot)[progress];
    m->granted = std::max(m->granted, progress);
  } else {
    // Off its plan: plan again from where everyone stands once the others
    // have finished what they were released for.
    m->at = cell;
    m->granted = g->schedule->progress(m->robot);
    Freeze(*g, id);
  }
  PlanIfSettled(*g, id);
  GrantAndPush(*g, id);
  m = g->Find(id);
  Fill(*g, *m, answer);
  m->push(*answer);
  return absl::OkStatus();
}

bool FleetGroups::Describe(uint64_t id, v1::NavigateResponse* answer) {
  std::shared_ptr<Group> g;
  {
    absl::MutexLock lock(&mu_);
    auto it = by_session_.find(id);
    if (it == by_session_.end()) return false;
    g = it->second;
  }
  absl::MutexLock lock(&g->mu);
  const Member* m = g->Find(id);
  if (m == nullptr) return false;
  Fill(*g, *m, answer);
  m->push(*answer);
  return true;
}

void FleetGroups::Remove(uint64_t id) {
  std::shared_ptr<Group> g;
  {
    absl::MutexLock lock(&mu_);
    auto it = by_session_.find(id);
    if (it == by_session_.end()) return;
    g = std::move(it->second);
    by_session_.erase(it);
  }
  bool empty;
  {
    absl::MutexLock lock(&g->mu);
    Member* m = g->Find(id);
    if (m != nullptr) {
      m->gone = true;
      if (g->schedule.has_value() && m->robot >= 0)
        g->schedule->Remove(m->robot);
    }
    empty = g->Live() == 0;
    if (empty) {
      g->closed = true;
    } else {
      PlanIfSettled(*g, 0);
      GrantAndPush(*g, 0);
    }
  }
  if (empty) {
    absl::MutexLock lock(&mu_);
    auto it = groups_.find(KeyOf(g->map, g->name));
    if (it != groups_.end() && it->second == g) groups_.erase(it);
  }
}

int FleetGroups::groups() const {
  absl::MutexLock lock(&mu_);
  return static_cast<int>(groups_.size());
}

void FleetGroups::OnMapChanged(
    std::string_view name, const std::shared_ptr<const MapSnapshot>& snapshot) {
  if (snapshot == nullptr) return;  // the sessions end, and leave
  std::vector<std::shared_ptr<Group>> affected;
  {
    absl::MutexLock lock(&mu_);
    for (const auto& [key, g] : groups_) {
      if (key.first == name) affected.push_back(g);
    }
  }
  for (std::shared_ptr<Group>& g : affected) {
    // Shaping the new version and planning are worker work.
    const absl::Status submitted =
        pool_.Submit(MakeJob([this, g, snapshot](SearchScratch&) {
          absl::MutexLock lock(&g->mu);
          if (g->closed || snapshot->version <= g->snapshot->version) return;
          g->snapshot = snapshot;
          bool blocked = !g->schedule.has_value();
          for (Member& m : g->members) {
            if (m.gone) continue;
            absl::StatusOr<std::shared_ptr<const Grid>> grid =
                GridFor(inflation_, *g, m.shape);
            if (!grid.ok()) {
              g->failure = std::string(grid.status().message());
              continue;
            }
            m.grid = *std::move(grid);
            if (!g->schedule.has_value() || m.robot < 0) continue;
            const std::vector<Cell>& path = g->schedule->path(m.robot);
            const int64_t progress = g->schedule->progress(m.robot);
            for (int64_t t = progress + 1;
                 t < static_cast<int64_t>(path.size()); ++t) {
              if (Traversable(m.grid->cost(path[t].x, path[t].y),
                              g->cost.unknown_is_free)) {
                continue;
              }
              blocked = true;
              // Stop before the blocked cell: the release is cut back (a robot
              // already moving into it has its own sensors).
              if (t <= m.granted) m.granted = std::max(progress, t - 1);
              break;
            }
          }
          if (!blocked) return;
          const bool was_frozen = g->replan_wanted;
          Freeze(*g, 0);
          if (was_frozen && g->replan_wanted) {
            // Frozen already: tell the robots where a blocked cell cut a
            // release back.
            for (const Member& m : g->members) PushTo(*g, m);
          }
        }));
    if (!submitted.ok()) {
      // The next report or join notices nothing; say so in the log only.
      continue;
    }
  }
}

}  // namespace pathd::server
