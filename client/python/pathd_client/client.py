"""A thin typed wrapper around pathd's gRPC API (proto/pathd/v1).

Every call carries the map name in the `x-pathd-map` request header (a load
balancer hashes on it so each map lives on one replica) and a deadline, and
a failed call raises PathdError carrying the gRPC status. Results are small
dataclasses; each keeps the proto message it came from in `raw` for fields
the wrapper does not lift out.
"""

from __future__ import annotations

import dataclasses
import itertools
import queue
import threading
import time
from collections.abc import Iterable, Iterator, Sequence
from typing import NamedTuple, Union

import grpc

from pathd.v1 import common_pb2
from pathd.v1 import map_service_pb2
from pathd.v1 import map_service_pb2_grpc
from pathd.v1 import planner_service_pb2
from pathd.v1 import planner_service_pb2_grpc

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


CellLike = Union[Cell, tuple[int, int]]


class PathdError(Exception):
    """A call to pathd failed.

    `code` is the grpc.StatusCode, `details` the server's message, `outcome`
    the PlanOutcome name (e.g. "GOAL_OCCUPIED") when the server sent one, and
    `metadata` every trailing metadata pair (e.g. "retry-after-ms" with
    RESOURCE_EXHAUSTED). Codes with their own subclass below raise that.
    """

    def __init__(self, code: grpc.StatusCode, details: str,
                 metadata: dict[str, str] | None = None):
        super().__init__(f"{code.name}: {details}")
        self.code = code
        self.details = details
        self.metadata = dict(metadata or {})

    @property
    def outcome(self) -> str | None:
        name = self.metadata.get(PLAN_OUTCOME_KEY)
        return name.removeprefix("PLAN_OUTCOME_") if name else None


class NotFoundError(PathdError):
    """NOT_FOUND: no map of that name (or a map_dir file is missing)."""


class InvalidArgumentError(PathdError):
    """INVALID_ARGUMENT: the message names the bad field, cell or line."""


class AlreadyExistsError(PathdError):
    """ALREADY_EXISTS: CreateMap without replace on a taken name."""


class AbortedError(PathdError):
    """ABORTED: UpdateMap's expected_version is not the map's version."""


class FailedPreconditionError(PathdError):
    """FAILED_PRECONDITION: the planner does not apply to this query."""


class ResourceExhaustedError(PathdError):
    """RESOURCE_EXHAUSTED: a queue or limit is full; see retry_after."""

    @property
    def retry_after(self) -> float | None:
        """The server's hint, in seconds, when it gave one."""
        ms = self.metadata.get("retry-after-ms")
        return int(ms) / 1000.0 if ms and ms.isdigit() else None


class DeadlineExceededError(PathdError):
    """DEADLINE_EXCEEDED: the call's deadline (or a session wait) passed."""


class UnavailableError(PathdError):
    """UNAVAILABLE: no server there, or it is shutting down."""


_ERROR_CLASSES: dict[grpc.StatusCode, type[PathdError]] = {
    grpc.StatusCode.NOT_FOUND: NotFoundError,
    grpc.StatusCode.INVALID_ARGUMENT: InvalidArgumentError,
    grpc.StatusCode.ALREADY_EXISTS: AlreadyExistsError,
    grpc.StatusCode.ABORTED: AbortedError,
    grpc.StatusCode.FAILED_PRECONDITION: FailedPreconditionError,
    grpc.StatusCode.RESOURCE_EXHAUSTED: ResourceExhaustedError,
    grpc.StatusCode.DEADLINE_EXCEEDED: DeadlineExceededError,
    grpc.StatusCode.UNAVAILABLE: UnavailableError,
}


def make_error(code: grpc.StatusCode, details: str,
               metadata: dict[str, str] | None = None) -> PathdError:
    """The PathdError subclass for `code` (PathdError itself for the rest)."""
    return _ERROR_CLASSES.get(code, PathdError)(code, details, metadata)


def _from_rpc_error(error: grpc.RpcError) -> PathdError:
    # Every RpcError grpc raises for a call is also a grpc.Call.
    trailing = error.trailing_metadata() or ()
    metadata = {key: value for key, value in trailing if isinstance(value, str)}
    return make_error(error.code(), error.details() or "", metadata)


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
    raw: planner_service_pb2.PlanResponse = dataclasses.field(
        repr=False, compare=False)

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
            raw=plan)


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
            raw=response)


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


def _position(cell: CellLike) -> common_pb2.Position:
    x, y = cell
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
                 simplify: bool = False) -> planner_service_pb2.PlanOptions:
    """The common PlanOptions; build the message yourself for the rest."""
    if connectivity not in (4, 8):
        raise ValueError(f"connectivity must be 4 or 8, not {connectivity}")
    options = planner_service_pb2.PlanOptions(
        connectivity=connectivity, unknown_is_free=unknown_is_free,
        simplify=simplify)
    if cost_weight is not None:
        options.cost_weight = cost_weight
    if robot_radius_cells is not None:
        options.robot_radius_cells = robot_radius_cells
    return options


