"""The client's value types (cells, map info, changes, plans, events) and the
conversions between them and the pathd.v1 messages."""

from __future__ import annotations

import dataclasses
from typing import NamedTuple, Union

from pathd.v1 import common_pb2
from pathd.v1 import map_service_pb2
from pathd.v1 import planner_service_pb2

# Request header naming the map a call is about; pathctl sets it too.
MAP_HEADER = "x-pathd-map"
# Trailing metadata key of a rejected Plan's PlanOutcome name.
PLAN_OUTCOME_KEY = "pathd-plan-outcome"
# Seconds each unary call may take unless the caller says otherwise (pathctl's
# --timeout default).
DEFAULT_TIMEOUT = 10.0

# Nav2 cost values (one byte per cell).
FREE = 0
INSCRIBED = 253
LETHAL = 254
UNKNOWN = 255


class Cell(NamedTuple):
    """A grid cell: x is the column, y the row, both 0-based."""

    x: int
    y: int


class WorldPose(NamedTuple):
    """A pose in the map's world frame: metres, heading in radians."""

    x: float
    y: float
    yaw: float = 0.0


CellLike = Union[Cell, tuple[int, int]]
# Where a plan starts or ends: a cell, or an exact world pose (kinematic
# planners use its position and heading; the others the cell it lies in).
PositionLike = Union[Cell, tuple[int, int], WorldPose]


@dataclasses.dataclass(frozen=True)
class MapInfo:
    """What the server knows about one map version."""

    name: str
    width: int
    height: int
    resolution: float
    version: int
    free_cells: int
    blocked_cells: int
    raw: common_pb2.MapInfo = dataclasses.field(repr=False, compare=False)

    @classmethod
    def from_proto(cls, info: common_pb2.MapInfo) -> MapInfo:
        return cls(info.name, info.width, info.height, info.resolution,
                   info.version, info.free_cells, info.blocked_cells, info)


@dataclasses.dataclass(frozen=True)
class MapCells:
    """A map version with its cost bytes, row-major."""

    info: MapInfo
    cells: bytes

    def cost(self, cell: CellLike) -> int:
        x, y = cell
        return self.cells[y * self.info.width + x]


@dataclasses.dataclass(frozen=True)
class SetCell:
    """An UpdateMap change: one cell gets `cost`."""

    x: int
    y: int
    cost: int


@dataclasses.dataclass(frozen=True)
class SetRect:
    """An UpdateMap change: every cell of the rectangle (corners included)."""

    x_min: int
    y_min: int
    x_max: int
    y_max: int
    cost: int


Change = Union[SetCell, SetRect]


@dataclasses.dataclass(frozen=True)
class UpdateResult:
    """What UpdateMap (or a shared observation) did."""

    version: int
    cells_changed: int


@dataclasses.dataclass(frozen=True)
class PlanResult:
    """A plan's answer; `found` False with an outcome such as "NO_PATH"."""

    found: bool
    outcome: str
    reason: str
    path: list[Cell]
    cost: float
    length: float
    expansions: int
    map_version: int
    planner: str
    # The path as world poses with headings (in `frame_id`); kinematic
    # planners' own poses, else cell centres facing along the path.
    poses: list[WorldPose] = dataclasses.field(default_factory=list)
    # Per pose: reached driving backwards (empty when no pose reverses).
    reverse: list[bool] = dataclasses.field(default_factory=list)
    cost_m: float = 0.0
    length_m: float = 0.0
    frame_id: str = ""
    # Grid/geometric planners with smooth=True: the index into `poses` of the
    # first pose where the footprint touches an obstacle (None: it fits).
    footprint_collision: int | None = None
    raw: planner_service_pb2.PlanResponse = dataclasses.field(
        default=None, repr=False, compare=False)

    @classmethod
    def from_proto(cls, plan: planner_service_pb2.PlanResponse) -> PlanResult:
        return cls(
            found=plan.found,
            outcome=_enum_name(planner_service_pb2.PlanOutcome, plan.outcome,
                               "PLAN_OUTCOME_"),
            reason=plan.reason,
            path=[Cell(c.x, c.y) for c in plan.path],
            cost=plan.cost,
            length=plan.length,
            expansions=plan.expansions,
            map_version=plan.map_version,
            planner=plan.planner,
            poses=[WorldPose(p.x, p.y, p.yaw) for p in plan.world_poses],
            reverse=list(plan.reverse),
            cost_m=plan.cost_m,
            length_m=plan.length_m,
            frame_id=plan.frame_id,
            footprint_collision=(plan.footprint_collision
                                 if plan.HasField("footprint_collision") else None),
            raw=plan)


