"""The client's value types (cells, map info, changes, plans, events) and the
conversions between them and the pathd.v1 messages."""

from __future__ import annotations

import dataclasses
import math
import operator
from collections.abc import Sequence
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


class WorldPoint(NamedTuple):
    """A point in the map's world frame, metres, without a heading: the
    server uses the cell that contains it (kinematic planners: the point)."""

    x: float
    y: float


class CellPose(NamedTuple):
    """A pose in continuous cell coordinates: cell (x, y) spans [x, x+1) x
    [y, y+1), so (x + 0.5, y + 0.5) is its centre; yaw in radians."""

    x: float
    y: float
    yaw: float = 0.0


class Origin(NamedTuple):
    """The world pose of the map's cell (0, 0) corner: metres, radians."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0


CellLike = Union[Cell, tuple[int, int]]
# Where a plan starts or ends: a cell, a world point, or an exact pose (world
# or cell coordinates; kinematic planners use its position and heading, the
# others the cell it lies in).
PositionLike = Union[Cell, tuple[int, int], WorldPose, WorldPoint, CellPose]


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
    origin: Origin = Origin()

    @classmethod
    def from_proto(cls, info: common_pb2.MapInfo) -> MapInfo:
        return cls(info.name, info.width, info.height, info.resolution,
                   info.version, info.free_cells, info.blocked_cells, info,
                   Origin(info.origin.x, info.origin.y, info.origin.yaw))

    # World <-> cell conversions as the server makes them: the origin's yaw
    # is ignored, as Nav2's costmap and pathd do unless pathd runs with
    # --honour_origin_yaw (then pass honour_origin_yaw=True).

    def cell_to_world(self, cell: CellLike, *,
                      honour_origin_yaw: bool = False) -> tuple[float, float]:
        """The world point (metres) of the cell's centre."""
        x, y = cell
        return self.cell_point_to_world(x + 0.5, y + 0.5,
                                        honour_origin_yaw=honour_origin_yaw)

    def cell_point_to_world(self, x: float, y: float, *,
                            honour_origin_yaw: bool = False) -> tuple[float, float]:
        """Continuous cell coordinates to the world frame (metres)."""
        yaw = self.origin.yaw if honour_origin_yaw else 0.0
        gx, gy = x * self.resolution, y * self.resolution
        return (self.origin.x + math.cos(yaw) * gx - math.sin(yaw) * gy,
                self.origin.y + math.sin(yaw) * gx + math.cos(yaw) * gy)

    def world_to_cell(self, x: float, y: float, *,
                      honour_origin_yaw: bool = False) -> Cell | None:
        """The cell containing world point (x, y); None when it is off the
        map (the server answers INVALID_ARGUMENT for such a position)."""
        yaw = self.origin.yaw if honour_origin_yaw else 0.0
        dx, dy = x - self.origin.x, y - self.origin.y
        gx = (math.cos(yaw) * dx + math.sin(yaw) * dy) / self.resolution
        gy = (-math.sin(yaw) * dx + math.cos(yaw) * dy) / self.resolution
        if not (0.0 <= gx < self.width and 0.0 <= gy < self.height):
            return None
        return Cell(int(gx), int(gy))


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
    # The start and goal cells used (after snap_start / goal tolerance, which
    # start_snapped / goal_substituted report) and the path's cell centres in
    # the world frame.
    start: Cell | None = None
    goal: Cell | None = None
    start_snapped: bool = False
    goal_substituted: bool = False
    world_path: list[tuple[float, float]] = dataclasses.field(default_factory=list)
    # Geometric planners: the exact polyline, cell coordinates and metres.
    polyline: list[tuple[float, float]] = dataclasses.field(default_factory=list)
    world_polyline: list[tuple[float, float]] = dataclasses.field(default_factory=list)
    # return_expansions: the expanded cells in order (truncated: more were).
    expanded: list[Cell] = dataclasses.field(default_factory=list)
    expanded_truncated: bool = False
    # via points: index into (via..., goal) of the last goal reached, and
    # where each reached goal's leg ends in `path`.
    reached_goal_index: int = -1
    leg_end_indices: list[int] = dataclasses.field(default_factory=list)
    # The path's smallest clearance in metres when the server measured it
    # (min_clearance options, the voronoi planner), else None.
    min_clearance_m: float | None = None
    planning_time_ms: float = 0.0

    @classmethod
    def from_proto(cls, plan: planner_service_pb2.PlanResponse) -> PlanResult:
        if plan.packed_path and not plan.path:
            # A packed answer (the client asks for one unless options chose):
            # the same cells and world points a readable one holds.
            path = decode_packed_path(plan.packed_path)
            if not 0 < plan.path_frame.resolution < math.inf:
                raise ValueError("path_frame.resolution must be finite and > 0 "
                                 "beside packed_path")
            world_path = [path_frame_cell_center(plan.path_frame, c.x, c.y)
                          for c in path]
        else:
            path = [Cell(c.x, c.y) for c in plan.path]
            world_path = [(p.x, p.y) for p in plan.world_path]
        return cls(
            found=plan.found,
            outcome=_enum_name(planner_service_pb2.PlanOutcome, plan.outcome,
                               "PLAN_OUTCOME_"),
            reason=plan.reason,
            path=path,
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
            raw=plan,
            start=Cell(plan.start.x, plan.start.y) if plan.HasField("start") else None,
            goal=Cell(plan.goal.x, plan.goal.y) if plan.HasField("goal") else None,
            start_snapped=plan.start_snapped,
            goal_substituted=plan.goal_substituted,
            world_path=world_path,
            polyline=[(p.x, p.y) for p in plan.polyline],
            world_polyline=[(p.x, p.y) for p in plan.world_polyline],
            expanded=[Cell(c.x, c.y) for c in plan.expanded],
            expanded_truncated=plan.expanded_truncated,
            reached_goal_index=plan.reached_goal_index,
            leg_end_indices=list(plan.leg_end_indices),
            min_clearance_m=plan.min_clearance_m if plan.has_clearance else None,
            planning_time_ms=plan.planning_time_us / 1000.0)


