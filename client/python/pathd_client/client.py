"""A thin typed wrapper around pathd's gRPC API (proto/pathd/v1).

Every call carries the map name in the `x-pathd-map` request header (a load
balancer hashes on it so each map lives on one replica) and a deadline, and
a failed call raises PathdError carrying the gRPC status. Results are small
dataclasses; each keeps the proto message it came from in `raw` for fields
the wrapper does not lift out.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence

import grpc

from pathd.v1 import common_pb2
from pathd.v1 import map_service_pb2
from pathd.v1 import map_service_pb2_grpc
from pathd.v1 import planner_service_pb2
from pathd.v1 import planner_service_pb2_grpc

from pathd_client import health
from pathd_client.channel import PemSource, make_channel
from pathd_client.errors import PathdError, _from_rpc_error
from pathd_client.map_files import cells_from_file, parse_movingai, set_source_from_file
from pathd_client.streams import MapWatch, NavigationSession, PlanBatch, PlanStream
from pathd_client.values import (DEFAULT_TIMEOUT, MAP_HEADER, CacheStatsResult, Change,
                                 CostToGoResult, FleetPlanResult, IsochroneResult,
                                 MapCells, MapInfo, NearestResult, PathCheck,
                                 PlanResult, PositionLike, SessionInfo, TableResult, TripResult,
                                 UpdateResult, _change_proto, _options, _plan_options, _planner,
                                 _position, plan_request)

# A CreateMap request over this goes through UploadMap instead: gRPC's
# default message limit, which any pathd accepts.
UNARY_CREATE_MAP_BYTES = 4 << 20
# Band size upload_map sends by default.
UPLOAD_BAND_BYTES = 1 << 20
# Transfer rate the streamed calls' deadlines allow for.
TRANSFER_BYTES_PER_SECOND = 16 << 20


class PathdClient:
    """Typed calls to one pathd server.

    Unary calls (and PlanStream, PlanBatch) get a deadline of `timeout`
    seconds unless a call passes its own. The channel is plaintext unless
    `tls_ca` is given (PEM bytes or a file path; `tls_cert` + `tls_key` for
    mutual TLS, `tls_server_name` when the certificate names another host);
    `token` or `token_file` is sent as a bearer token on every call (see
    channel.make_channel). Or pass `channel`, one you built yourself. Every
    option keyword of plan_options() is accepted by the calls that take
    `options=`. Thread-safe, as grpc channels and stubs are. Use as a
    context manager, or call close().
    """

    def __init__(self, address: str = "127.0.0.1:50051", *,
                 timeout: float = DEFAULT_TIMEOUT,
                 channel: grpc.Channel | None = None,
                 tls_ca: PemSource | None = None, tls_cert: PemSource | None = None,
                 tls_key: PemSource | None = None, tls_server_name: str | None = None,
                 token: str | None = None, token_file: str | os.PathLike | None = None):
        self.timeout = timeout
        if channel is None:
            channel = make_channel(address, tls_ca=tls_ca, tls_cert=tls_cert,
                                   tls_key=tls_key, tls_server_name=tls_server_name,
                                   token=token, token_file=token_file)
        elif any(v is not None for v in (tls_ca, tls_cert, tls_key, tls_server_name,
                                         token, token_file)):
            raise ValueError("give channel= or the TLS / token arguments, not both")
        self._channel = channel
        self._maps = map_service_pb2_grpc.MapServiceStub(self._channel)
        self._planner = planner_service_pb2_grpc.PlannerServiceStub(self._channel)
        self._health_check = self._channel.unary_unary(
            health.HEALTH_CHECK_METHOD,
            request_serializer=health.HealthCheckRequest.SerializeToString,
            response_deserializer=health.HealthCheckResponse.FromString)

    def close(self) -> None:
        self._channel.close()

    def __enter__(self) -> PathdClient:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def _call(self, method, request, map_name: str | None,
              timeout: float | None):
        # ListMaps has no map: without the header a balancer picks any replica.
        try:
            return method(request, timeout=self._timeout(timeout),
                          metadata=self._metadata(map_name))
        except grpc.RpcError as error:
            raise _from_rpc_error(error) from None

    def _timeout(self, timeout: float | None) -> float:
        return self.timeout if timeout is None else timeout

    @staticmethod
    def _metadata(map_name: str | None) -> tuple:
        return ((MAP_HEADER, map_name),) if map_name else ()

    # ---- grpc.health.v1 ----

    def health(self, service: str = "", *, timeout: float | None = None) -> str:
        """The server's serving state ("SERVING", "NOT_SERVING", ...) from
        the standard gRPC health check; `service` empty asks about the whole
        server. Needs no token."""
        response = self._call(self._health_check,
                              health.HealthCheckRequest(service=service), None, timeout)
        return health.status_name(response)

    # ---- MapService ----

    def create_map(self, name: str, rows: Sequence[str] | None = None, *,
                   cells: bytes | None = None, width: int | None = None,
                   height: int | None = None, from_file: str | os.PathLike | None = None,
                   map_dir_file: str | None = None, resolution: float = 1.0,
                   origin: tuple[float, float, float] | None = None,
                   replace: bool = False, timeout: float | None = None) -> MapInfo:
        """Creates a map from one of `rows`, `cells`, `from_file` and
        `map_dir_file`.

        `rows` are Moving AI map rows, all the same length ('.' free; '@',
        'T', 'O', 'W' blocked), sent as a .map text so the server's parser
        checks them. `cells` are width * height cost bytes, row-major.
        `from_file` is a map file on this machine, as `pathctl maps create
        --from FILE` takes it: a Moving AI .map or a ROS map_server .yaml
        (with the image it names). `map_dir_file` is a .map or .yaml file
        in the server's --map_dir. `resolution` (metres per cell) and
        `origin` ((x, y, yaw) of cell (0, 0)'s corner) apply to rows, cells
        and .map files; a ROS map carries its own. `replace` replaces a map
        of the same name instead of raising AlreadyExistsError.
        """
        request = map_service_pb2.CreateMapRequest(
            name=name, resolution=resolution, replace=replace)
        if origin is not None:
            x, y, *yaw = origin
            request.origin.CopyFrom(common_pb2.Origin(x=x, y=y, yaw=yaw[0] if yaw else 0.0))
        sources = [s for s in (rows, cells, from_file, map_dir_file) if s is not None]
        if len(sources) != 1:
            raise ValueError("give exactly one of rows, cells, from_file and map_dir_file")
        if from_file is not None:
            set_source_from_file(request, from_file)
        elif map_dir_file is not None:
            request.map_dir_file = map_dir_file
        elif rows is not None:
            if not rows:
                raise ValueError("rows is empty")
            request.movingai_text = (
                f"type octile\nheight {len(rows)}\nwidth {len(rows[0])}\nmap\n"
                + "\n".join(rows) + "\n")
        else:
            if width is None or height is None:
                raise ValueError("cells needs width and height")
            if len(cells) > UNARY_CREATE_MAP_BYTES:
                return self.upload_map(name, cells, width, height, resolution=resolution,
                                       origin=origin, replace=replace, timeout=timeout)
            request.raw.CopyFrom(map_service_pb2.RawCells(
                width=width, height=height, cells=bytes(cells)))
        if request.ByteSize() > UNARY_CREATE_MAP_BYTES and from_file is not None:
            # As pathctl: parsed here by the server's rules and streamed.
            width, height, cells, file_resolution, file_origin = cells_from_file(from_file)
            return self.upload_map(
                name, cells, width, height,
                resolution=resolution if file_resolution is None else file_resolution,
                origin=origin if file_origin is None else file_origin,
                replace=replace, timeout=timeout)
        if request.ByteSize() > UNARY_CREATE_MAP_BYTES and rows is not None:
            width, height, cells = parse_movingai(request.movingai_text.encode(), "rows")
            return self.upload_map(name, cells, width, height, resolution=resolution,
                                   origin=origin, replace=replace, timeout=timeout)
        if request.ByteSize() > UNARY_CREATE_MAP_BYTES:
            raise ValueError(
                f"map {name!r}: a {request.ByteSize()}-byte CreateMap request is over "
                f"{UNARY_CREATE_MAP_BYTES} bytes; pass its cost bytes as cells= "
                "(streamed through UploadMap)")
        response = self._call(self._maps.CreateMap, request, name, timeout)
        return MapInfo.from_proto(response.info)

    def upload_map(self, name: str, cells: bytes, width: int, height: int, *,
                   resolution: float = 1.0,
                   origin: tuple[float, float, float] | None = None,
                   replace: bool = False, band_bytes: int = UPLOAD_BAND_BYTES,
                   timeout: float | None = None) -> MapInfo:
        """Creates a map of any size through UploadMap: a header, then the
        width * height row-major cost bytes in bands of whole rows of at most
        `band_bytes` (at least one row). create_map calls it for cells over
        4 MiB. The deadline is `timeout` plus a second per 16 MiB."""
        header = map_service_pb2.UploadMapHeader(
            name=name, width=width, height=height, resolution=resolution,
            replace=replace)
        if origin is not None:
            x, y, *yaw = origin
            header.origin.CopyFrom(common_pb2.Origin(x=x, y=y, yaw=yaw[0] if yaw else 0.0))
        data = memoryview(bytes(cells))
        row_bytes = max(width, 1)
        band = max(1, band_bytes // row_bytes) * row_bytes

        def messages():
            yield map_service_pb2.UploadMapRequest(header=header)
            for offset in range(0, len(data), band):
                yield map_service_pb2.UploadMapRequest(band=map_service_pb2.CellBand(
                    first_row=offset // row_bytes, cells=bytes(data[offset:offset + band])))

        response = self._call(self._maps.UploadMap, messages(), name,
                              self._transfer_timeout(timeout, len(data)))
        return MapInfo.from_proto(response.info)

    def _transfer_timeout(self, timeout: float | None, size: int) -> float:
        return self._timeout(timeout) + size / TRANSFER_BYTES_PER_SECOND

    def get_map(self, name: str, *, timeout: float | None = None) -> MapInfo:
        response = self._call(self._maps.GetMap,
                              map_service_pb2.GetMapRequest(name=name), name, timeout)
        return MapInfo.from_proto(response.info)

    def get_cells(self, name: str, *, timeout: float | None = None) -> MapCells:
        """The current version with its cost bytes, of any size: streamed
        through DownloadMap (metadata, then bands of rows of at most 1 MiB),
        with GetMap's size setting the deadline as upload_map does."""
        info = self.get_map(name, timeout=timeout)
        call_timeout = self._transfer_timeout(timeout, info.width * info.height)
        parts: list[bytes] = []
        first = None
        received = 0
        try:
            for message in self._maps.DownloadMap(
                    map_service_pb2.DownloadMapRequest(name=name), timeout=call_timeout,
                    metadata=self._metadata(name)):
                if message.HasField("info"):
                    first = message.info
                    continue
                if first is None or message.band.first_row * first.width != received:
                    raise PathdError(
                        grpc.StatusCode.INTERNAL, f"DownloadMap of {name!r}: band at row {message.band.first_row} "
                        f"does not continue the {received} bytes received")
                parts.append(message.band.cells)
                received += len(message.band.cells)
        except grpc.RpcError as error:
            raise _from_rpc_error(error) from None
        if first is None or received != first.width * first.height:
            raise PathdError(grpc.StatusCode.INTERNAL,
                             f"DownloadMap of {name!r}: got {received} cell bytes")
        return MapCells(MapInfo.from_proto(first), b"".join(parts))

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

    def plan(self, map_name: str, start: PositionLike, goal: PositionLike, *,
             planner: str | None = None,
             options: planner_service_pb2.PlanOptions | None = None,
             via: Sequence[PositionLike] = (), allow_partial: bool = False,
             timeout: float | None = None, **option_keywords) -> PlanResult:
        """Plans one path. `planner` is a name as pathctl spells it ("astar",
        "dstar_lite", ...; None: the server's default). start, goal and `via`
        (intermediate goals, in order) are cells, WorldPoint, WorldPose
        (metres, radians; the exact pose for the kinematic planners) or
        CellPose. `allow_partial`: with via, a failed leg answers the path
        to the last goal reached. Options as `options=plan_options(...)` or
        as the same keywords here. No path is a result with found False; a
        bad start or goal raises with `outcome` set."""
        request = plan_request(map_name, start, goal, planner=planner, options=options,
                               via=via, allow_partial=allow_partial, **option_keywords)
        return PlanResult.from_proto(
            self._call(self._planner.Plan, request, map_name, timeout))

    def plan_stream(self, map_name: str, start: PositionLike, goal: PositionLike, *,
                    planner: str | None = None,
                    options: planner_service_pb2.PlanOptions | None = None,
                    via: Sequence[PositionLike] = (), allow_partial: bool = False,
                    timeout: float | None = None, **option_keywords) -> PlanStream:
        """Plans one path as plan() does, streaming the search's progress:
        iterate the PlanStream for PlanProgress events, then the PlanResult
        (or call .wait() for the result alone). The deadline covers the
        whole plan; leaving a `with` block early cancels it."""
        request = plan_request(map_name, start, goal, planner=planner, options=options,
                               via=via, allow_partial=allow_partial, **option_keywords)
        return PlanStream(self._planner.PlanStream(
            request, timeout=self._timeout(timeout), metadata=self._metadata(map_name)))

    def plan_batch(self, requests: Iterable[planner_service_pb2.PlanRequest
                                            | tuple[str, planner_service_pb2.PlanRequest]],
                   *, map_name: str | None = None,
                   timeout: float | None = None) -> PlanBatch:
        """Many plans over one PlanBatch stream: `requests` are PlanRequest
        messages (plan_request() builds them), each optionally paired with
        its own request_id (else its index as a string). Iterate the
        PlanBatch for a BatchAnswer per request as the plans finish. The
        stream is routed by `map_name` (default: the first request's map,
        when `requests` is a sequence). The deadline covers the whole batch
        (default `timeout`): pass a longer one for a long batch."""
        if map_name is None and isinstance(requests, Sequence) and requests:
            first = requests[0]
            map_name = (first[1] if isinstance(first, tuple) else first).map
        timeout, metadata = self._timeout(timeout), self._metadata(map_name)
        return PlanBatch(lambda iterator: self._planner.PlanBatch(
            iterator, timeout=timeout, metadata=metadata), requests)

    def cost_to_go(self, map_name: str, goal: PositionLike, *,
                   window: tuple[int, int, int, int] | None = None,
                   options: planner_service_pb2.PlanOptions | None = None,
                   timeout: float | None = None, **option_keywords) -> CostToGoResult:
        """The goal's cost-to-go field (the shortest path map the server
        caches for the spm planner): every cell's cheapest cost to `goal`,
        math.inf where unreachable; `window` (x, y, width, height) asks for
        part of the map. Cost options only (connectivity, cost_weight,
        unknown_is_free, robot radius, ...)."""
        request = planner_service_pb2.CostToGoRequest(
            map=map_name, goal=_position(goal), options=_options(options, option_keywords))
        if window is not None:
            x, y, width, height = window
            request.window.CopyFrom(planner_service_pb2.CellWindow(
                x=x, y=y, width=width, height=height))
        return CostToGoResult.from_proto(
            self._call(self._planner.CostToGo, request, map_name, timeout))

    def is_path_valid(self, map_name: str, path: Sequence[PositionLike], *,
                      options: planner_service_pb2.PlanOptions | None = None,
                      timeout: float | None = None, **option_keywords) -> PathCheck:
        """Checks a path the robot holds against the map's current version:
        poses the robot may not occupy and steps that are not legal moves
        (with a footprint: the footprint along the poses). An invalid path
        is a PathCheck with valid False, not an error."""
        request = planner_service_pb2.IsPathValidRequest(
            map=map_name, path=[_position(p) for p in path],
            options=_options(options, option_keywords))
        return PathCheck.from_proto(
            self._call(self._planner.IsPathValid, request, map_name, timeout))

    def list_sessions(self, map_name: str | None = None, *,
                      timeout: float | None = None) -> list[SessionInfo]:
        """The open Navigate sessions (on `map_name`, or on every map), in
        session id order, each with the last update it sent."""
        response = self._call(self._planner.ListSessions,
                              planner_service_pb2.ListSessionsRequest(map=map_name or ""),
                              map_name, timeout)
        return [SessionInfo.from_proto(info) for info in response.sessions]

    def get_cache_stats(self, *, timeout: float | None = None) -> CacheStatsResult:
        """Counters of the server's incremental-state caches (spm,
        dstar_lite) and its open Navigate sessions."""
        return CacheStatsResult.from_proto(self._call(
            self._planner.GetCacheStats, planner_service_pb2.GetCacheStatsRequest(),
            None, timeout))

    def table(self, map_name: str, sources: Sequence[PositionLike],
              destinations: Sequence[PositionLike], *, method: str | None = None,
              options: planner_service_pb2.PlanOptions | None = None,
              timeout: float | None = None, **option_keywords) -> TableResult:
        """Cheapest costs from every source to every destination (OSRM's
        table); None where no path exists. `method` "backward" (one cached
        cost-to-go field per destination), "forward" (one search per source)
        or None (the server's choice). `options` carries the cost options and
        robot radius (plan_options())."""
        request = planner_service_pb2.TableRequest(
            map=map_name, sources=[_position(p) for p in sources],
            destinations=[_position(p) for p in destinations],
            options=_options(options, option_keywords))
        if method:
            request.method = planner_service_pb2.TableMethod.Value(
                "TABLE_METHOD_" + method.upper())
        return TableResult.from_proto(
            self._call(self._planner.Table, request, map_name, timeout))

    def nearest(self, map_name: str, point: PositionLike, *,
                max_distance_m: float | None = None,
                max_distance_cells: float | None = None,
                options: planner_service_pb2.PlanOptions | None = None,
                timeout: float | None = None, **option_keywords) -> NearestResult:
        """The nearest cell to `point` where the robot (options' robot radius,
        or polygon footprint at the point's heading) may stand."""
        request = planner_service_pb2.NearestRequest(
            map=map_name, point=_position(point), options=_options(options, option_keywords))
        if max_distance_m is not None and max_distance_cells is not None:
            raise ValueError("give max_distance_m or max_distance_cells, not both")
        if max_distance_m is not None:
            request.max_distance_m = max_distance_m
        if max_distance_cells is not None:
            request.max_distance_cells = max_distance_cells
        return NearestResult.from_proto(
            self._call(self._planner.Nearest, request, map_name, timeout))

    def trip(self, map_name: str, waypoints: Sequence[PositionLike], *,
             end: str = "round_trip", planner: str | None = None,
             options: planner_service_pb2.PlanOptions | None = None,
             timeout: float | None = None, **option_keywords) -> TripResult:
        """The order to visit `waypoints` starting at the first: `end`
        "round_trip" (back to it), "fixed_last" or "any"; exact up to 12
        stops, a local search with a lower bound above. The legs come back
        as one plan."""
        request = planner_service_pb2.TripRequest(
            map=map_name, waypoints=[_position(p) for p in waypoints],
            end=planner_service_pb2.TripEnd.Value("TRIP_END_" + end.upper()),
            planner=_planner(planner), options=_plan_options(options, option_keywords))
        return TripResult.from_proto(
            self._call(self._planner.Trip, request, map_name, timeout))

    def isochrone(self, map_name: str, start: PositionLike, *,
                  budget_m: float | None = None, budget_cells: float | None = None,
                  options: planner_service_pb2.PlanOptions | None = None,
                  timeout: float | None = None, **option_keywords) -> IsochroneResult:
        """The region reachable from `start` within a cost budget (metres or
        cells, one of them), as polygons with holes in world metres."""
        if (budget_m is None) == (budget_cells is None):
            raise ValueError("give budget_m or budget_cells, one of them")
        request = planner_service_pb2.IsochroneRequest(
            map=map_name, start=_position(start), options=_options(options, option_keywords))
        if budget_m is not None:
            request.budget_m = budget_m
        else:
            request.budget_cells = budget_cells
        return IsochroneResult.from_proto(
            self._call(self._planner.Isochrone, request, map_name, timeout))

    def plan_fleet(self, map_name: str,
                   robots: Sequence[tuple[PositionLike, PositionLike]
                                    | tuple[PositionLike, PositionLike, float | None]
                                    | tuple[PositionLike, PositionLike, float | None, str]],
                   *,
                   solver: str = "lacam", time_limit_s: float | None = None,
                   suboptimality: float | None = None, restarts: int | None = None,
                   seed: int | None = None, max_steps: int | None = None,
                   refine: bool = False,
                   options: planner_service_pb2.PlanOptions | None = None,
                   timeout: float | None = None, **option_keywords) -> FleetPlanResult:
        """Conflict-free timed paths for many robots: `robots` holds (start,
        goal), (start, goal, radius_m) or (start, goal, radius_m, name) per
        robot (the name comes back in FleetPlanResult.names). `solver` "lacam"
        (complete, scales to hundreds), "pibt" (fastest, incomplete),
        "prioritized" (cooperative A* with restarts) or "cbs" (optimal sum of
        costs; `suboptimality` > 1 for ECBS); `refine` makes lacam improve its
        first plan (LaCAM*) until the time limit. The solver answers with its
        best plan when `time_limit_s` (default 10 s) runs out; `timeout` is
        the call's deadline."""
        request = planner_service_pb2.PlanFleetRequest(
            map=map_name, options=_options(options, option_keywords),
            solver=planner_service_pb2.FleetSolver.Value("FLEET_SOLVER_" + solver.upper()))
        for robot in robots:
            r = request.robots.add(start=_position(robot[0]), goal=_position(robot[1]))
            if len(robot) > 2 and robot[2] is not None:
                r.radius_m = robot[2]
            if len(robot) > 3:
                r.name = robot[3]
        if time_limit_s is not None:
            request.time_limit_ms = max(1, round(time_limit_s * 1000))
        if suboptimality is not None:
            request.suboptimality = suboptimality
        if restarts is not None:
            request.restarts = restarts
        if seed is not None:
            request.seed = seed
        if max_steps is not None:
            request.max_steps = max_steps
        request.refine = refine
        return FleetPlanResult.from_proto(
            self._call(self._planner.PlanFleet, request, map_name, timeout))

    def navigate(self, map_name: str, start: PositionLike, goal: PositionLike, *,
                 options: planner_service_pb2.PlanOptions | None = None,
                 planner: str | None = None,
                 replan_max_expansions: int = 0,
                 control: planner_service_pb2.ControlOptions | dict | None = None,
                 fleet: str | None = None, fleet_solver: str | None = None,
                 timeout: float | None = None, **option_keywords) -> NavigationSession:
        """Opens a Navigate session and waits for its first path.

        D* Lite by default. With planner "hybrid_astar" or "state_lattice"
        (or options giving a turning radius or motion model) it is a
        kinematic session for the robot of `options` (footprint, turning
        radius, ...): start, goal and move() take WorldPose values, and each
        answer's plan.poses are world poses from the robot's pose, each
        replan spending at most `replan_max_expansions` (0: the server's
        default, 20000).

        With `control` (a ControlOptions, or a dict of its fields:
        {"local_planner": "orca", "limits": {"max_v": 0.8}, "control_period":
        0.1, "local_options": {"time_horizon": 2.0}}; {} for every default)
        it is a control session: session.control(pose, v=..., w=...) answers
        each robot state with a velocity command (docs/service.md, "Control
        sessions"). The robot needs a size: robot_radius_m or a footprint.

        With `fleet` (a group name) it is a fleet session: the robots of the
        group's sessions on the map are planned together (`fleet_solver`:
        "lacam", "pibt", "prioritized" or "cbs"; the group's when None) and
        each answer and push carries `update.fleet`, the robot's timed path
        and how far it may drive now (`released_cells`); move() to each of
        those cells in turn and wait_push() when none is left
        (docs/service.md, "Fleet sessions").

        `timeout` bounds each wait for an answer, not the session, which
        lasts until closed (the server ends it after --session_idle_timeout
        without a message).
        """
        open_request = planner_service_pb2.NavigateOpen(
            map=map_name, start=_position(start), goal=_position(goal),
            options=_plan_options(options, option_keywords), planner=_planner(planner),
            replan_max_expansions=replan_max_expansions)
        if control is not None:
            open_request.control.CopyFrom(_control_options(control))
        if fleet is not None:
            open_request.fleet.group = fleet
            if fleet_solver is not None:
                open_request.fleet.solver = planner_service_pb2.FleetSolver.Value(
                    "FLEET_SOLVER_" + fleet_solver.upper())
        return NavigationSession(self._planner, map_name, open_request,
                                 self.timeout if timeout is None else timeout)


def _control_options(value: planner_service_pb2.ControlOptions | dict
                     ) -> planner_service_pb2.ControlOptions:
    """A ControlOptions from itself or a dict of its fields (local_planner by
    name: "orca", "dwa" or "firas")."""
    if isinstance(value, planner_service_pb2.ControlOptions):
        return value
    fields = dict(value)
    planner = fields.pop("local_planner", None)
    limits = fields.pop("limits", None)
    local_options = fields.pop("local_options", None)
    options = planner_service_pb2.ControlOptions(**fields)
    if planner is not None:
        options.local_planner = planner_service_pb2.LocalPlanner.Value(
            "LOCAL_PLANNER_" + str(planner).upper())
    if limits is not None:
        options.limits.CopyFrom(planner_service_pb2.VelocityLimits(**limits))
    if local_options is not None:
        for name, number in local_options.items():
            options.local_options[name] = float(number)
    return options