@dataclasses.dataclass(frozen=True)
class TableResult:
    """A Table answer: cost_m[i][j] and length_m[i][j] from source i to
    destination j in metres (cost in cells too), None where no path exists.
    `method` is "BACKWARD" (one cost-to-go field per destination, from the
    server's cache when `fields_cached` says so) or "FORWARD"."""

    cost: list[list[float | None]]
    cost_m: list[list[float | None]]
    length_m: list[list[float | None]]
    method: str
    fields_cached: int
    map_version: int
    raw: planner_service_pb2.TableResponse = dataclasses.field(
        default=None, repr=False, compare=False)

    @classmethod
    def from_proto(cls, r: planner_service_pb2.TableResponse) -> TableResult:
        m = len(r.destinations)
        rows = [r.entries[i * m:(i + 1) * m] for i in range(len(r.sources))]

        def grid(field):
            return [[getattr(e, field) if e.reachable else None for e in row] for row in rows]
        return cls(cost=grid("cost"), cost_m=grid("cost_m"), length_m=grid("length_m"),
                   method=_enum_name(planner_service_pb2.TableMethod, r.method,
                                     "TABLE_METHOD_"),
                   fields_cached=r.fields_cached, map_version=r.map_version, raw=r)


@dataclasses.dataclass(frozen=True)
class NearestResult:
    """The nearest cell where the robot may stand (`found` False: none within
    the distance), its centre in the world frame and its distance."""

    found: bool
    cell: Cell | None
    world: tuple[float, float] | None
    distance_m: float
    distance_cells: float
    raw: planner_service_pb2.NearestResponse = dataclasses.field(
        default=None, repr=False, compare=False)

    @classmethod
    def from_proto(cls, r: planner_service_pb2.NearestResponse) -> NearestResult:
        return cls(found=r.found, cell=Cell(r.cell.x, r.cell.y) if r.found else None,
                   world=(r.world.x, r.world.y) if r.found else None,
                   distance_m=r.distance_m, distance_cells=r.distance_cells, raw=r)


@dataclasses.dataclass(frozen=True)
class TripResult:
    """A Trip answer: the waypoint indices in visiting order (starting with
    0; a round trip does not repeat it), its cost and a lower bound in
    metres, and the legs as one plan. `found` False with `reason` when no
    order joins every stop."""

    found: bool
    reason: str
    order: list[int]
    cost_m: float
    lower_bound_m: float
    gap: float
    exact: bool
    method: str
    bound_method: str
    plan: PlanResult | None
    raw: planner_service_pb2.TripResponse = dataclasses.field(
        default=None, repr=False, compare=False)

    @classmethod
    def from_proto(cls, r: planner_service_pb2.TripResponse) -> TripResult:
        return cls(found=r.found, reason=r.reason, order=list(r.order), cost_m=r.cost_m,
                   lower_bound_m=r.lower_bound_m, gap=r.gap, exact=r.exact,
                   method=r.method, bound_method=r.bound_method,
                   plan=PlanResult.from_proto(r.plan) if r.HasField("plan") else None, raw=r)


@dataclasses.dataclass(frozen=True)
class IsochroneResult:
    """The region reachable within a budget: `polygons` in world metres, each
    a list of rings [(x, y), ...] (open: the last point joins the first), the
    exterior first and then its holes. A cell is reachable exactly when its
    centre is inside a polygon."""

    polygons: list[list[list[tuple[float, float]]]]
    reachable_cells: int
    area_m2: float
    budget_m: float
    map_version: int
    raw: planner_service_pb2.IsochroneResponse = dataclasses.field(
        default=None, repr=False, compare=False)

    @classmethod
    def from_proto(cls, r: planner_service_pb2.IsochroneResponse) -> IsochroneResult:
        def ring(rg):
            return [(p.x, p.y) for p in rg.points]
        return cls(polygons=[[ring(p.world_exterior)] + [ring(h) for h in p.world_holes]
                             for p in r.polygons],
                   reachable_cells=r.reachable_cells, area_m2=r.area_m2,
                   budget_m=r.budget_m, map_version=r.map_version, raw=r)

    def geojson(self) -> dict:
        """The region as a GeoJSON (RFC 7946) Feature with a MultiPolygon,
        each ring closed, as `pathctl isochrone --output geojson` prints."""
        def closed(r):
            return [list(p) for p in r] + ([list(r[0])] if r else [])
        return {"type": "Feature",
                "geometry": {"type": "MultiPolygon",
                             "coordinates": [[closed(r) for r in poly] for poly in self.polygons]},
                "properties": {"budget_m": self.budget_m,
                               "reachable_cells": self.reachable_cells,
                               "area_m2": self.area_m2}}