# PlanResponse.packed_path (proto/pathd/v1/planner_service.proto documents
# the bytes; proto/path_codec.cc is the server's encoder and the C++ decoder).
_PACKED_MOVES = 0x01
_PACKED_DELTAS = 0x02
# MOVES direction codes as (dx, dy); the index is the code.
_MOVE_STEPS = ((1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1))
_INT32_MIN, _INT32_MAX = -(1 << 31), (1 << 31) - 1


def decode_packed_path(data: bytes) -> list[Cell]:
    """The cells of a PlanResponse.packed_path (none for empty bytes). A
    ValueError naming packed_path and the byte or cell for truncated bytes,
    an unknown format byte, an invalid move code or padding nibble, a
    coordinate outside int32 or bytes after the last cell."""
    data = bytes(data)
    if not data:
        return []
    pos = 1

    def varint() -> int:
        nonlocal pos
        start, value, shift = pos, 0, 0
        while True:
            if pos >= len(data):
                raise ValueError(f"packed_path: truncated varint at byte {start}")
            b = data[pos]
            pos += 1
            if shift == 63 and b > 1:
                raise ValueError(f"packed_path: varint at byte {start} is longer than 64 bits")
            value |= (b & 0x7F) << shift
            if not b & 0x80:
                return value
            shift += 7

    def zigzag() -> int:
        v = varint()
        return (v >> 1) ^ -(v & 1)

    def coordinate(v: int, cell: int, axis: str) -> int:
        if not _INT32_MIN <= v <= _INT32_MAX:
            raise ValueError(f"packed_path: cell {cell}: {axis} outside the int32 range")
        return v

    fmt = data[0]
    if fmt not in (_PACKED_MOVES, _PACKED_DELTAS):
        raise ValueError(f"packed_path: unknown format byte 0x{fmt:02x} "
                         "(0x01 MOVES or 0x02 DELTAS)")
    count = varint()
    if count == 0:
        raise ValueError("packed_path: a cell count of 0 (an empty path is empty bytes)")
    x = coordinate(zigzag(), 0, "x")
    y = coordinate(zigzag(), 0, "y")
    steps = count - 1
    remaining = len(data) - pos
    if fmt == _PACKED_MOVES:
        needed, room = (steps + 1) // 2, remaining
    else:
        needed, room = steps, remaining // 2
    if needed > room:
        raise ValueError(f"packed_path: truncated: {count} cells need more than the "
                         f"{remaining} bytes after byte {pos}")
    cells = [Cell(x, y)]
    for i in range(steps):
        if fmt == _PACKED_MOVES:
            byte = data[pos + i // 2]
            code = byte & 0x0F if i % 2 == 0 else byte >> 4
            if code >= 8:
                raise ValueError(f"packed_path: invalid move code {code} at move {i} "
                                 f"(byte {pos + i // 2})")
            dx, dy = _MOVE_STEPS[code]
        else:
            dx = zigzag()
            dy = zigzag()
        x = coordinate(x + dx, i + 1, "x")
        y = coordinate(y + dy, i + 1, "y")
        cells.append(Cell(x, y))
    if fmt == _PACKED_MOVES:
        if steps % 2 == 1 and data[pos + steps // 2] >> 4:
            raise ValueError(f"packed_path: the padding nibble of byte {pos + steps // 2} "
                             "is not 0")
        pos += needed
    if pos != len(data):
        raise ValueError(f"packed_path: {len(data) - pos} bytes after the last cell "
                         f"(byte {pos})")
    return cells


def path_frame_cell_center(frame: planner_service_pb2.PathFrame, x: int,
                           y: int) -> tuple[float, float]:
    """The world point of cell (x, y)'s centre under a PlanResponse's
    path_frame: the server's computation, operation for operation, so equal
    to a readable world_path's point."""
    lx = (x + 0.5) * frame.resolution
    ly = (y + 0.5) * frame.resolution
    cs = math.cos(frame.origin.yaw)
    sn = math.sin(frame.origin.yaw)
    return (frame.origin.x + cs * lx - sn * ly, frame.origin.y + sn * lx + cs * ly)


class PlanProgress(NamedTuple):
    """A PlanStream progress event: nodes expanded so far, the open list's
    smallest key (None for planners without one) and the time since the
    server received the request."""

    expansions: int
    best_f: float | None
    elapsed_ms: float

    @classmethod
    def from_proto(cls, p: planner_service_pb2.PlanProgress) -> PlanProgress:
        return cls(p.expansions, p.best_f if p.HasField("best_f") else None,
                   p.elapsed_us / 1000.0)


@dataclasses.dataclass(frozen=True)
class CostToGoResult:
    """A goal's cost-to-go field over `window` (x, y, width, height):
    `costs` row-major within the window, math.inf where the goal cannot be
    reached; cost() reads one cell by its map coordinates."""

    map_version: int
    goal: Cell
    window: tuple[int, int, int, int]
    costs: list[float]
    cache_hit: bool
    expansions: int
    raw: planner_service_pb2.CostToGoResponse = dataclasses.field(
        default=None, repr=False, compare=False)

    def cost(self, cell: CellLike) -> float:
        x, y = cell
        wx, wy, width, height = self.window
        if not (wx <= x < wx + width and wy <= y < wy + height):
            raise IndexError(f"cell ({x}, {y}) is outside the window {self.window}")
        return self.costs[(y - wy) * width + (x - wx)]

    @classmethod
    def from_proto(cls, r: planner_service_pb2.CostToGoResponse) -> CostToGoResult:
        w = r.window
        return cls(map_version=r.map_version, goal=Cell(r.goal.x, r.goal.y),
                   window=(w.x, w.y, w.width, w.height), costs=list(r.cost),
                   cache_hit=r.cache_hit, expansions=r.expansions, raw=r)


@dataclasses.dataclass(frozen=True)
class PathCheck:
    """An IsPathValid answer: `valid`, the poses the robot may not occupy
    (`invalid_indices`), the steps i (pose i-1 to i) that are not legal
    moves (`invalid_steps`), the first fault as text (`reason`), and for a
    valid path its cost and length."""

    valid: bool
    invalid_indices: list[int]
    invalid_steps: list[int]
    reason: str
    cost: float
    length: float
    length_m: float
    footprint_checked: bool
    map_version: int
    raw: planner_service_pb2.IsPathValidResponse = dataclasses.field(
        default=None, repr=False, compare=False)

    @classmethod
    def from_proto(cls, r: planner_service_pb2.IsPathValidResponse) -> PathCheck:
        return cls(valid=r.valid, invalid_indices=list(r.invalid_indices),
                   invalid_steps=list(r.invalid_steps), reason=r.reason, cost=r.cost,
                   length=r.length, length_m=r.length_m,
                   footprint_checked=r.footprint_checked, map_version=r.map_version, raw=r)


@dataclasses.dataclass(frozen=True)
class CacheStats:
    """Counters of one incremental-state cache ("spm" or "dstar_lite")."""

    name: str
    entries: int
    bytes: int
    budget_bytes: int
    hits: int
    misses: int
    evictions: int
    repairs: int
    rebuilds: int


@dataclasses.dataclass(frozen=True)
class CacheStatsResult:
    """GetCacheStats: `caches` by name, open Navigate sessions and their
    bytes."""

    caches: dict[str, CacheStats]
    sessions: int
    session_bytes: int

    @classmethod
    def from_proto(cls, r: planner_service_pb2.GetCacheStatsResponse) -> CacheStatsResult:
        caches = {c.name: CacheStats(c.name, c.entries, c.bytes, c.budget_bytes, c.hits,
                                     c.misses, c.evictions, c.repairs, c.rebuilds)
                  for c in r.caches}
        return cls(caches=caches, sessions=r.sessions, session_bytes=r.session_bytes)


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
    # Per robot: the name it was given ("" when none) and its radius.
    names: list[str] = dataclasses.field(default_factory=list)
    radii_m: list[float] = dataclasses.field(default_factory=list)

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
                   map_version=r.map_version, raw=r,
                   names=[p.name for p in r.paths], radii_m=[p.radius_m for p in r.paths])


@dataclasses.dataclass(frozen=True)
class NavigateUpdate:
    """One message of a Navigate session's server side.

    `event` is "OPENED", "MOVED", "OBSERVED" or "CONTROL" (the answer to
    request `seq`), or "MAP_CHANGED" or "FLEET" (pushed unasked, seq 0).
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
    # Control sessions, event "CONTROL": the command for the state (plan is
    # then set only when the global path changed; has_plan says so).
    command: VelocityCommand | None = None
    has_plan: bool = True
    # Fleet sessions: the robot's timed path, progress and release.
    fleet: FleetSessionState | None = None

    @property
    def pushed(self) -> bool:
        return self.event in ("MAP_CHANGED", "FLEET")

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
                             if response.HasField("robot_pose") else None),
            command=(VelocityCommand.from_proto(response.command)
                     if response.HasField("command") else None),
            has_plan=response.HasField("plan"),
            fleet=(FleetSessionState.from_proto(response.fleet)
                   if response.HasField("fleet") else None))


@dataclasses.dataclass(frozen=True)
class FleetSessionState:
    """A fleet session's robot in its group's plan (docs/service.md, "Fleet
    sessions"): `path[t]` is its cell at step t of plan `epoch` (`world` the
    cells' centres, metres), `progress` the index where it last reported
    standing, `release` the furthest index it may drive to now (report each
    cell as it arrives); `planned` is False while the group waits for a
    joint plan (`reason` says why), when the release does not grow."""

    epoch: int
    path: list[Cell]
    world: list[WorldPoint]
    progress: int
    release: int
    robots: int
    planned: bool
    reason: str

    @property
    def released_cells(self) -> list[Cell]:
        """The cells the robot may drive through now, in order."""
        return self.path[self.progress + 1:self.release + 1]

    @property
    def arrived(self) -> bool:
        return self.planned and self.progress + 1 == len(self.path)

    @classmethod
    def from_proto(cls, fleet: planner_service_pb2.FleetSessionPlan) -> FleetSessionState:
        return cls(epoch=fleet.epoch,
                   path=[Cell(c.x, c.y) for c in fleet.path.cells],
                   world=[WorldPoint(w.x, w.y) for w in fleet.path.world],
                   progress=fleet.progress, release=fleet.release, robots=fleet.robots,
                   planned=fleet.planned, reason=fleet.reason)


@dataclasses.dataclass(frozen=True)
class VelocityCommand:
    """A control session's answer to a robot state: the body-frame command
    (m/s forward, m/s to the left, rad/s), how the cycle ended ("OK",
    "BLOCKED", "LOCAL_MINIMUM", "GOAL_REACHED" or "NO_PATH") and why, the
    predicted world poses under it (from the reported pose), the echoed
    stamp, the neighbours taken into account and the map version of the
    global path followed."""

    v: float
    vy: float
    w: float
    outcome: str
    reason: str
    trajectory: list[WorldPose]
    stamp: float
    neighbours: int
    map_version: int

    @classmethod
    def from_proto(cls, command: planner_service_pb2.VelocityCommand) -> VelocityCommand:
        return cls(
            v=command.v, vy=command.vy, w=command.w,
            outcome=_enum_name(planner_service_pb2.LocalOutcome, command.outcome,
                               "LOCAL_OUTCOME_"),
            reason=command.reason,
            trajectory=[WorldPose(p.x, p.y, p.yaw) for p in command.trajectory],
            stamp=command.stamp, neighbours=command.neighbours,
            map_version=command.map_version)


@dataclasses.dataclass(frozen=True)
class SessionInfo:
    """One open Navigate session (ListSessions): its id, map, the last
    update it sent (None before its first answer; its plan starts at the
    robot) and its age and idle time in seconds."""

    session_id: int
    map: str
    last: NavigateUpdate | None
    age_s: float
    idle_s: float

    @classmethod
    def from_proto(cls, info: planner_service_pb2.SessionInfo) -> SessionInfo:
        return cls(info.session_id, info.map,
                   NavigateUpdate.from_proto(info.last) if info.HasField("last") else None,
                   info.age_seconds, info.idle_seconds)


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
    if isinstance(where, WorldPoint):
        return common_pb2.Position(world=common_pb2.WorldPoint(x=where.x, y=where.y))
    if isinstance(where, CellPose):
        return common_pb2.Position(cell_pose=common_pb2.CellPose(
            x=where.x, y=where.y, yaw=where.yaw))
    if isinstance(where, common_pb2.Position):
        return where
    x, y = where
    try:
        x, y = operator.index(x), operator.index(y)
    except TypeError:
        raise TypeError(f"a cell is two integers, not ({x!r}, {y!r}); use WorldPoint, "
                        "WorldPose or CellPose for coordinates") from None
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


def _enum_value(enum, prefix: str, name: str, what: str) -> int:
    try:
        return enum.Value(prefix + name.upper())
    except ValueError:
        raise ValueError(f"unknown {what} '{name}'") from None


def _one_of(options, field_pair, values) -> None:
    """Sets the one of two oneof fields (metres / cells) that was given."""
    given = [(f, v) for f, v in zip(field_pair, values) if v is not None]
    if len(given) > 1:
        raise ValueError(f"give {field_pair[0]} or {field_pair[1]}, not both")
    for field, value in given:
        setattr(options, field, value)


# PotentialFieldOptions' fields plan_options(potential_field={...}) takes.
_POTENTIAL_FIELD_KEYS = ("attractive", "attractive_gain", "switch_distance",
                         "repulsive_gain", "influence_distance", "step_size",
                         "max_steps")


def plan_options(*, connectivity: int = 8, cost_weight: float | None = None,
                 unknown_is_free: bool = False,
                 max_expansions: int = 0,
                 heuristic_weight: float | None = None,
                 robot_radius_m: float | None = None,
                 robot_radius_cells: float | None = None,
                 simplify: bool = False,
                 lookahead: int = 0,
                 return_cost_to_go: bool = False,
                 potential_field: dict | None = None,
                 goal_tolerance_m: float | None = None,
                 goal_tolerance_cells: float | None = None,
                 return_expansions: bool = False,
                 min_clearance_m: float | None = None,
                 min_clearance_cells: float | None = None,
                 inflation_radius_m: float | None = None,
                 inflation_radius_cells: float | None = None,
                 cost_scaling_factor: float | None = None,
                 footprint_m: list[tuple[float, float]] | None = None,
                 footprint_cells: list[tuple[float, float]] | None = None,
                 footprint_radius_m: float | None = None,
                 footprint_radius_cells: float | None = None,
                 min_turning_radius_m: float | None = None,
                 min_turning_radius_cells: float | None = None,
                 motion_model: str | None = None,
                 reverse_penalty: float | None = None,
                 change_penalty: float | None = None,
                 non_straight_penalty: float | None = None,
                 cost_penalty: float | None = None,
                 goal_yaw_tolerance: float | None = None,
                 lattice: str = "",
                 smooth: bool | None = None,
                 snap_start: bool = False,
                 snap_start_max_m: float | None = None,
                 snap_start_max_cells: float | None = None,
                 ant_colony: dict | None = None,
                 reaction_diffusion: dict | None = None,
                 path_encoding: str | None = None,
                 ) -> planner_service_pb2.PlanOptions:
    """A PlanOptions message from keyword arguments, one per field of
    proto/pathd/v1/planner_service.proto's PlanOptions (docs/python.md lists
    them; the proto says what each does). A metres / cells pair is a oneof:
    give one. Every call that takes `options=` also takes these keywords.

    connectivity 4 or 8; cost_weight (unset 1; 0 ignores cell costs);
    max_expansions (0: the server's limit); heuristic_weight (weighted_astar,
    state_lattice); robot_radius_*; simplify (ray-shot any-angle path);
    lookahead (rtaa_star, lrta_star); return_cost_to_go (distance transform
    planners); potential_field: a dict of PotentialFieldOptions fields
    ("attractive": "quadratic" | "conic", "attractive_gain",
    "switch_distance", "repulsive_gain", "influence_distance", "step_size",
    "max_steps"); goal_tolerance_* (a blocked goal moves to the nearest free
    cell within it); return_expansions (PlanResult.expanded);
    min_clearance_* (grid planners keep this far from obstacles);
    inflation_radius_*, cost_scaling_factor (Nav2's inflation layer, the
    factor per metre, unset 10); footprint_m / footprint_cells (polygon,
    [(x, y), ...], x forward, y left) or footprint_radius_* (a circle);
    min_turning_radius_*, motion_model ("dubins", "reeds_shepp",
    "differential", "omnidirectional"), reverse_penalty, change_penalty,
    non_straight_penalty, cost_penalty (Nav2 Smac's penalties),
    goal_yaw_tolerance (radians), lattice, smooth (kinematic planners; grid
    planners with smooth=True also answer poses smoothed for the robot);
    snap_start, snap_start_max_* (a blocked start moves to the nearest
    free cell); ant_colony: a dict of AntColonyOptions fields ("ants",
    "iterations", "stall_iterations", "alpha", "beta", "rho", "xi", "q0",
    "tau0", "max_steps", "seed"); reaction_diffusion: a dict of
    ReactionDiffusionOptions fields ("diffusion", "reaction_rate",
    "threshold", "time_step", "max_steps"); path_encoding ("packed",
    "readable", "both"; unset: the client asks for "packed" and decodes it,
    so PlanResult is the same either way). Unknown keys are a ValueError;
    the server checks the ranges.
    """
    if connectivity not in (4, 8):
        raise ValueError(f"connectivity must be 4 or 8, not {connectivity}")
    options = planner_service_pb2.PlanOptions(
        connectivity=connectivity, unknown_is_free=unknown_is_free,
        max_expansions=max_expansions, simplify=simplify, lookahead=lookahead,
        return_cost_to_go=return_cost_to_go, return_expansions=return_expansions,
        lattice=lattice, snap_start=snap_start)
    if cost_weight is not None:
        options.cost_weight = cost_weight
    if heuristic_weight is not None:
        options.heuristic_weight = heuristic_weight
    _one_of(options, ("robot_radius_m", "robot_radius_cells"),
            (robot_radius_m, robot_radius_cells))
    _one_of(options, ("goal_tolerance_m", "goal_tolerance_cells"),
            (goal_tolerance_m, goal_tolerance_cells))
    _one_of(options, ("min_clearance_m", "min_clearance_cells"),
            (min_clearance_m, min_clearance_cells))
    _one_of(options, ("inflation_radius_m", "inflation_radius_cells"),
            (inflation_radius_m, inflation_radius_cells))
    _one_of(options, ("min_turning_radius_m", "min_turning_radius_cells"),
            (min_turning_radius_m, min_turning_radius_cells))
    _one_of(options, ("snap_start_max_m", "snap_start_max_cells"),
            (snap_start_max_m, snap_start_max_cells))
    if cost_scaling_factor is not None:
        options.cost_scaling_factor = cost_scaling_factor
    if potential_field:
        unknown = set(potential_field) - set(_POTENTIAL_FIELD_KEYS)
        if unknown:
            raise ValueError(f"unknown potential_field key(s) {sorted(unknown)}; "
                             f"expected {list(_POTENTIAL_FIELD_KEYS)}")
        fields = dict(potential_field)
        if "attractive" in fields:
            fields["attractive"] = _enum_value(
                planner_service_pb2.AttractivePotential, "ATTRACTIVE_POTENTIAL_",
                fields["attractive"], "attractive potential")
        options.potential_field.CopyFrom(planner_service_pb2.PotentialFieldOptions(**fields))
    for name, given, message in (
            ("ant_colony", ant_colony, planner_service_pb2.AntColonyOptions),
            ("reaction_diffusion", reaction_diffusion,
             planner_service_pb2.ReactionDiffusionOptions)):
        if not given:
            continue
        known = [f.name for f in message.DESCRIPTOR.fields]
        unknown = set(given) - set(known)
        if unknown:
            raise ValueError(f"unknown {name} key(s) {sorted(unknown)}; expected {known}")
        getattr(options, name).CopyFrom(message(**given))
    shapes = [s for s in (footprint_m, footprint_cells, footprint_radius_m,
                          footprint_radius_cells) if s is not None]
    if len(shapes) > 1:
        raise ValueError("give one of footprint_m, footprint_cells, footprint_radius_m "
                         "and footprint_radius_cells")
    for x, y in footprint_m or []:
        options.footprint.polygon_m.add(x=x, y=y)
    for x, y in footprint_cells or []:
        options.footprint.polygon_cells.add(x=x, y=y)
    if footprint_radius_m is not None:
        options.footprint.radius_m = footprint_radius_m
    if footprint_radius_cells is not None:
        options.footprint.radius_cells = footprint_radius_cells
    if motion_model is not None:
        options.motion_model = _enum_value(planner_service_pb2.MotionModel,
                                           "MOTION_MODEL_", motion_model, "motion model")
    for field, value in (("reverse", reverse_penalty), ("change", change_penalty),
                         ("non_straight", non_straight_penalty), ("cost", cost_penalty)):
        if value is not None:
            setattr(options.penalties, field, value)
    if goal_yaw_tolerance is not None:
        options.goal_yaw_tolerance = goal_yaw_tolerance
    if smooth is not None:
        options.smooth = smooth
    if path_encoding is not None:
        options.path_encoding = _enum_value(planner_service_pb2.PathEncoding,
                                            "PATH_ENCODING_", path_encoding, "path encoding")
    return options


def _plan_options(options: planner_service_pb2.PlanOptions | None,
                  keywords: dict) -> planner_service_pb2.PlanOptions:
    """_options for a call whose answer carries a plan: unless the options
    chose a path_encoding, they ask for the packed path (PlanResult decodes
    it), a fraction of the readable form's bytes."""
    chosen = _options(options, keywords)
    packed = planner_service_pb2.PlanOptions()
    if chosen is not None:
        if chosen.path_encoding != planner_service_pb2.PATH_ENCODING_UNSPECIFIED:
            return chosen
        packed.CopyFrom(chosen)
    packed.path_encoding = planner_service_pb2.PATH_ENCODING_PACKED
    return packed


def _options(options: planner_service_pb2.PlanOptions | None,
             keywords: dict) -> planner_service_pb2.PlanOptions | None:
    """A call's PlanOptions: `options` as given, or plan_options(**keywords);
    not both, so no keyword silently overrides a field of the message."""
    if keywords:
        if options is not None:
            raise ValueError("give options= or option keywords "
                             f"({', '.join(sorted(keywords))}), not both")
        return plan_options(**keywords)
    return options


def plan_request(map_name: str, start: PositionLike, goal: PositionLike, *,
                 planner: str | None = None,
                 options: planner_service_pb2.PlanOptions | None = None,
                 via: Sequence[PositionLike] = (), allow_partial: bool = False,
                 **option_keywords) -> planner_service_pb2.PlanRequest:
    """A PlanRequest, as PathdClient.plan sends it: for plan_batch, or to
    keep and send again. `via`: intermediate goals visited in order;
    `allow_partial`: a failed leg answers the path to the last goal
    reached. The options ask for the packed path unless they chose."""
    return planner_service_pb2.PlanRequest(
        map=map_name, start=_position(start), goal=_position(goal),
        planner=_planner(planner), options=_plan_options(options, option_keywords),
        via=[_position(v) for v in via], allow_partial=allow_partial)
