#!/usr/bin/python3
"""The Python client (client/python) against a real pathd, plus a fake
server that records what the client puts on the wire.

Run by ctest with PYTHONPATH set to the build's client/python directory and
PATHD_BIN to the daemon; by hand:
    PYTHONPATH=build/client/python PATHD_BIN=build/server/pathd \\
        tests/client/pathd_client_test.py
"""

import heapq
import itertools
import math
import os
import pathlib
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import unittest
from concurrent import futures

import grpc

import pathd_client
from pathd_client import (LETHAL, Cell, PathdClient, PathdError, SetCell,
                          SetRect)
from pathd.v1 import common_pb2
from pathd.v1 import map_service_pb2
from pathd.v1 import map_service_pb2_grpc
from pathd.v1 import planner_service_pb2
from pathd.v1 import planner_service_pb2_grpc

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(SOURCE_DIR / "tests" / "testing"))
from pathd_process import PathdProcess  # pylint: disable=wrong-import-position
EXAMPLE = SOURCE_DIR / "client" / "python" / "examples" / "robot_loop.py"

# 14 x 8: a wall at column 6 with openings at rows 0 and 7.
ROWS = [
    "..............",
    "......@.......",
    "......@.......",
    "......@.......",
    "......@.......",
    "......@.......",
    "......@.......",
    "..............",
]


def fleet_conflicts(paths, robots, blocked) -> list[str]:
    """What breaks PlanFleet's rule in `paths`: each path runs from its
    robot's start to its goal in legal 8-connected moves (no corner
    cutting), and in each step no two robots sweep one cell (their cells
    before and after, and a diagonal move's two side cells)."""
    problems = []
    horizon = max(len(p) for p in paths)

    def at(p, t):
        return p[min(t, len(p) - 1)]
    for i, (path, (start, goal)) in enumerate(zip(paths, robots)):
        if path[0] != start or path[-1] != goal:
            problems.append(f"robot {i} runs {path[0]} -> {path[-1]}")
    for t in range(horizon):
        owner = {}
        for i, path in enumerate(paths):
            a, b = at(path, t), at(path, t + 1)
            dx, dy = b.x - a.x, b.y - a.y
            if max(abs(dx), abs(dy)) > 1 or b in blocked:
                problems.append(f"robot {i} jumps {a} -> {b} at {t}")
            swept = {a, b}
            if dx and dy:
                swept |= {Cell(a.x + dx, a.y), Cell(a.x, a.y + dy)}
                if swept & blocked:
                    problems.append(f"robot {i} cuts a corner at {t}")
            for c in swept:
                if c in owner and owner[c] != i:
                    problems.append(f"robots {owner[c]} and {i} share {c} at step {t}")
                owner[c] = i
    return problems


def blocked_cells(rows: list[str]) -> set[Cell]:
    return {Cell(x, y) for y, row in enumerate(rows) for x, c in enumerate(row) if c == "@"}


def shortest_cost(width: int, height: int, blocked: set[Cell], start: Cell,
                  goal: Cell) -> float:
    """Dijkstra on a free/blocked grid under pathd's default rules:
    8-connected, 1 per straight and sqrt(2) per diagonal move, diagonals only
    when both side cells are free. math.inf when unreachable."""
    def free(x, y):
        return 0 <= x < width and 0 <= y < height and Cell(x, y) not in blocked

    dist = {start: 0.0}
    heap = [(0.0, start)]
    while heap:
        d, cell = heapq.heappop(heap)
        if cell == goal:
            return d
        if d > dist[cell]:
            continue
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                x, y = cell.x + dx, cell.y + dy
                if (dx, dy) == (0, 0) or not free(x, y):
                    continue
                if dx and dy and not (free(cell.x + dx, cell.y) and free(cell.x, cell.y + dy)):
                    continue
                nd = d + (math.sqrt(2) if dx and dy else 1.0)
                if nd < dist.get(Cell(x, y), math.inf):
                    dist[Cell(x, y)] = nd
                    heapq.heappush(heap, (nd, Cell(x, y)))
    return math.inf


class PathChecks:
    """Assertions shared by the real-server tests."""

    def assert_valid_path(self, path, start, goal, width, height, blocked):
        self.assertEqual(path[0], start)
        self.assertEqual(path[-1], goal)
        for cell in path:
            self.assertTrue(0 <= cell.x < width and 0 <= cell.y < height, cell)
            self.assertNotIn(cell, blocked)
        for a, b in zip(path, path[1:]):
            dx, dy = b.x - a.x, b.y - a.y
            self.assertEqual(max(abs(dx), abs(dy)), 1, f"{a} -> {b} is not one move")
            if dx and dy:
                self.assertNotIn(Cell(a.x + dx, a.y), blocked, f"{a} -> {b} cuts a corner")
                self.assertNotIn(Cell(a.x, a.y + dy), blocked, f"{a} -> {b} cuts a corner")


