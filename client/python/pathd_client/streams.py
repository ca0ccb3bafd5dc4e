"""The client's streaming calls: a WatchMap subscription, a Navigate
session, a PlanStream with its progress and a PlanBatch, each an object
over one gRPC stream."""

from __future__ import annotations

import itertools
import queue
import threading
import time
from collections.abc import Iterable, Iterator
from typing import NamedTuple

import grpc

from pathd.v1 import planner_service_pb2
from pathd.v1 import planner_service_pb2_grpc

from pathd_client.errors import (DeadlineExceededError, PathdError,
                                 _from_plan_error, _from_rpc_error, make_error)
from pathd_client.values import (MAP_HEADER, Cell, Change, MapEvent,
                                 NavigateUpdate, PlanProgress, PlanResult,
                                 PositionLike, WorldPose, _change_proto,
                                 _position)



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


class PlanStream:
    """An open PlanStream call. Iterating yields PlanProgress events while
    the search runs (at most one per the server's --progress_interval; none
    when the plan ends sooner), then the PlanResult, and stops; a plan that
    fails raises PathdError as Plan would (with `outcome`). `result` holds
    the PlanResult once it came, `progress` every event so far; wait()
    reads to the end and returns the result. A context manager that
    cancels the call (and so the plan) on exit if it has not ended."""

    def __init__(self, call):
        self._call = call
        self.result: PlanResult | None = None
        self.progress: list[PlanProgress] = []

    def __iter__(self) -> Iterator[PlanProgress | PlanResult]:
        try:
            for event in self._call:
                kind = event.WhichOneof("kind")
                if kind == "progress":
                    progress = PlanProgress.from_proto(event.progress)
                    self.progress.append(progress)
                    yield progress
                elif kind == "result":
                    self.result = PlanResult.from_proto(event.result)
                    yield self.result
                elif kind == "error":
                    self._call.cancel()
                    raise _from_plan_error(event.error)
        except grpc.RpcError as error:
            raise _from_rpc_error(error) from None

    def wait(self) -> PlanResult:
        for _ in self:
            pass
        if self.result is None:  # the server always sends one; a guard
            raise make_error(grpc.StatusCode.UNKNOWN, "PlanStream ended without a result")
        return self.result

    def cancel(self) -> None:
        self._call.cancel()

    def __enter__(self) -> PlanStream:
        return self

    def __exit__(self, *exc_info) -> None:
        self.cancel()


class BatchAnswer(NamedTuple):
    """One PlanBatch answer: the item's position in the requests given
    (`index`), its request_id, and its PlanResult or its PathdError (a bad
    item never ends the batch)."""

    index: int
    request_id: str
    result: PlanResult | None
    error: PathdError | None


class PlanBatch:
    """An open PlanBatch stream: iterate for a BatchAnswer per request, in
    the order the plans finish (sort by `index` for request order). The
    requests are sent from grpc's own thread as the server's flow control
    lets them, so a long generator of requests is fine. A context manager
    that cancels the stream on exit if it has not ended."""

    def __init__(self, call_factory, requests: Iterable):
        self._ids: dict[str, int] = {}
        self._call = call_factory(self._request_iterator(requests))

    def _request_iterator(self, requests: Iterable
                          ) -> Iterator[planner_service_pb2.PlanBatchRequest]:
        for index, item in enumerate(requests):
            if isinstance(item, tuple):
                request_id, request = item
            else:
                request_id, request = str(index), item
            self._ids[request_id] = index
            yield planner_service_pb2.PlanBatchRequest(request_id=request_id,
                                                       request=request)

    def __iter__(self) -> Iterator[BatchAnswer]:
        try:
            for answer in self._call:
                index = self._ids.get(answer.request_id, -1)
                if answer.WhichOneof("kind") == "result":
                    yield BatchAnswer(index, answer.request_id,
                                      PlanResult.from_proto(answer.result), None)
                else:
                    yield BatchAnswer(index, answer.request_id, None,
                                      _from_plan_error(answer.error))
        except grpc.RpcError as error:
            raise _from_rpc_error(error) from None

    def cancel(self) -> None:
        self._call.cancel()

    def __enter__(self) -> PlanBatch:
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
        self._latest_plan = self.opened

    @property
    def session_id(self) -> int:
        return self.opened.session_id

    @property
    def path(self) -> list[Cell]:
        """The newest path, from the robot's cell to the goal (a control
        session's: the global path it follows)."""
        return self._latest_plan.plan.path

    @property
    def poses(self) -> list[WorldPose]:
        """The newest path as world poses (a kinematic session's own poses,
        from the robot's pose to the goal)."""
        return self._latest_plan.plan.poses

    # ---- sending ----

    def _send(self, request: planner_service_pb2.NavigateRequest) -> int:
        if self._end is not None:
            raise self._end.error or make_error(
                grpc.StatusCode.FAILED_PRECONDITION, "the session has ended")
        request.seq = next(self._seq)
        self._requests.put(request)
        return request.seq

    def send_pose(self, where: PositionLike) -> int:
        """The robot is now at `where` (a cell, or a WorldPose with its
        heading; a cell keeps a kinematic robot's heading); returns the
        message's seq."""
        return self._send(planner_service_pb2.NavigateRequest(pose=_position(where)))

    def send_observation(self, changes: Iterable[Change], *,
                         session_only: bool = False) -> int:
        """The robot's sensors saw these cells change; shared with the map
        (as UpdateMap) unless session_only. Returns the message's seq."""
        observation = planner_service_pb2.NavigateObservation(
            changes=[_change_proto(c) for c in changes], session_only=session_only)
        return self._send(planner_service_pb2.NavigateRequest(observe=observation))

    def send_state(self, pose: WorldPose, *, v: float = 0.0, vy: float = 0.0,
                   w: float = 0.0, stamp: float = 0.0,
                   obstacles: Iterable[tuple[float, float, float, float, float]] = ()
                   ) -> int:
        """Control sessions: the robot is at `pose` (world, metres and
        radians) moving at (v, vy, w) in its body frame; `obstacles` are
        non-robot moving discs it sees, (x, y, vx, vy, radius) in the map
        frame, for this message only. Returns the message's seq."""
        state = planner_service_pb2.RobotState(
            pose=_position(pose), v=v, vy=vy, w=w, stamp=stamp)
        for x, y, vx, ovy, radius in obstacles:
            report = state.obstacles.add(vx=vx, vy=ovy, radius=radius)
            report.position.world.x = x
            report.position.world.y = y
        return self._send(planner_service_pb2.NavigateRequest(state=state))

    def control(self, pose: WorldPose, *, v: float = 0.0, vy: float = 0.0,
                w: float = 0.0, stamp: float = 0.0,
                obstacles: Iterable[tuple[float, float, float, float, float]] = (),
                timeout: float | None = None) -> NavigateUpdate:
        """Control sessions: sends the robot's state and returns its answer,
        whose `command` is the velocity to hold for one control period."""
        return self._answer(self.send_state(pose, v=v, vy=vy, w=w, stamp=stamp,
                                            obstacles=obstacles), timeout)

    def move(self, where: PositionLike, *, timeout: float | None = None) -> NavigateUpdate:
        """Sends a pose and returns its answer (the path from `where`)."""
        return self._answer(self.send_pose(where), timeout)

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
                if item.has_plan:
                    self._latest_plan = item
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