@dataclasses.dataclass(frozen=True)
class FleetPlanResult:
    """A PlanFleet answer: `paths[i][t]` is robot i's cell at time step t
    (a wait repeats the cell; after its last entry the robot stays at its
    goal), `world_paths` the same in world metres. Costs are in steps.
    `found` False with `reason` when there is no plan; `stopped_early` when
    the time limit cut the solver short (a plan is then the best so far)."""

    found: bool
    reason: str
    paths: list[list[Cell]]
    world_paths: list[list[tuple[float, float]]]
    costs: list[int]
    makespan: int
    sum_of_costs: int
    lower_bound: int
    optimal: bool
    stopped_early: bool
    solver: str
    solver_time_ms: float
    map_version: int
    raw: planner_service_pb2.PlanFleetResponse = dataclasses.field(
        default=None, repr=False, compare=False)

    @classmethod
    def from_proto(cls, r: planner_service_pb2.PlanFleetResponse) -> FleetPlanResult:
        return cls(found=r.found, reason=r.reason,
                   paths=[[Cell(c.x, c.y) for c in p.cells] for p in r.paths],
                   world_paths=[[(w.x, w.y) for w in p.world] for p in r.paths],
                   costs=[p.cost for p in r.paths], makespan=r.makespan,
                   sum_of_costs=r.sum_of_costs, lower_bound=r.lower_bound,
                   optimal=r.optimal, stopped_early=r.stopped_early,
                   solver=_enum_name(planner_service_pb2.FleetSolver, r.solver,
                                     "FLEET_SOLVER_").lower(),
                   solver_time_ms=r.solver_time_us / 1000.0,
                   map_version=r.map_version, raw=r)


@dataclasses.dataclass(frozen=True)
class NavigateUpdate:
    """One message of a Navigate session's server side.

    `event` is "OPENED", "MOVED" or "OBSERVED" (the answer to request `seq`)
    or "MAP_CHANGED" (pushed unasked, seq 0).
    """

    event: str
    seq: int
    session_id: int
    plan: PlanResult
    applied_version: int
    raw: planner_service_pb2.NavigateResponse = dataclasses.field(
        repr=False, compare=False)
    # Kinematic sessions: the replan ran out of its budget and `plan` is the
    # rest of the previous path, rechecked collision-free; the budget; the
    # pose planned from, in cell coordinates (x, y, yaw).
    kept_previous_path: bool = False
    replan_max_expansions: int = 0
    robot_cell_pose: tuple[float, float, float] | None = None

    @property
    def pushed(self) -> bool:
        return self.event == "MAP_CHANGED"

    @classmethod
    def from_proto(cls, response: planner_service_pb2.NavigateResponse
                   ) -> NavigateUpdate:
        return cls(
            event=_enum_name(planner_service_pb2.NavigateEvent, response.event,
                             "NAVIGATE_EVENT_"),
            seq=response.seq,
            session_id=response.session_id,
            plan=PlanResult.from_proto(response.plan),
            applied_version=response.applied_version,
            raw=response,
            kept_previous_path=response.kept_previous_path,
            replan_max_expansions=response.replan_max_expansions,
            robot_cell_pose=((response.robot_pose.x, response.robot_pose.y,
                              response.robot_pose.yaw)
                             if response.HasField("robot_pose") else None))


@dataclasses.dataclass(frozen=True)
class ChangedRect:
    """A rectangle of changed cells and their new costs, row-major."""

    x_min: int
    y_min: int
    x_max: int
    y_max: int
    costs: bytes


@dataclasses.dataclass(frozen=True)
class MapEvent:
    """One WatchMap event: "UPDATED" (changes), "RESYNC" / "REPLACED" (info
    and the whole map in cells) or "DELETED" (the last one)."""

    kind: str
    version: int
    changes: list[ChangedRect]
    info: MapInfo | None
    cells: bytes | None
    raw: map_service_pb2.MapEvent = dataclasses.field(repr=False, compare=False)

    @classmethod
    def from_proto(cls, event: map_service_pb2.MapEvent) -> MapEvent:
        whole = event.HasField("info")
        return cls(
            kind=_enum_name(map_service_pb2.MapEventKind, event.kind,
                            "MAP_EVENT_KIND_"),
            version=event.version,
            changes=[ChangedRect(c.rect.x_min, c.rect.y_min, c.rect.x_max,
                                 c.rect.y_max, c.costs) for c in event.changes],
            info=MapInfo.from_proto(event.info) if whole else None,
            cells=event.cells if whole else None,
            raw=event)


def _enum_name(enum, value: int, prefix: str) -> str:
    try:
        return enum.Name(value).removeprefix(prefix)
    except ValueError:  # a value newer than these stubs
        return str(value)


def _position(where: PositionLike) -> common_pb2.Position:
    if isinstance(where, WorldPose):
        return common_pb2.Position(world_pose=common_pb2.WorldPose(
            x=where.x, y=where.y, yaw=where.yaw))
    x, y = where
    return common_pb2.Position(cell=common_pb2.Cell(x=x, y=y))