class RealServerTest(unittest.TestCase, PathChecks):
    """pathd itself, started on a free loopback port."""

    @classmethod
    def setUpClass(cls):
        pathd = os.environ.get("PATHD_BIN", str(SOURCE_DIR / "build" / "server" / "pathd"))
        cls.map_dir = tempfile.TemporaryDirectory()
        # A progress event per millisecond of planning: PlanStream's
        # progress shows on a plan of a few milliseconds.
        cls.daemon = PathdProcess(pathd, [f"--map_dir={cls.map_dir.name}",
                                          "--progress_interval=1ms"])
        cls.address = cls.daemon.address
        cls.client = PathdClient(cls.address, timeout=10.0)
        # Another program changing the map: its own channel.
        cls.operator = PathdClient(cls.address, timeout=10.0)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        cls.operator.close()
        cls.daemon.stop()
        cls.map_dir.cleanup()

    def make_map(self, name: str):
        info = self.client.create_map(name, ROWS, replace=True)
        self.addCleanup(self._delete_quietly, name)
        return info

    def _delete_quietly(self, name):
        try:
            self.client.delete_map(name)
        except pathd_client.NotFoundError:
            pass

    def test_map_calls(self):
        info = self.make_map("maps")
        self.assertEqual((info.name, info.width, info.height, info.version),
                         ("maps", 14, 8, 1))
        self.assertEqual(info.blocked_cells, 6)
        self.assertEqual(info.free_cells, 14 * 8 - 6)

        cells = self.client.get_cells("maps")
        self.assertEqual(len(cells.cells), 14 * 8)
        self.assertEqual(cells.cost((6, 3)), LETHAL)
        self.assertEqual(cells.cost((5, 3)), 0)

        raw = bytes([0, 0, 254, 0, 9, 0])
        made = self.client.create_map("maps_raw", cells=raw, width=3, height=2)
        self.addCleanup(self._delete_quietly, "maps_raw")
        self.assertEqual((made.width, made.height, made.blocked_cells), (3, 2, 1))
        self.assertEqual(self.client.get_cells("maps_raw").cells, raw)

        names = [m.name for m in self.client.list_maps()]
        self.assertIn("maps", names)
        self.assertEqual(names, sorted(names))

        result = self.client.update_map(
            "maps", [SetCell(0, 0, LETHAL), SetRect(10, 2, 11, 3, 50)],
            expected_version=1)
        self.assertEqual((result.version, result.cells_changed), (2, 5))
        after = self.client.get_cells("maps")
        self.assertEqual(after.info.version, 2)
        self.assertEqual(after.cost((0, 0)), LETHAL)
        self.assertEqual(after.cost((11, 3)), 50)

        self.assertEqual(self.client.delete_map("maps"), 2)
        with self.assertRaises(pathd_client.NotFoundError):
            self.client.get_map("maps")

    def test_maps_over_one_message_are_streamed(self):
        # 3000 x 2000 cells (5.7 MiB): create_map streams them (UploadMap,
        # bands of 1 MiB), get_cells reads them back through DownloadMap.
        width, height = 3000, 2000
        cells = bytes((x * 7 + y) % 256 for y in range(height) for x in range(0, width, 1000)
                      for _ in range(1000))
        info = self.client.create_map("streamed", cells=cells, width=width, height=height,
                                      resolution=0.05, origin=(1.0, -2.0, 0.0))
        self.addCleanup(self._delete_quietly, "streamed")
        self.assertEqual((info.width, info.height, info.version), (width, height, 1))
        back = self.client.get_cells("streamed")
        self.assertEqual(back.info.resolution, 0.05)
        self.assertEqual(back.cells, cells)
        # Small bands, a header that does not match the cells.
        self.client.upload_map("streamed", cells[:width * 10], width, 10, replace=True,
                               band_bytes=width * 3)
        self.assertEqual(self.client.get_cells("streamed").cells, cells[:width * 10])
        with self.assertRaises(pathd_client.InvalidArgumentError) as raised:
            self.client.upload_map("short", cells[:width * 9], width, 10)
        self.assertIn("ended after 9 of header.height 10 rows", raised.exception.details)
        with self.assertRaises(pathd_client.NotFoundError):
            self.client.get_map("short")

    def test_large_map_files_are_parsed_here_like_the_server_parses_them(self):
        # Over 4 MiB: create_map(from_file=...) parses the file here and
        # streams it; the server parses the same file from --map_dir. Both
        # must give the same cells, resolution and origin.
        side = 2100
        folder = pathlib.Path(self.map_dir.name)
        rows = ["".join("@" if (x * 5 + y * 3) % 13 == 0 else "." for x in range(side))
                for y in range(side)]
        (folder / "bigtext.map").write_text(
            f"type octile\nheight {side}\nwidth {side}\nmap\n" + "\n".join(rows) + "\n")
        pixels = bytes((x * 7 + y * 11) % 256 for y in range(side) for x in range(side))
        (folder / "bigimage.pgm").write_bytes(f"P5\n{side} {side}\n255\n".encode() + pixels)
        for mode in ("trinary", "scale", "raw"):
            (folder / f"big_{mode}.yaml").write_text(
                "image: bigimage.pgm\nresolution: 0.05\norigin: [1.5, -2.0, 0.0]\n"
                f"negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: {mode}\n")
        for file in ["bigtext.map"] + [f"big_{m}.yaml" for m in ("trinary", "scale", "raw")]:
            with self.subTest(file=file):
                mine = self.client.create_map("mine", from_file=folder / file, replace=True)
                self.addCleanup(self._delete_quietly, "mine")
                theirs = self.client.create_map("theirs", map_dir_file=file, replace=True)
                self.addCleanup(self._delete_quietly, "theirs")
                self.assertEqual((mine.width, mine.height, mine.resolution, mine.origin),
                                 (theirs.width, theirs.height, theirs.resolution, theirs.origin))
                self.assertEqual(self.client.get_cells("mine").cells,
                                 self.client.get_cells("theirs").cells)
        # Rows over 4 MiB are streamed the same way.
        info = self.client.create_map("mine", rows, replace=True)
        self.assertEqual((info.width, info.height), (side, side))
        self.client.create_map("theirs", map_dir_file="bigtext.map", replace=True)
        self.assertEqual(self.client.get_cells("mine").cells,
                         self.client.get_cells("theirs").cells)

    def test_plan_is_valid_and_optimal(self):
        self.make_map("plan")
        start, goal = Cell(1, 3), Cell(12, 4)
        for planner in ("astar", "dijkstra", "jps"):
            with self.subTest(planner=planner):
                plan = self.client.plan("plan", start, goal, planner=planner)
                self.assertTrue(plan.found)
                self.assertEqual(plan.outcome, "FOUND")
                self.assertEqual(plan.map_version, 1)
                self.assert_valid_path(plan.path, start, goal, 14, 8, blocked_cells(ROWS))
                self.assertAlmostEqual(
                    plan.cost, shortest_cost(14, 8, blocked_cells(ROWS), start, goal), places=6)

        self.client.update_map("plan", [SetRect(6, 0, 6, 0, LETHAL), SetRect(6, 7, 6, 7, LETHAL)])
        cut = self.client.plan("plan", start, goal)
        self.assertFalse(cut.found)
        self.assertEqual(cut.outcome, "NO_PATH")
        self.assertEqual(cut.path, [])

    def test_min_clearance_is_sent_and_reported(self):
        self.make_map("clear")
        start, goal = Cell(1, 3), Cell(12, 4)
        plain = self.client.plan("clear", start, goal)
        options = pathd_client.plan_options(min_clearance_m=2.0)
        self.assertEqual(options.min_clearance_m, 2.0)
        wide = self.client.plan("clear", start, goal, options=options)
        self.assertTrue(wide.found)
        self.assertTrue(wide.raw.has_clearance)
        self.assertFalse(plain.raw.has_clearance)
        self.assertGreaterEqual(wide.cost, plain.cost)
        with self.assertRaisesRegex(ValueError, "not both"):
            pathd_client.plan_options(robot_radius_cells=1, robot_radius_m=1)

    def test_world_poses_in_and_out(self):
        self.make_map("poses")
        # Resolution 1, origin 0: world (1.5, 3.5) is cell (1, 3)'s centre.
        start = pathd_client.WorldPose(1.5, 3.5, 0.0)
        goal = pathd_client.WorldPose(12.5, 4.5, 1.0)
        plan = self.client.plan("poses", start, goal)
        self.assertTrue(plan.found)
        self.assertEqual(plan.path[0], Cell(1, 3))
        self.assertEqual(plan.path[-1], Cell(12, 4))
        self.assertEqual(plan.frame_id, "map")
        self.assertEqual(len(plan.poses), len(plan.path))
        self.assertAlmostEqual(plan.poses[0].x, 1.5)
        self.assertAlmostEqual(plan.poses[0].y, 3.5)
        self.assertAlmostEqual(plan.length_m, plan.length)
        for pose, nxt in zip(plan.poses, plan.poses[1:]):
            self.assertAlmostEqual(pose.yaw, math.atan2(nxt.y - pose.y, nxt.x - pose.x))
        rectangle = [(0.3, 0.2), (0.3, -0.2), (-0.3, -0.2), (-0.3, 0.2)]
        options = pathd_client.plan_options(footprint_m=rectangle, motion_model="reeds_shepp",
                                            min_turning_radius_m=2.0, goal_yaw_tolerance=0.1)
        self.assertEqual(len(options.footprint.polygon_m), 4)
        self.assertEqual(options.min_turning_radius_m, 2.0)
        with self.assertRaisesRegex(ValueError, "motion model 'tank'"):
            pathd_client.plan_options(motion_model="tank")
        # A grid planner plans for the footprint's inscribed radius (0.2 m).
        shaped = self.client.plan("poses", start, goal, options=options)
        self.assertAlmostEqual(shaped.raw.robot_radius_m, 0.2)
        self.assertIsNone(shaped.footprint_collision)
        # smooth=True: the grid path also as poses smoothed for the robot.
        smoothed = self.client.plan(
            "poses", start, goal,
            options=pathd_client.plan_options(footprint_m=rectangle, smooth=True))
        self.assertTrue(smoothed.found)
        self.assertGreater(len(smoothed.poses), len(smoothed.path))
        self.assertAlmostEqual(smoothed.poses[0].x, 1.5)
        self.assertAlmostEqual(smoothed.poses[0].y, 3.5)

    def test_inflation_costs_are_sent(self):
        self.make_map("inflate")
        start, goal = Cell(1, 3), Cell(12, 4)
        plain = self.client.plan("inflate", start, goal)
        options = pathd_client.plan_options(inflation_radius_m=3.0,
                                            cost_scaling_factor=0.5)
        self.assertEqual(options.inflation_radius_m, 3.0)
        self.assertEqual(options.cost_scaling_factor, 0.5)
        inflated = self.client.plan("inflate", start, goal, options=options)
        self.assertTrue(inflated.found)
        # Around the wall's ends every path pays the inflation costs.
        self.assertGreater(inflated.cost, plain.cost)
        with self.assertRaises(pathd_client.InvalidArgumentError) as bad:
            self.client.plan("inflate", start, goal, options=pathd_client.plan_options(
                inflation_radius_m=3.0, cost_scaling_factor=0.0))
        self.assertIn("options.cost_scaling_factor", bad.exception.details)

    def test_fleet_queries(self):
        self.make_map("fleet")
        blocked = blocked_cells(ROWS)
        sources = [Cell(1, 3), Cell(12, 4)]
        destinations = [Cell(12, 1), Cell(3, 6), Cell(6, 0)]
        # More destinations than sources: the server searches per source.
        table = self.client.table("fleet", sources, destinations)
        self.assertEqual(table.method, "FORWARD")
        for i, s in enumerate(sources):
            for j, d in enumerate(destinations):
                self.assertAlmostEqual(table.cost[i][j],
                                       shortest_cost(14, 8, blocked, s, d), places=6)
        backward = self.client.table("fleet", sources, destinations, method="backward")
        self.assertEqual(backward.method, "BACKWARD")
        again = self.client.table("fleet", sources, destinations, method="backward")
        self.assertEqual(again.fields_cached, 3)
        self.assertEqual(again.cost, backward.cost)

        near = self.client.nearest("fleet", (6, 3))
        self.assertTrue(near.found)
        self.assertIn(near.cell, (Cell(5, 3), Cell(7, 3)))
        self.assertAlmostEqual(near.distance_cells, 1.0)

        stops = [Cell(1, 1), Cell(12, 6), Cell(1, 6), Cell(12, 1)]
        trip = self.client.trip("fleet", stops)
        self.assertTrue(trip.found and trip.exact)
        self.assertEqual(sorted(trip.order), [0, 1, 2, 3])
        self.assertEqual(trip.order[0], 0)
        best = min(
            sum(shortest_cost(14, 8, blocked, stops[a], stops[b])
                for a, b in zip([0, *perm], [*perm, 0]))
            for perm in itertools.permutations([1, 2, 3]))
        self.assertAlmostEqual(trip.cost_m, best, places=6)
        self.assertTrue(trip.plan.found)
        self.assertEqual(trip.plan.path[0], stops[0])
        self.assertEqual(trip.plan.path[-1], stops[0])

        iso = self.client.isochrone("fleet", (1, 3), budget_cells=2.5)
        within = sum(1 for y in range(8) for x in range(14)
                     if Cell(x, y) not in blocked
                     and shortest_cost(14, 8, blocked, Cell(1, 3), Cell(x, y)) <= 2.5)
        self.assertEqual(iso.reachable_cells, within)
        self.assertEqual(len(iso.polygons), 1)
        self.assertEqual(iso.geojson()["geometry"]["type"], "MultiPolygon")
        with self.assertRaisesRegex(ValueError, "one of them"):
            self.client.isochrone("fleet", (1, 3))

        snapped = self.client.plan("fleet", (6, 3), (12, 4),
                                   options=pathd_client.plan_options(snap_start=True))
        self.assertTrue(snapped.found)
        self.assertTrue(snapped.raw.start_snapped)
        self.assertEqual(snapped.path[0], Cell(5, 3))  # ties: smaller row, then column
        with self.assertRaisesRegex(pathd_client.InvalidArgumentError, r"sources\[0\]"):
            self.client.table("fleet", [(6, 3)], destinations)

    def test_plan_fleet(self):
        self.make_map("fleet")
        blocked = blocked_cells(ROWS)
        # Four robots trading sides of the wall, two of them through the
        # same gap.
        robots = [(Cell(1, 0), Cell(12, 7)), (Cell(12, 7), Cell(1, 0)),
                  (Cell(1, 7), Cell(12, 0)), (Cell(12, 0), Cell(1, 7))]
        for solver in ("lacam", "pibt", "prioritized", "cbs"):
            fleet = self.client.plan_fleet("fleet", robots, solver=solver, time_limit_s=5)
            self.assertTrue(fleet.found, (solver, fleet.reason))
            self.assertEqual(fleet.solver, solver)
            self.assertEqual(fleet_conflicts(fleet.paths, robots, blocked), [], solver)
            self.assertEqual(fleet.sum_of_costs, sum(fleet.costs))
            self.assertGreaterEqual(fleet.sum_of_costs, fleet.lower_bound)
            self.assertEqual(len(fleet.world_paths[0]), len(fleet.paths[0]))
        named = self.client.plan_fleet("fleet", [robots[0] + (None, "amr-1"),
                                                 robots[1] + (0.4, "amr-2")], solver="pibt")
        self.assertEqual(named.names, ["amr-1", "amr-2"])
        self.assertEqual(named.radii_m[1], 0.4)
        with self.assertRaisesRegex(pathd_client.InvalidArgumentError,
                                    r"robots\[1\]\.start \(1, 0\) is the start of robots\[0\]"):
            self.client.plan_fleet("fleet", [robots[0], (Cell(1, 0), Cell(5, 0))])

    def test_errors_carry_the_status(self):
        self.make_map("errors")
        with self.assertRaises(PathdError) as missing:
            self.client.plan("no_such_map", (0, 0), (1, 1))
        self.assertIsInstance(missing.exception, pathd_client.NotFoundError)
        self.assertEqual(missing.exception.code, grpc.StatusCode.NOT_FOUND)
        self.assertIn("no_such_map", missing.exception.details)
        self.assertEqual(missing.exception.outcome, "MAP_NOT_FOUND")

        with self.assertRaises(pathd_client.InvalidArgumentError) as occupied:
            self.client.plan("errors", (0, 0), (6, 3))
        self.assertEqual(occupied.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertEqual(occupied.exception.outcome, "GOAL_OCCUPIED")

        with self.assertRaises(pathd_client.AlreadyExistsError):
            self.client.create_map("errors", ROWS)
        with self.assertRaises(pathd_client.AbortedError) as stale:
            self.client.update_map("errors", [SetCell(0, 0, LETHAL)], expected_version=7)
        self.assertEqual(stale.exception.code, grpc.StatusCode.ABORTED)
        with self.assertRaises(pathd_client.InvalidArgumentError):
            self.client.create_map("bad_rows", ["...", ".x."])
        with self.assertRaises(pathd_client.NotFoundError):
            self.client.navigate("no_such_map", (0, 0), (1, 1))
        with self.assertRaises(pathd_client.NotFoundError):
            self.client.delete_map("no_such_map")

        # A port nobody listens on: the transport error is a PathdError too.
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        with PathdClient(f"127.0.0.1:{port}", timeout=5.0) as nobody:
            with self.assertRaises(pathd_client.UnavailableError):
                nobody.list_maps()

    def test_navigation_follows_the_pushed_path(self):
        self.make_map("nav")
        start, goal = Cell(1, 3), Cell(12, 4)
        blocked = blocked_cells(ROWS)
        with self.client.navigate("nav", start, goal) as nav:
            self.assertEqual(nav.opened.event, "OPENED")
            self.assertEqual(nav.opened.seq, 1)
            self.assertTrue(nav.opened.plan.found)
            self.assert_valid_path(nav.path, start, goal, 14, 8, blocked)

            # Two steps along the path, each answered with the path from there.
            position = start
            for _ in range(2):
                position = nav.path[1]
                answer = nav.move(position)
                self.assertEqual(answer.event, "MOVED")
                self.assertEqual(answer.session_id, nav.session_id)
                self.assertEqual(answer.plan.path[0], position)

            # Another client closes the opening the path goes through.
            door = next(c for c in nav.path if c.x == 6)
            update = self.operator.update_map("nav", [SetCell(door.x, door.y, LETHAL)])
            blocked.add(door)
            push = nav.wait_push(10.0)
            self.assertIsNotNone(push, "no path pushed after the map changed")
            self.assertEqual((push.event, push.seq, push.pushed), ("MAP_CHANGED", 0, True))
            self.assertEqual(push.plan.map_version, update.version)
            self.assertTrue(push.plan.found)
            self.assertNotIn(door, push.plan.path)
            self.assert_valid_path(push.plan.path, position, goal, 14, 8, blocked)
            self.assertAlmostEqual(
                push.plan.cost, shortest_cost(14, 8, blocked, position, goal), places=6)
            self.assertEqual(nav.path, push.plan.path)

            # The robot's own sensor: a shared observation on the new path.
            # (Not in the wall's column: blocking the last opening leaves no path.)
            seen = next(c for c in nav.path if c.x > 7 and c != goal)
            observed = nav.observe([SetCell(seen.x, seen.y, LETHAL)])
            blocked.add(seen)
            self.assertEqual(observed.event, "OBSERVED")
            self.assertEqual(observed.applied_version, update.version + 1)
            self.assertNotIn(seen, observed.plan.path)
            self.assert_valid_path(observed.plan.path, position, goal, 14, 8, blocked)

            # Drive the rest of the way.
            while position != goal:
                position = nav.path[1]
                self.assertNotIn(position, blocked)
                self.assertEqual(nav.move(position).plan.path[0], position)
            self.assertEqual(nav.path, [goal])
            self.assertEqual(len(nav.pushes), 1)
        self.assertEqual(self.client.get_map("nav").version, update.version + 1)

    def test_kinematic_navigation_takes_and_returns_world_poses(self):
        # An open hall, 20 x 10 cells of 1 m: a 0.8 m x 0.6 m robot turning
        # on 1.5 m drives along row 3; another client walls off the row.
        rows = ["." * 20] * 10
        self.client.create_map("kin", rows, replace=True)
        self.addCleanup(self._delete_quietly, "kin")
        rectangle = [(0.4, 0.3), (0.4, -0.3), (-0.4, -0.3), (-0.4, 0.3)]
        options = pathd_client.plan_options(footprint_m=rectangle, motion_model="dubins",
                                            min_turning_radius_m=1.5)
        start = pathd_client.WorldPose(2.5, 3.5, 0.0)
        goal = pathd_client.WorldPose(17.5, 3.5, 0.0)
        with self.client.navigate("kin", start, goal, options=options,
                                  planner="hybrid_astar", replan_max_expansions=5000) as nav:
            self.assertTrue(nav.opened.plan.found)
            self.assertEqual(nav.opened.replan_max_expansions, 5000)
            self.assertEqual(nav.opened.plan.planner, "hybrid_astar")
            self.assertAlmostEqual(nav.poses[0].x, 2.5)
            self.assertAlmostEqual(nav.poses[-1].x, 17.5)
            robot = nav.poses[4]
            answer = nav.move(robot)
            self.assertEqual(answer.event, "MOVED")
            # A pose of its own path, whose rest is as cheap as the replan:
            # the robot keeps the path it is on.
            self.assertTrue(answer.kept_previous_path)
            self.assertTrue(answer.plan.found)
            self.assertAlmostEqual(answer.plan.poses[0].x, robot.x)
            self.assertAlmostEqual(answer.plan.poses[0].y, robot.y)
            self.assertAlmostEqual(answer.plan.poses[0].yaw, robot.yaw)
            self.assertAlmostEqual(answer.robot_cell_pose[0], robot.x)
            update = self.operator.update_map("kin", [SetRect(9, 0, 10, 5, LETHAL)])
            push = nav.wait_push(10.0)
            self.assertIsNotNone(push, "no replan pushed after the path was walled off")
            self.assertEqual(push.plan.map_version, update.version)
            self.assertTrue(push.plan.found)
            self.assertAlmostEqual(push.plan.poses[0].x, robot.x)
            # Round the wall: the robot's centre passes above row 6 there.
            self.assertTrue(any(p.y > 6.0 for p in push.plan.poses if 8.5 <= p.x <= 11.5))

    def test_control_session_drives_a_robot_to_its_goal(self):
        # An open hall, 20 x 10 cells of 1 m; a 0.4 m robot from (2.5, 4.5) to
        # (12.5, 4.5), integrated here (a unicycle) under each command.
        self.client.create_map("ctl", ["." * 20] * 10, replace=True)
        self.addCleanup(self._delete_quietly, "ctl")
        control = {"local_planner": "orca",
                   "limits": {"max_v": 1.0, "max_w": 2.0, "acc_v": 2.0, "acc_w": 4.0},
                   "control_period": 0.1, "local_options": {"goal_tolerance": 0.3}}
        x, y, yaw, v, w = 2.5, 4.5, 0.0, 0.0, 0.0
        with self.client.navigate("ctl", pathd_client.WorldPose(x, y, yaw),
                                  pathd_client.WorldPose(12.5, 4.5, 0.0),
                                  robot_radius_m=0.4, control=control) as nav:
            self.assertTrue(nav.opened.plan.found)
            outcome = None
            for step in range(400):
                answer = nav.control(pathd_client.WorldPose(x, y, yaw), v=v, w=w,
                                     stamp=step * 0.1,
                                     obstacles=[(x + 3.0, y + 3.0, 0.0, 0.0, 0.3)])
                self.assertEqual(answer.event, "CONTROL")
                command = answer.command
                self.assertEqual(answer.has_plan, step == 0)
                self.assertAlmostEqual(command.stamp, step * 0.1)
                self.assertEqual(command.neighbours, 1)  # the reported obstacle
                self.assertLessEqual(command.v, 1.0 + 1e-9)
                self.assertLessEqual(abs(command.v - v), 2.0 * 0.1 + 1e-9)
                self.assertLessEqual(abs(command.w - w), 4.0 * 0.1 + 1e-9)
                self.assertAlmostEqual(command.trajectory[0].x, x)
                outcome = command.outcome
                if outcome == "GOAL_REACHED":
                    break
                self.assertEqual(outcome, "OK", command.reason)
                v, w = command.v, command.w
                for _ in range(10):
                    x += v * math.cos(yaw + w * 0.005) * 0.01
                    y += v * math.sin(yaw + w * 0.005) * 0.01
                    yaw += w * 0.01
            self.assertEqual(outcome, "GOAL_REACHED")
            self.assertLess(math.hypot(x - 12.5, y - 4.5), 0.3 + 1e-6)
            # The global path stays the one the first answer carried.
            self.assertEqual(nav.path[-1], (12, 4))
        with self.assertRaises(pathd_client.InvalidArgumentError) as bad:
            self.client.navigate("ctl", (2, 4), (12, 4), control={})
        self.assertIn("open.options.robot_radius", bad.exception.details)

    def test_fleet_sessions_drive_released_cells_to_their_goals(self):
        # Two robots swapping the ends of an open hall, each a fleet session
        # of one group, driven in turns only through their released cells.
        self.client.create_map("fleet_hall", ["." * 12] * 4, replace=True)
        self.addCleanup(self._delete_quietly, "fleet_hall")
        ends = [((0, 1), (11, 2)), ((11, 2), (0, 1))]
        with self.client.navigate("fleet_hall", ends[0][0], ends[0][1], fleet="py",
                                  fleet_solver="lacam") as first, \
                self.client.navigate("fleet_hall", ends[1][0], ends[1][1],
                                     fleet="py") as second:
            robots = [first, second]
            self.assertEqual(first.opened.fleet.robots, 1)
            self.assertEqual(second.opened.fleet.robots, 2)
            states = [first.opened.fleet, second.opened.fleet]
            at = [ends[0][0], ends[1][0]]
            for _ in range(200):
                moved = False
                for r, nav in enumerate(robots):
                    pushed = nav.poll_pushes()
                    if pushed and pushed[-1].fleet is not None:
                        states[r] = pushed[-1].fleet
                    for cell in states[r].released_cells:
                        if cell == at[r]:
                            continue
                        other = at[1 - r]
                        self.assertGreater(max(abs(cell[0] - other[0]),
                                               abs(cell[1] - other[1])), 0)
                        answer = nav.move(cell)
                        self.assertEqual(answer.event, "MOVED")
                        states[r] = answer.fleet
                        at[r] = cell
                        moved = True
                        break
                if all(state.arrived for state in states):
                    break
                if not moved:
                    # Both wait: a push releases one of them.
                    for r, nav in enumerate(robots):
                        push = nav.wait_push(0.2)
                        if push is not None and push.fleet is not None:
                            states[r] = push.fleet
            self.assertEqual(at, [ends[0][1], ends[1][1]])
            self.assertTrue(all(state.planned for state in states))

    def test_bad_navigate_message_ends_the_session(self):
        self.make_map("nav_bad")
        with self.client.navigate("nav_bad", (0, 0), (13, 7)) as nav:
            with self.assertRaises(pathd_client.InvalidArgumentError) as off_map:
                nav.move((40, 0))
            self.assertIn("outside", off_map.exception.details)
            with self.assertRaises(pathd_client.InvalidArgumentError):
                nav.move((1, 0))  # the session has ended with that error

    def test_watch_map(self):
        self.make_map("watched")
        with self.client.watch_map("watched") as watch:
            events = iter(watch)
            first = next(events)
            self.assertEqual(first.kind, "RESYNC")
            self.assertEqual(first.version, 1)
            self.assertEqual(len(first.cells), 14 * 8)
            self.operator.update_map("watched", [SetRect(2, 2, 3, 2, 7)])
            updated = next(events)
            self.assertEqual((updated.kind, updated.version), ("UPDATED", 2))
            self.assertEqual(updated.changes, [pathd_client.ChangedRect(2, 2, 3, 2, bytes([7, 7]))])
            self.operator.delete_map("watched")
            self.assertEqual(next(events).kind, "DELETED")
            self.assertEqual(list(events), [])

    def test_every_rpc_has_a_client_method(self):
        # A new RPC in proto/pathd/v1 fails this until the client has it
        # (and this table names it).
        methods = {
            "MapService": {"CreateMap": "create_map", "GetMap": "get_map",
                           "ListMaps": "list_maps", "DeleteMap": "delete_map",
                           "UpdateMap": "update_map", "WatchMap": "watch_map",
                           "UploadMap": "upload_map", "DownloadMap": "get_cells"},
            "PlannerService": {"Plan": "plan", "CostToGo": "cost_to_go",
                               "Navigate": "navigate", "GetCacheStats": "get_cache_stats",
                               "IsPathValid": "is_path_valid", "PlanStream": "plan_stream",
                               "PlanBatch": "plan_batch", "Table": "table",
                               "Nearest": "nearest", "Trip": "trip",
                               "Isochrone": "isochrone", "PlanFleet": "plan_fleet",
                               "ListSessions": "list_sessions"},
        }
        for module in (map_service_pb2, planner_service_pb2):
            for service in module.DESCRIPTOR.services_by_name.values():
                for method in service.methods:
                    with self.subTest(rpc=f"{service.name}/{method.name}"):
                        self.assertIn(method.name, methods[service.name])
                        self.assertTrue(callable(getattr(PathdClient,
                                                         methods[service.name][method.name])))

    def test_plan_options_set_every_field(self):
        # One keyword setting per PlanOptions field (a oneof's metres and
        # cells members each): a field added to the proto fails this until
        # plan_options() takes it.
        settings = [
            dict(connectivity=4), dict(cost_weight=0.5), dict(unknown_is_free=True),
            dict(max_expansions=10), dict(heuristic_weight=1.2), dict(robot_radius_m=0.2),
            dict(robot_radius_cells=1.0), dict(simplify=True), dict(lookahead=8),
            dict(return_cost_to_go=True),
            dict(potential_field={"attractive": "conic", "attractive_gain": 2.0,
                                  "switch_distance": 4.0, "repulsive_gain": 5.0,
                                  "influence_distance": 2.0, "step_size": 0.25,
                                  "max_steps": 99}),
            dict(goal_tolerance_m=0.5), dict(goal_tolerance_cells=2.0),
            dict(return_expansions=True), dict(min_clearance_m=0.5),
            dict(min_clearance_cells=2.0), dict(inflation_radius_m=1.0),
            dict(inflation_radius_cells=3.0), dict(cost_scaling_factor=3.0),
            dict(footprint_m=[(0.3, 0.2), (0.3, -0.2), (-0.3, 0.0)]),
            dict(footprint_cells=[(3, 2), (3, -2), (-3, 0)]), dict(footprint_radius_m=0.3),
            dict(footprint_radius_cells=2.0), dict(min_turning_radius_m=1.0),
            dict(min_turning_radius_cells=4.0), dict(motion_model="reeds_shepp"),
            dict(reverse_penalty=2.0, change_penalty=0.5, non_straight_penalty=1.1,
                 cost_penalty=1.5),
            dict(goal_yaw_tolerance=0.2), dict(lattice="diff_5cm"), dict(smooth=False),
            dict(snap_start=True), dict(snap_start_max_m=0.4), dict(snap_start_max_cells=4.0),
            dict(ant_colony={"ants": 5, "iterations": 7, "stall_iterations": 0, "alpha": 1.5,
                             "beta": 3.0, "rho": 0.2, "xi": 0.05, "q0": 0.0, "tau0": 0.01,
                             "max_steps": 50, "seed": 9}),
            dict(reaction_diffusion={"diffusion": 2.0, "reaction_rate": 0.3,
                                     "threshold": 0.2, "time_step": 0.1, "max_steps": 500}),
        ]
        settings.insert(0, dict(path_encoding="both"))
        covered = set()
        for keywords in settings:
            options = pathd_client.plan_options(**keywords)
            changed = {field.name for field, _ in options.ListFields()} - {"connectivity"}
            if "connectivity" in keywords:
                self.assertEqual(options.connectivity, planner_service_pb2.CONNECTIVITY_FOUR)
                changed.add("connectivity")
            self.assertTrue(changed, keywords)
            covered |= changed
        fields = {f.name for f in planner_service_pb2.PlanOptions.DESCRIPTOR.fields}
        self.assertEqual(fields - covered, set())
        self.assertEqual(
            len(pathd_client.plan_options(reverse_penalty=2.0, change_penalty=0.5,
                                          non_straight_penalty=1.1,
                                          cost_penalty=1.5).penalties.ListFields()), 4)
        self.assertEqual(len(pathd_client.plan_options(
            potential_field=settings[11]["potential_field"]).potential_field.ListFields()), 7)
        # Every field set, a zero (q0 0, stall_iterations 0) included: they are
        # optional on the wire, so 0 is a value, not "unset".
        self.assertEqual(len(pathd_client.plan_options(
            ant_colony=settings[-2]["ant_colony"]).ant_colony.ListFields()), 11)
        self.assertEqual(len(pathd_client.plan_options(
            reaction_diffusion=settings[-1]["reaction_diffusion"])
            .reaction_diffusion.ListFields()), 5)
        for bad, message in ((dict(goal_tolerance_m=1, goal_tolerance_cells=1), "not both"),
                             (dict(footprint_m=[(1, 0)], footprint_radius_m=1), "one of"),
                             (dict(potential_field={"gain": 1}), "potential_field key"),
                             (dict(ant_colony={"ant": 1}), "ant_colony key"),
                             (dict(reaction_diffusion={"speed": 1}), "reaction_diffusion key"),
                             (dict(motion_model="hover"), "motion model 'hover'")):
            with self.assertRaisesRegex(ValueError, message):
                pathd_client.plan_options(**bad)

    def test_packed_paths_decode_to_the_readable_form(self):
        # The client asks for packed paths unless the options chose; the
        # decoder in values.py gives the cells and world points a readable
        # answer holds, world points bit for bit (a resolution and an origin
        # that make them unlike cells).
        self.client.create_map("packed", ROWS, resolution=0.05, origin=(-3.3, 1.7, 0.0),
                               replace=True)
        self.addCleanup(self._delete_quietly, "packed")
        cases = [dict(planner="astar"), dict(planner="jps"), dict(planner="theta_star"),
                 dict(planner="astar", connectivity=4), dict(planner="astar", simplify=True)]
        for keywords in cases:
            with self.subTest(**keywords):
                packed = self.client.plan("packed", (0, 0), (13, 7), **keywords)
                readable = self.client.plan("packed", (0, 0), (13, 7),
                                            path_encoding="readable", **keywords)
                self.assertTrue(packed.raw.packed_path)
                self.assertEqual(len(packed.raw.path), 0)
                self.assertFalse(readable.raw.packed_path)
                self.assertGreater(len(readable.path), 1)
                self.assertEqual(packed.path, readable.path)
                self.assertEqual(packed.world_path, readable.world_path)
                self.assertEqual(packed.poses, readable.poses)
                both = self.client.plan("packed", (0, 0), (13, 7), path_encoding="both",
                                        **keywords)
                self.assertEqual(pathd_client.decode_packed_path(both.raw.packed_path),
                                 readable.path)
        for bad, message in ((b"\x05\x01\x00\x00", "unknown format byte 0x05"),
                             (b"\x01\x03\x00\x00", "truncated"),
                             (b"\x01\x01\x00\x00\x00", "1 bytes after the last cell"),
                             (b"\x01\x02\x00\x00\x0b", "invalid move code 11")):
            with self.assertRaisesRegex(ValueError, message):
                pathd_client.decode_packed_path(bad)
        self.assertEqual(pathd_client.decode_packed_path(b""), [])

    def test_plan_via_points_and_option_keywords(self):
        self.make_map("via")
        blocked = blocked_cells(ROWS)
        start, via, goal = Cell(1, 3), Cell(3, 7), Cell(12, 4)
        plan = self.client.plan("via", start, goal, via=[via], return_expansions=True)
        self.assertTrue(plan.found)
        self.assert_valid_path(plan.path, start, goal, 14, 8, blocked)
        self.assertEqual(plan.reached_goal_index, 1)
        self.assertEqual(plan.path[plan.leg_end_indices[0]], via)
        self.assertAlmostEqual(plan.cost, shortest_cost(14, 8, blocked, start, via)
                               + shortest_cost(14, 8, blocked, via, goal), places=6)
        self.assertGreater(len(plan.expanded), 0)  # the option keyword reached the server
        # A blocked goal with a tolerance: the nearest free cell instead.
        near = self.client.plan("via", start, Cell(6, 3), goal_tolerance_cells=1.0)
        self.assertTrue(near.goal_substituted)
        self.assertEqual(near.goal, Cell(5, 3))  # ties: smaller row, then column
        # allow_partial: the walled-off second leg leaves the path to the via point.
        self.client.update_map("via", [SetRect(6, 0, 6, 0, LETHAL), SetRect(6, 7, 6, 7, LETHAL)])
        partial = self.client.plan("via", start, goal, via=[Cell(2, 2)], allow_partial=True)
        self.assertFalse(partial.found)
        self.assertEqual(partial.reached_goal_index, 0)
        self.assertEqual(partial.path[-1], Cell(2, 2))
        with self.assertRaisesRegex(ValueError, "not both"):
            self.client.plan("via", start, goal, options=pathd_client.plan_options(),
                             simplify=True)

    def test_plan_stream_reports_progress_then_the_plan(self):
        # 400 x 400 open cells, Dijkstra corner to corner: about 160,000
        # expansions, so several milliseconds of planning at any speed.
        side = 400
        self.client.create_map("stream", cells=bytes(side * side), width=side, height=side,
                               replace=True)
        self.addCleanup(self._delete_quietly, "stream")
        start, goal = Cell(0, 0), Cell(side - 1, side - 2)
        with self.client.plan_stream("stream", start, goal, planner="dijkstra") as stream:
            events = list(stream)
        self.assertIsInstance(events[-1], pathd_client.PlanResult)
        self.assertIs(events[-1], stream.result)
        progress = events[:-1]
        self.assertEqual(progress, stream.progress)
        self.assertGreater(len(progress), 0, "no progress event from a long plan")
        for p in progress:
            self.assertIsInstance(p, pathd_client.PlanProgress)
        self.assertEqual(sorted(p.expansions for p in progress), [p.expansions for p in progress])
        self.assertLessEqual(progress[-1].expansions, stream.result.expansions)
        # The same answer as Plan: on open cells the cheapest cost is the
        # octile distance.
        self.assertTrue(stream.result.found)
        dx, dy = goal.x - start.x, goal.y - start.y
        self.assertAlmostEqual(stream.result.cost, abs(dx - dy) + math.sqrt(2) * min(dx, dy),
                               places=6)
        self.assertEqual(stream.result.cost, self.client.plan("stream", start, goal,
                                                              planner="dijkstra").cost)
        # A failed plan raises as Plan does, outcome included.
        with self.assertRaises(pathd_client.NotFoundError) as missing:
            self.client.plan_stream("no_such_map", start, goal).wait()
        self.assertEqual(missing.exception.outcome, "MAP_NOT_FOUND")
        with self.assertRaises(pathd_client.InvalidArgumentError) as off:
            self.client.plan_stream("stream", start, Cell(side, 0)).wait()
        self.assertEqual(off.exception.outcome, "GOAL_OUTSIDE_MAP")

    def test_plan_batch_answers_every_item(self):
        self.make_map("batch")
        blocked = blocked_cells(ROWS)
        pairs = [(Cell(x, y), Cell(13 - x, 7 - y)) for x in range(0, 6) for y in (0, 3, 7)]
        requests = [pathd_client.plan_request("batch", a, b, planner="astar") for a, b in pairs]
        requests.append(pathd_client.plan_request("batch", Cell(0, 0), Cell(6, 3)))  # blocked
        answers = sorted(self.client.plan_batch(requests), key=lambda a: a.index)
        self.assertEqual([a.index for a in answers], list(range(len(requests))))
        for answer, (a, b) in zip(answers, pairs):
            self.assertIsNone(answer.error, answer)
            self.assertEqual(answer.request_id, str(answer.index))
            self.assert_valid_path(answer.result.path, a, b, 14, 8, blocked)
            self.assertAlmostEqual(answer.result.cost, shortest_cost(14, 8, blocked, a, b),
                                   places=6)
        bad = answers[-1]
        self.assertIsNone(bad.result)
        self.assertIsInstance(bad.error, pathd_client.InvalidArgumentError)
        self.assertEqual(bad.error.outcome, "GOAL_OCCUPIED")
        # Own request ids, from a generator.
        named = list(self.client.plan_batch(
            ((f"leg-{i}", pathd_client.plan_request("batch", (0, i), (13, i)))
             for i in range(3)), map_name="batch"))
        self.assertEqual(sorted(a.request_id for a in named), ["leg-0", "leg-1", "leg-2"])

    def test_cost_to_go_field(self):
        self.make_map("ctg")
        blocked = blocked_cells(ROWS)
        goal = Cell(12, 4)
        field = self.client.cost_to_go("ctg", goal)
        self.assertEqual((field.goal, field.window, field.map_version), (goal, (0, 0, 14, 8), 1))
        for y in range(8):
            for x in range(14):
                expected = (math.inf if Cell(x, y) in blocked
                            else shortest_cost(14, 8, blocked, Cell(x, y), goal))
                self.assertAlmostEqual(field.cost((x, y)), expected, places=4, msg=(x, y))
        window = self.client.cost_to_go("ctg", goal, window=(2, 1, 3, 2))
        self.assertTrue(window.cache_hit)
        self.assertEqual(len(window.costs), 6)
        self.assertEqual(window.cost((4, 2)), field.cost((4, 2)))
        with self.assertRaises(IndexError):
            window.cost((0, 0))
        four = self.client.cost_to_go("ctg", goal, connectivity=4)
        self.assertEqual(four.cost((1, 3)), 11 + 1 + 2 * 3)  # round the wall's end by rows

    def test_is_path_valid(self):
        self.make_map("valid")
        plan = self.client.plan("valid", (1, 3), (12, 4))
        check = self.client.is_path_valid("valid", plan.path)
        self.assertTrue(check.valid, check.reason)
        self.assertAlmostEqual(check.cost, plan.cost, places=6)
        self.assertEqual(check.map_version, 1)
        through_wall = [Cell(4, 3), Cell(5, 3), Cell(6, 3), Cell(7, 3), Cell(9, 3)]
        bad = self.client.is_path_valid("valid", through_wall)
        self.assertFalse(bad.valid)
        self.assertEqual(bad.invalid_indices, [2])
        self.assertEqual(bad.invalid_steps, [4])
        self.assertIn("pose 2 (6, 3) is on a blocked cell", bad.reason)
        # Option keywords: a robot radius of 1 cell makes cells beside the
        # wall invalid too.
        wide = self.client.is_path_valid("valid", through_wall, robot_radius_cells=1.0)
        self.assertEqual(wide.invalid_indices, [1, 2, 3])

    def test_cache_stats_sessions_and_health(self):
        self.make_map("stats")
        self.assertEqual(self.client.health(), "SERVING")
        before = self.client.get_cache_stats()
        self.assertIn("spm", before.caches)
        self.client.plan("stats", (1, 3), (12, 4), planner="spm")
        self.client.plan("stats", (2, 3), (12, 4), planner="spm")
        after = self.client.get_cache_stats().caches["spm"]
        self.assertEqual(after.misses, before.caches["spm"].misses + 1)
        self.assertEqual(after.hits, before.caches["spm"].hits + 1)
        self.assertGreater(after.bytes, 0)
        with self.client.navigate("stats", (1, 3), (12, 4)) as nav:
            self.assertGreaterEqual(self.client.get_cache_stats().sessions, 1)
            nav.move(nav.path[1])
            mine = [s for s in self.client.list_sessions("stats")
                    if s.session_id == nav.session_id]
            self.assertEqual(len(mine), 1)
            self.assertEqual(mine[0].map, "stats")
            self.assertEqual(mine[0].last.plan.path, nav.path)
            self.assertGreaterEqual(mine[0].age_s, mine[0].idle_s)
            self.assertIn(nav.session_id,
                          [s.session_id for s in self.client.list_sessions()])
        self.assertEqual(self.client.list_sessions("no_such_map"), [])

    def test_world_and_cell_coordinates(self):
        origin = (-3.0, 2.0, 0.0)
        info = self.client.create_map("world", ROWS, resolution=0.5, origin=origin,
                                      replace=True)
        self.addCleanup(self._delete_quietly, "world")
        self.assertEqual(info.origin, pathd_client.Origin(*origin))
        self.assertEqual(info.world_to_cell(-2.2, 3.7), Cell(1, 3))
        self.assertIsNone(info.world_to_cell(-3.1, 3.0))
        self.assertEqual(info.cell_to_world((12, 4)), (3.25, 4.25))
        plan = self.client.plan("world", pathd_client.WorldPoint(-2.2, 3.7),
                                pathd_client.CellPose(12.5, 4.5, 0.0))
        self.assertEqual((plan.start, plan.goal), (Cell(1, 3), Cell(12, 4)))
        self.assertEqual(len(plan.world_path), len(plan.path))
        for cell, world in zip(plan.path, plan.world_path):
            self.assertAlmostEqual(world[0], info.cell_to_world(cell)[0])
            self.assertAlmostEqual(world[1], info.cell_to_world(cell)[1])
            self.assertEqual(info.world_to_cell(*world), cell)
        self.assertAlmostEqual(plan.length_m, plan.length * 0.5)
        with self.assertRaisesRegex(TypeError, "two integers"):
            self.client.plan("world", (1.5, 3.0), (12, 4))

    def test_map_files_like_pathctl(self):
        # .map and ROS .yaml + .pgm from this machine, compared with the
        # same files read by the server from its --map_dir.
        for name in ("warehouse.yaml", "warehouse.pgm", "dstar_example.map"):
            shutil.copy(SOURCE_DIR / "maps" / name, self.map_dir.name)
        for name, file in (("imported_ros", "warehouse.yaml"),
                           ("imported_mai", "dstar_example.map")):
            with self.subTest(file=file):
                mine = self.client.create_map(name, from_file=SOURCE_DIR / "maps" / file,
                                              replace=True)
                self.addCleanup(self._delete_quietly, name)
                theirs = self.client.create_map(name + "_dir", map_dir_file=file, replace=True)
                self.addCleanup(self._delete_quietly, name + "_dir")
                self.assertEqual((mine.width, mine.height, mine.resolution, mine.origin),
                                 (theirs.width, theirs.height, theirs.resolution,
                                  theirs.origin))
                self.assertEqual(self.client.get_cells(name).cells,
                                 self.client.get_cells(name + "_dir").cells)
        ros = self.client.get_map("imported_ros")
        self.assertEqual((ros.width, ros.height, ros.resolution, ros.origin),
                         (60, 40, 0.1, pathd_client.Origin(-3.0, -2.0, 0.0)))
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            (tmp / "noimage.yaml").write_text("resolution: 0.1\norigin: [0, 0, 0]\n")
            with self.assertRaisesRegex(ValueError, "noimage.yaml: the YAML names no image"):
                self.client.create_map("x", from_file=tmp / "noimage.yaml")
            (tmp / "map.png").write_bytes(b"")
            with self.assertRaisesRegex(ValueError, "unknown map file type"):
                self.client.create_map("x", from_file=tmp / "map.png")
            (tmp / "lost.yaml").write_text("image: lost.pgm\nresolution: 0.1\n"
                                           "origin: [0, 0, 0]\n")
            with self.assertRaises(FileNotFoundError):
                self.client.create_map("x", from_file=tmp / "lost.yaml")
            # The server's parser judges the contents, naming the problem.
            (tmp / "bad.map").write_text("type octile\nheight 2\nwidth 3\nmap\n...\n")
            with self.assertRaisesRegex(pathd_client.InvalidArgumentError, "bad.map|row|height"):
                self.client.create_map("x", from_file=tmp / "bad.map")

    def test_example_robot_loop_reaches_its_goal(self):
        run = subprocess.run(
            [sys.executable, str(EXAMPLE), "--server", self.address, "--map", "example"],
            capture_output=True, text=True, timeout=120)
        self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
        self.assertIn("pushed (unasked): path of", run.stdout)
        self.assertIn("sensor sees an obstacle", run.stdout)
        self.assertIn("reached the goal", run.stdout)
        # It deletes its map afterwards.
        self.assertNotIn("example", [m.name for m in self.client.list_maps()])


def make_certs(directory: pathlib.Path) -> None:
    """A CA (ca.crt/.key), a server certificate it signed for the name
    pathd.test only (server.crt/.key) and a client certificate
    (client.crt/.key), made with the openssl tool as
    tests/testing/test_certs.h makes them: P-256 keys, generated in
    milliseconds."""
    new_key = ["-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes"]

    def run(*args):
        subprocess.run(["openssl", *args], cwd=directory, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    run("req", "-x509", *new_key, "-days", "2", "-subj", "/CN=ca", "-keyout", "ca.key",
        "-out", "ca.crt", "-addext", "basicConstraints=critical,CA:TRUE",
        "-addext", "keyUsage=critical,keyCertSign,cRLSign")
    for name, extra in (("server", ["-addext", "subjectAltName=DNS:pathd.test"]),
                        ("client", [])):
        run("req", "-new", *new_key, "-subj", f"/CN={name}", "-keyout", f"{name}.key",
            "-out", f"{name}.csr", *extra)
        run("x509", "-req", "-in", f"{name}.csr", "-CA", "ca.crt", "-CAkey", "ca.key",
            "-CAcreateserial", "-days", "2", "-copy_extensions", "copy",
            "-out", f"{name}.crt")


class TlsAndTokenTest(unittest.TestCase):
    """A pathd with mutual TLS and bearer tokens (docs/security.md)."""

    WRITE_TOKEN = "w" * 32
    READ_TOKEN = "r" * 32

    @classmethod
    def setUpClass(cls):
        pathd = os.environ.get("PATHD_BIN", str(SOURCE_DIR / "build" / "server" / "pathd"))
        cls.tmp = tempfile.TemporaryDirectory()
        d = pathlib.Path(cls.tmp.name)
        make_certs(d)
        tokens = d / "tokens.yaml"
        tokens.write_text("tokens:\n"
                          f"  - {{name: ops, role: write, token: {cls.WRITE_TOKEN}}}\n"
                          f"  - {{name: robot, role: read, token: {cls.READ_TOKEN}}}\n")
        tokens.chmod(0o600)
        (d / "read.token").write_text(cls.READ_TOKEN + "\n")
        cls.dir = d
        cls.daemon = PathdProcess(pathd, [f"--tls_cert={d / 'server.crt'}",
                                          f"--tls_key={d / 'server.key'}",
                                          f"--tls_client_ca={d / 'ca.crt'}",
                                          f"--auth_tokens={tokens}"])

    @classmethod
    def tearDownClass(cls):
        cls.daemon.stop()
        cls.tmp.cleanup()

    def client(self, **kwargs) -> PathdClient:
        d = self.dir
        tls = dict(tls_ca=d / "ca.crt", tls_cert=d / "client.crt",
                   tls_key=(d / "client.key").read_bytes(), tls_server_name="pathd.test")
        tls.update(kwargs)
        client = PathdClient(self.daemon.address, timeout=10.0,
                             **{k: v for k, v in tls.items() if v is not None})
        self.addCleanup(client.close)
        return client

    def test_token_reaches_unary_calls_and_streams(self):
        ops = self.client(token=self.WRITE_TOKEN)
        ops.create_map("secure", ROWS, replace=True)
        self.assertEqual([m.name for m in ops.list_maps()], ["secure"])
        self.assertTrue(ops.plan_stream("secure", (1, 3), (12, 4)).wait().found)
        self.assertIsNone(next(iter(ops.plan_batch(
            [pathd_client.plan_request("secure", (1, 3), (12, 4))]))).error)
        with ops.navigate("secure", (1, 3), (12, 4)) as nav:
            self.assertTrue(nav.opened.plan.found)
        with ops.watch_map("secure") as watch:
            self.assertEqual(next(iter(watch)).kind, "RESYNC")

        robot = self.client(token_file=self.dir / "read.token")
        self.assertTrue(robot.plan("secure", (1, 3), (12, 4)).found)
        with self.assertRaisesRegex(pathd_client.PermissionDeniedError, "role read"):
            robot.update_map("secure", [SetCell(0, 0, LETHAL)])

        anonymous = self.client()
        self.assertEqual(anonymous.health(), "SERVING")  # probes need no token
        with self.assertRaises(pathd_client.UnauthenticatedError):
            anonymous.list_maps()
        with self.assertRaises(pathd_client.UnauthenticatedError):
            self.client(token="x" * 32).list_maps()

    def test_tls_is_checked(self):
        # Plaintext to a TLS port, and a certificate for another name.
        with PathdClient(self.daemon.address, timeout=5.0, token=self.WRITE_TOKEN) as plain:
            with self.assertRaises(pathd_client.UnavailableError):
                plain.list_maps()
        with self.assertRaises(pathd_client.UnavailableError):
            self.client(tls_server_name=None, token=self.WRITE_TOKEN).list_maps()
        # Without a client certificate the mutual-TLS handshake fails.
        with self.assertRaises(pathd_client.UnavailableError):
            self.client(tls_cert=None, tls_key=None, token=self.WRITE_TOKEN).list_maps()

    def test_bad_credentials_are_refused_before_connecting(self):
        for kwargs, message in (
                (dict(tls_cert=b"x"), "tls_cert and tls_key together"),
                (dict(tls_server_name="a"), "need tls_ca"),
                (dict(token="a", token_file="b"), "not both"),
                (dict(token="two words"), "visible ASCII"),
                (dict(tls_ca="/no/such/ca.crt"), "tls_ca: cannot read /no/such/ca.crt"),
                (dict(token_file="/no/such/token"), "token_file: cannot read")):
            with self.subTest(kwargs=kwargs):
                with self.assertRaisesRegex(ValueError, message):
                    PathdClient("127.0.0.1:1", **kwargs)


class _Recorder(map_service_pb2_grpc.MapServiceServicer,
                planner_service_pb2_grpc.PlannerServiceServicer):
    """Answers every call with an empty message, noting what came with it."""

    def __init__(self):
        self.calls = []
        self.authorization = []
        self.lock = threading.Lock()

    def _note(self, method, context):
        metadata = dict(context.invocation_metadata())
        with self.lock:
            self.calls.append((method, metadata.get("x-pathd-map"), context.time_remaining()))
            self.authorization.append(metadata.get("authorization"))

    def CreateMap(self, request, context):
        self._note("CreateMap", context)
        return map_service_pb2.CreateMapResponse()

    def GetMap(self, request, context):
        self._note("GetMap", context)
        return map_service_pb2.GetMapResponse()

    def ListMaps(self, request, context):
        self._note("ListMaps", context)
        return map_service_pb2.ListMapsResponse()

    def UpdateMap(self, request, context):
        self._note("UpdateMap", context)
        return map_service_pb2.UpdateMapResponse()

    def DeleteMap(self, request, context):
        self._note("DeleteMap", context)
        return map_service_pb2.DeleteMapResponse()

    def DownloadMap(self, request, context):
        self._note("DownloadMap", context)
        yield map_service_pb2.DownloadMapResponse(info=common_pb2.MapInfo(name=request.name))

    def UploadMap(self, request_iterator, context):
        self._note("UploadMap", context)
        rows = sum(1 for m in request_iterator if m.HasField("band"))
        return map_service_pb2.CreateMapResponse(info=common_pb2.MapInfo(height=rows))

    def WatchMap(self, request, context):
        self._note("WatchMap", context)
        yield map_service_pb2.MapEvent(kind=map_service_pb2.MAP_EVENT_KIND_DELETED)

    def Plan(self, request, context):
        self._note("Plan", context)
        return planner_service_pb2.PlanResponse()

    def Navigate(self, request_iterator, context):
        self._note("Navigate", context)
        for request in request_iterator:
            yield planner_service_pb2.NavigateResponse(
                seq=request.seq, event=planner_service_pb2.NAVIGATE_EVENT_OPENED)

    def PlanStream(self, request, context):
        self._note("PlanStream", context)
        yield planner_service_pb2.PlanStreamEvent(
            progress=planner_service_pb2.PlanProgress(expansions=5))
        yield planner_service_pb2.PlanStreamEvent(
            result=planner_service_pb2.PlanResponse(found=True))

    def PlanBatch(self, request_iterator, context):
        self._note("PlanBatch", context)
        for item in request_iterator:
            yield planner_service_pb2.PlanBatchResponse(
                request_id=item.request_id, result=planner_service_pb2.PlanResponse())

    def CostToGo(self, request, context):
        self._note("CostToGo", context)
        return planner_service_pb2.CostToGoResponse()

    def IsPathValid(self, request, context):
        self._note("IsPathValid", context)
        return planner_service_pb2.IsPathValidResponse()

    def GetCacheStats(self, request, context):
        self._note("GetCacheStats", context)
        return planner_service_pb2.GetCacheStatsResponse()


class WireTest(unittest.TestCase):
    """What the client sends, seen by a fake server."""

    def setUp(self):
        self.recorder = _Recorder()
        self.server = grpc.server(futures.ThreadPoolExecutor(max_workers=4))
        map_service_pb2_grpc.add_MapServiceServicer_to_server(self.recorder, self.server)
        planner_service_pb2_grpc.add_PlannerServiceServicer_to_server(self.recorder, self.server)
        port = self.server.add_insecure_port("127.0.0.1:0")
        self.server.start()
        self.addCleanup(self.server.stop, None)
        self.port = port
        self.client = PathdClient(f"127.0.0.1:{port}", timeout=7.5)
        self.addCleanup(self.client.close)

    def test_every_call_names_its_map_and_unary_calls_have_a_deadline(self):
        c = self.client
        c.create_map("m1", ["..."])
        c.get_map("m2")
        c.get_cells("m3")
        c.update_map("m4", [SetCell(0, 0, 1)])
        c.delete_map("m5")
        c.plan("m6", (0, 0), (1, 0))
        c.plan("m7", (0, 0), (1, 0), timeout=2.5)
        c.list_maps()
        self.assertEqual([event.kind for event in c.watch_map("m8")], ["DELETED"])
        with c.navigate("m9", (0, 0), (1, 0)):
            pass
        # One band per row: 3 bands of 2 bytes.
        self.assertEqual(c.upload_map("m10", bytes(6), 2, 3, band_bytes=2).height, 3)
        calls = self.recorder.calls
        self.assertEqual([(m, h) for m, h, _ in calls], [
            ("CreateMap", "m1"), ("GetMap", "m2"),
            ("GetMap", "m3"), ("DownloadMap", "m3"),  # the size, then the stream
            ("UpdateMap", "m4"),
            ("DeleteMap", "m5"), ("Plan", "m6"), ("Plan", "m7"),
            ("ListMaps", None),  # no map to name
            ("WatchMap", "m8"), ("Navigate", "m9"), ("UploadMap", "m10")])
        # The server sees the deadline rounded (a few ms past the timeout):
        # upper bounds that tell 7.5 s from the 10 s default and from none.
        for method, _, remaining in calls[:7] + calls[8:9] + calls[11:12]:
            self.assertIsNotNone(remaining, method)
            self.assertTrue(0 < remaining < 8.0, f"{method}: {remaining}")
        self.assertTrue(0 < calls[7][2] < 2.6, calls[7])

    def test_streams_and_new_calls_have_deadlines_headers_and_the_token(self):
        c = PathdClient(f"127.0.0.1:{self.port}", timeout=7.5, token="t0ken-" * 4)
        self.addCleanup(c.close)
        stream = c.plan_stream("m1", (0, 0), (1, 0))
        self.assertTrue(stream.wait().found)
        self.assertEqual(stream.progress, [pathd_client.PlanProgress(5, None, 0.0)])
        answers = list(c.plan_batch([pathd_client.plan_request("m2", (0, 0), (1, 0))] * 3))
        self.assertEqual(sorted(a.index for a in answers), [0, 1, 2])
        c.cost_to_go("m3", (0, 0))
        c.is_path_valid("m4", [(0, 0), (1, 0)])
        c.get_cache_stats()
        with c.navigate("m5", (0, 0), (1, 0)):
            pass
        self.assertEqual([event.kind for event in c.watch_map("m6")], ["DELETED"])
        calls = self.recorder.calls
        self.assertEqual([(m, h) for m, h, _ in calls], [
            ("PlanStream", "m1"), ("PlanBatch", "m2"), ("CostToGo", "m3"),
            ("IsPathValid", "m4"), ("GetCacheStats", None), ("Navigate", "m5"),
            ("WatchMap", "m6")])
        for method, _, remaining in calls[:5]:
            self.assertIsNotNone(remaining, method)
            self.assertTrue(0 < remaining < 8.0, f"{method}: {remaining}")
        self.assertEqual(self.recorder.authorization, ["Bearer " + "t0ken-" * 4] * len(calls))

    def test_unknown_planner_is_refused_before_sending(self):
        with self.assertRaisesRegex(ValueError, "unknown planner 'warp'"):
            self.client.plan("m", (0, 0), (1, 0), planner="warp")
        self.assertEqual(self.recorder.calls, [])


if __name__ == "__main__":
    unittest.main(verbosity=2)