class PathdClient:
    """Typed calls to one pathd server.

    Unary calls get a deadline of `timeout` seconds unless a call passes its
    own. Pass `channel` to use one you built (TLS, interceptors); otherwise
    an insecure channel to `address` is opened. Thread-safe, as grpc
    channels and stubs are. Use as a context manager, or call close().
    """

    def __init__(self, address: str = "127.0.0.1:50051", *,
                 timeout: float = DEFAULT_TIMEOUT,
                 channel: grpc.Channel | None = None):
        self.timeout = timeout
        self._channel = channel if channel is not None else grpc.insecure_channel(address)
        self._maps = map_service_pb2_grpc.MapServiceStub(self._channel)
        self._planner = planner_service_pb2_grpc.PlannerServiceStub(self._channel)

    def close(self) -> None:
        self._channel.close()

    def __enter__(self) -> PathdClient:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def _call(self, method, request, map_name: str | None,
              timeout: float | None):
        # ListMaps has no map: without the header a balancer picks any replica.
        metadata = ((MAP_HEADER, map_name),) if map_name else ()
        try:
            return method(request, timeout=self.timeout if timeout is None else timeout,
                          metadata=metadata)
        except grpc.RpcError as error:
            raise _from_rpc_error(error) from None

    # ---- MapService ----

    def create_map(self, name: str, rows: Sequence[str] | None = None, *,
                   cells: bytes | None = None, width: int | None = None,
                   height: int | None = None, resolution: float = 1.0,
                   replace: bool = False, timeout: float | None = None) -> MapInfo:
        """Creates a map from `rows` or from `cells`.

        `rows` are Moving AI map rows, all the same length ('.' free; '@',
        'T', 'O', 'W' blocked), sent as a .map text so the server's parser
        checks them. `cells` are width * height cost bytes, row-major.
        `replace` replaces a map of the same name instead of raising
        AlreadyExistsError.
        """
        request = map_service_pb2.CreateMapRequest(
            name=name, resolution=resolution, replace=replace)
        if (rows is None) == (cells is None):
            raise ValueError("give exactly one of rows and cells")
        if rows is not None:
            if not rows:
                raise ValueError("rows is empty")
            request.movingai_text = (
                f"type octile\nheight {len(rows)}\nwidth {len(rows[0])}\nmap\n"
                + "\n".join(rows) + "\n")
        else:
            if width is None or height is None:
                raise ValueError("cells needs width and height")
            request.raw.CopyFrom(map_service_pb2.RawCells(
                width=width, height=height, cells=bytes(cells)))
        response = self._call(self._maps.CreateMap, request, name, timeout)
        return MapInfo.from_proto(response.info)

    def get_map(self, name: str, *, timeout: float | None = None) -> MapInfo:
        response = self._call(self._maps.GetMap,
                              map_service_pb2.GetMapRequest(name=name), name, timeout)
        return MapInfo.from_proto(response.info)

    def get_cells(self, name: str, *, timeout: float | None = None) -> MapCells:
        """The current version with its cost bytes."""
        response = self._call(
            self._maps.GetMap,
            map_service_pb2.GetMapRequest(name=name, include_cells=True), name, timeout)
        return MapCells(MapInfo.from_proto(response.info), response.cells)

    def list_maps(self, *, timeout: float | None = None) -> list[MapInfo]:
        response = self._call(self._maps.ListMaps, map_service_pb2.ListMapsRequest(),
                              None, timeout)
        return [MapInfo.from_proto(info) for info in response.maps]

    def update_map(self, name: str, changes: Iterable[Change], *,
                   expected_version: int | None = None,
                   timeout: float | None = None) -> UpdateResult:
        """Applies the changes atomically (AbortedError when expected_version
        is given and is not the map's version)."""
        request = map_service_pb2.UpdateMapRequest(
            name=name, changes=[_change_proto(c) for c in changes])
        if expected_version is not None:
            request.expected_version = expected_version
        response = self._call(self._maps.UpdateMap, request, name, timeout)
        return UpdateResult(response.version, response.cells_changed)

    def delete_map(self, name: str, *, timeout: float | None = None) -> int:
        """Deletes the map; returns the version it had."""
        response = self._call(self._maps.DeleteMap,
                              map_service_pb2.DeleteMapRequest(name=name), name, timeout)
        return response.last_version

    def watch_map(self, name: str, from_version: int = 0, *,
                  timeout: float | None = None) -> MapWatch:
        """Streams the map's later versions (see MapWatch). No deadline
        unless `timeout` is given: a watch lasts until the map is deleted."""
        call = self._maps.WatchMap(
            map_service_pb2.WatchMapRequest(name=name, from_version=from_version),
            timeout=timeout, metadata=((MAP_HEADER, name),))
        return MapWatch(call)

    # ---- PlannerService ----

    def plan(self, map_name: str, start: CellLike, goal: CellLike, *,
             planner: str | None = None,
             options: planner_service_pb2.PlanOptions | None = None,
             timeout: float | None = None) -> PlanResult:
        """Plans one path. `planner` is a name as pathctl spells it ("astar",
        "dstar_lite", ...; None: the server's default). No path is a result
        with found False; a bad start or goal raises with `outcome` set."""
        request = planner_service_pb2.PlanRequest(
            map=map_name, start=_position(start), goal=_position(goal),
            planner=_planner(planner), options=options)
        return PlanResult.from_proto(
            self._call(self._planner.Plan, request, map_name, timeout))

    def navigate(self, map_name: str, start: CellLike, goal: CellLike, *,
                 options: planner_service_pb2.PlanOptions | None = None,
                 timeout: float | None = None) -> NavigationSession:
        """Opens a Navigate session (D* Lite) and waits for its first path.

        `timeout` bounds each wait for an answer, not the session, which
        lasts until closed (the server ends it after --session_idle_timeout
        without a message).
        """
        open_request = planner_service_pb2.NavigateOpen(
            map=map_name, start=_position(start), goal=_position(goal),
            options=options)
        return NavigationSession(self._planner, map_name, open_request,
                                 self.timeout if timeout is None else timeout)