def _change_proto(change: Change) -> map_service_pb2.CellChange:
    if isinstance(change, SetCell):
        return map_service_pb2.CellChange(
            cell=common_pb2.Cell(x=change.x, y=change.y), cost=change.cost)
    if isinstance(change, SetRect):
        return map_service_pb2.CellChange(
            rect=map_service_pb2.CellRect(x_min=change.x_min, y_min=change.y_min,
                                          x_max=change.x_max, y_max=change.y_max),
            cost=change.cost)
    raise TypeError(f"a change is a SetCell or SetRect, not {type(change).__name__}")


def _planner(name: str | None) -> int:
    if not name:
        return planner_service_pb2.PLANNER_UNSPECIFIED
    try:
        return planner_service_pb2.Planner.Value("PLANNER_" + name.upper())
    except ValueError:
        raise ValueError(f"unknown planner '{name}'") from None


def plan_options(*, connectivity: int = 8, cost_weight: float | None = None,
                 unknown_is_free: bool = False,
                 robot_radius_cells: float | None = None,
                 robot_radius_m: float | None = None,
                 min_clearance_m: float | None = None,
                 inflation_radius_m: float | None = None,
                 cost_scaling_factor: float | None = None,
                 simplify: bool = False,
                 footprint_m: list[tuple[float, float]] | None = None,
                 min_turning_radius_m: float | None = None,
                 motion_model: str | None = None,
                 goal_yaw_tolerance: float | None = None,
                 reverse_penalty: float | None = None,
                 lattice: str = "",
                 smooth: bool | None = None,
                 snap_start: bool = False,
                 snap_start_max_m: float | None = None) -> planner_service_pb2.PlanOptions:
    """The common PlanOptions; build the message yourself for the rest.

    min_clearance_m: grid planners prefer keeping this far from obstacles
    (cells nearer cost more; the response's min_clearance_m says how close
    the path came).
    footprint_m: the robot's outline, [(x, y), ...] in metres, x forward, y
    left (Nav2's footprint). The kinematic planners (hybrid_astar,
    state_lattice) check it at every pose with min_turning_radius_m,
    motion_model ("dubins", "reeds_shepp", "differential",
    "omnidirectional"), goal_yaw_tolerance (radians), reverse_penalty,
    lattice and smooth; the others plan for its inscribed radius, and with
    smooth=True also return the path as poses smoothed for it
    (PlanResult.footprint_collision says where it does not fit).
    inflation_radius_m, cost_scaling_factor: Nav2's inflation layer for the
    grid planners: cells up to inflation_radius_m from a lethal cell, beyond
    the robot radius, cost 252 * exp(-cost_scaling_factor * (distance -
    robot radius)); the factor is per metre, unset means Nav2's 10.
    snap_start: a start on a blocked cell or within the robot radius of an
    obstacle moves to the nearest free cell within snap_start_max_m (unset:
    twice the robot radius, at least 2 cells); the PlanResult's
    raw.start_snapped says it did.
    """
    if robot_radius_cells is not None and robot_radius_m is not None:
        raise ValueError("give robot_radius_cells or robot_radius_m, not both")
    if connectivity not in (4, 8):
        raise ValueError(f"connectivity must be 4 or 8, not {connectivity}")
    options = planner_service_pb2.PlanOptions(
        connectivity=connectivity, unknown_is_free=unknown_is_free,
        simplify=simplify)
    if cost_weight is not None:
        options.cost_weight = cost_weight
    if robot_radius_cells is not None:
        options.robot_radius_cells = robot_radius_cells
    if robot_radius_m is not None:
        options.robot_radius_m = robot_radius_m
    if min_clearance_m is not None:
        options.min_clearance_m = min_clearance_m
    for x, y in footprint_m or []:
        options.footprint.polygon_m.add(x=x, y=y)
    if min_turning_radius_m is not None:
        options.min_turning_radius_m = min_turning_radius_m
    if motion_model is not None:
        try:
            options.motion_model = planner_service_pb2.MotionModel.Value(
                "MOTION_MODEL_" + motion_model.upper())
        except ValueError:
            raise ValueError(f"unknown motion model '{motion_model}'") from None
    if goal_yaw_tolerance is not None:
        options.goal_yaw_tolerance = goal_yaw_tolerance
    if reverse_penalty is not None:
        options.penalties.reverse = reverse_penalty
    options.lattice = lattice
    if smooth is not None:
        options.smooth = smooth
    if inflation_radius_m is not None:
        options.inflation_radius_m = inflation_radius_m
    if cost_scaling_factor is not None:
        options.cost_scaling_factor = cost_scaling_factor
    options.snap_start = snap_start
    if snap_start_max_m is not None:
        options.snap_start_max_m = snap_start_max_m
    return options