class MapWatch:
    """An open WatchMap stream: iterate for MapEvents. Iteration ends after
    the DELETED event (or once cancel() was called); a failed stream raises
    PathdError. A context manager that cancels the stream on exit."""

    def __init__(self, call):
        self._call = call
        self._cancelled = False

    def __iter__(self) -> Iterator[MapEvent]:
        try:
            for event in self._call:
                yield MapEvent.from_proto(event)
        except grpc.RpcError as error:
            if self._cancelled and error.code() == grpc.StatusCode.CANCELLED:
                return
            raise _from_rpc_error(error) from None

    def cancel(self) -> None:
        self._cancelled = True
        self._call.cancel()

    def __enter__(self) -> MapWatch:
        return self

    def __exit__(self, *exc_info) -> None:
        self.cancel()


class _StreamEnd(NamedTuple):
    error: PathdError | None


class NavigationSession:
    """An open Navigate stream.

    Two ways to use it. Request/answer: move() and observe() send one
    message and return its answer; MAP_CHANGED pushes that arrive meanwhile
    are recorded in `pushes`, and wait_push() / poll_pushes() hand out the
    pushes not yet handed out. Or low level: send_pose() / send_observation()
    return the message's seq, and updates() yields every server message in
    arrival order. `latest` is always the newest message received, so
    `path` is the freshest path whichever way it came.

    Not thread-safe: drive one session from one thread (grpc's own threads
    do the sending and receiving). A context manager: a clean exit closes
    the session (OK), an exception cancels it.
    """

    def __init__(self, stub: planner_service_pb2_grpc.PlannerServiceStub,
                 map_name: str, open_request: planner_service_pb2.NavigateOpen,
                 timeout: float):
        self.map_name = map_name
        self.timeout = timeout
        self.pushes: list[NavigateUpdate] = []
        self._pushes_handed_out = 0
        self._seq = itertools.count(1)
        self._requests: queue.Queue = queue.Queue()
        self._received: queue.Queue = queue.Queue()
        self._end: _StreamEnd | None = None
        self._error_raised = False
        self._cancelled = False
        seq = self._send(planner_service_pb2.NavigateRequest(open=open_request))
        # No deadline on the stream itself: it lasts as long as the robot drives.
        self._call = stub.Navigate(self._request_iterator(),
                                   metadata=((MAP_HEADER, map_name),))
        self._reader = threading.Thread(target=self._read, daemon=True,
                                        name="pathd-navigate-reader")
        self._reader.start()
        try:
            self.opened = self._answer(seq, None)
        except BaseException:
            self.cancel()
            raise
        self.latest = self.opened

    @property
    def session_id(self) -> int:
        return self.opened.session_id

    @property
    def path(self) -> list[Cell]:
        """The newest path, from the robot's cell to the goal."""
        return self.latest.plan.path

    # ---- sending ----

    def _send(self, request: planner_service_pb2.NavigateRequest) -> int:
        if self._end is not None:
            raise self._end.error or make_error(
                grpc.StatusCode.FAILED_PRECONDITION, "the session has ended")
        request.seq = next(self._seq)
        self._requests.put(request)
        return request.seq

    def send_pose(self, cell: CellLike) -> int:
        """The robot is now at `cell`; returns the message's seq."""
        return self._send(planner_service_pb2.NavigateRequest(pose=_position(cell)))

    def send_observation(self, changes: Iterable[Change], *,
                         session_only: bool = False) -> int:
        """The robot's sensors saw these cells change; shared with the map
        (as UpdateMap) unless session_only. Returns the message's seq."""
        observation = planner_service_pb2.NavigateObservation(
            changes=[_change_proto(c) for c in changes], session_only=session_only)
        return self._send(planner_service_pb2.NavigateRequest(observe=observation))

    def move(self, cell: CellLike, *, timeout: float | None = None) -> NavigateUpdate:
        """Sends a pose and returns its answer (the path from `cell`)."""
        return self._answer(self.send_pose(cell), timeout)

    def observe(self, changes: Iterable[Change], *, session_only: bool = False,
                timeout: float | None = None) -> NavigateUpdate:
        """Sends an observation and returns its answer (the repaired path)."""
        return self._answer(
            self.send_observation(changes, session_only=session_only), timeout)

    # ---- receiving ----

    def _request_iterator(self) -> Iterator[planner_service_pb2.NavigateRequest]:
        while True:
            request = self._requests.get()
            if request is None:  # close(): half-close the stream
                return
            yield request

    def _read(self) -> None:
        try:
            for response in self._call:
                self._received.put(NavigateUpdate.from_proto(response))
            self._received.put(_StreamEnd(None))
        except grpc.RpcError as error:
            self._received.put(_StreamEnd(_from_rpc_error(error)))

    def _take(self, timeout: float | None) -> NavigateUpdate | None:
        """The next message, or None once the stream ended OK. Raises the
        stream's error, or DeadlineExceededError after `timeout` seconds
        (None: the session's timeout) without a message."""
        if self._end is None:
            wait = self.timeout if timeout is None else timeout
            try:
                item = self._received.get(timeout=wait)
            except queue.Empty:
                raise make_error(
                    grpc.StatusCode.DEADLINE_EXCEEDED,
                    f"no message from the Navigate session within {wait:g} s") from None
            if isinstance(item, NavigateUpdate):
                self.latest = item
                if item.pushed:
                    self.pushes.append(item)
                return item
            self._end = item
        if self._end.error is not None:
            self._error_raised = True
            raise self._end.error
        return None

    def _answer(self, seq: int, timeout: float | None) -> NavigateUpdate:
        while True:
            update = self._take(timeout)
            if update is None:
                raise make_error(grpc.StatusCode.UNKNOWN,
                                 f"the session ended before answering message {seq}")
            if not update.pushed and update.seq == seq:
                return update

    def wait_push(self, timeout: float | None = None) -> NavigateUpdate | None:
        """The oldest push not yet handed out, waiting up to `timeout`
        seconds (None: the session's timeout) for one; None if none came.
        Answers to earlier send_* messages received meanwhile only update
        `latest`."""
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while self._pushes_handed_out == len(self.pushes):
            try:
                if self._take(max(0.0, deadline - time.monotonic())) is None:
                    return None
            except DeadlineExceededError:
                return None
        self._pushes_handed_out += 1
        return self.pushes[self._pushes_handed_out - 1]

    def poll_pushes(self) -> list[NavigateUpdate]:
        """The pushes received and not yet handed out, without waiting."""
        while self._end is None and not self._received.empty():
            self._take(0)
        new = self.pushes[self._pushes_handed_out:]
        self._pushes_handed_out = len(self.pushes)
        return new

    def updates(self, timeout: float | None = None) -> Iterator[NavigateUpdate]:
        """Every message in arrival order until the session ends OK; raises
        its error, or DeadlineExceededError when a wait exceeds `timeout`."""
        while (update := self._take(timeout)) is not None:
            yield update

    # ---- ending ----

    def close(self, timeout: float | None = None) -> None:
        """Half-closes the stream and waits for the server to end it; raises
        PathdError if it ended with an error not raised before. Messages
        still arriving are recorded (latest, pushes)."""
        if self._end is None:
            self._requests.put(None)
            while self._take(timeout) is not None:
                pass
        elif self._end.error is not None and not (self._cancelled or self._error_raised):
            self._error_raised = True
            raise self._end.error

    def cancel(self) -> None:
        """Ends the session at once (the server sees CANCELLED)."""
        self._cancelled = True
        self._requests.put(None)
        self._call.cancel()
        self._reader.join()
        self._end = self._end or _StreamEnd(
            make_error(grpc.StatusCode.CANCELLED, "the session was cancelled"))

    def __enter__(self) -> NavigationSession:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        elif self._end is None:
            self.cancel()
