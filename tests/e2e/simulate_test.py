#!/usr/bin/env python3
"""`pathctl simulate` against a real pathd: control sessions, their local
planners and the robots' reciprocity, judged by an independent referee.

- The shipped scenarios (examples/simulate): two robots head-on in a
  corridor, eight swapping places across a circle, twenty in the bundled
  warehouse.
- Random scenarios (PATHD_SIM_CASES, default 50): 10-30 robots on random
  maps of boxes, each robot's start and goal in one free region
  (PATHD_SIM_OPTIONS: their local planner options, for measurements).

For every run tests/testing/sim_checker.py re-integrates the logged commands
and checks that no robot overlaps a blocked cell and that no two robots
come closer than the sum of their radii, and the simulator must have
reported no contact either. Every robot that does not arrive must be
reported with why (deadlock, unreachable, timed out); all arrive in the
corridor and the circle, at least 50% in the warehouse (measured 60-100%,
docs/performance.md) and 95% over the random scenarios (measured 99%).

    tests/e2e/simulate_test.py build/server/pathd build/client/pathctl
"""

import json
import math
import os
import random
import subprocess
import sys
import tempfile
import unittest
from collections import deque

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(HERE, "..", "testing"))
from pathd_process import PathdProcess  # pylint: disable=wrong-import-position
import sim_checker  # pylint: disable=wrong-import-position

PATHD = sys.argv[1] if len(sys.argv) > 1 else "build/server/pathd"
PATHCTL = sys.argv[2] if len(sys.argv) > 2 else "build/client/pathctl"
CASES = int(os.environ.get("PATHD_SIM_CASES", "50"))
# Local planner options for the random scenarios, as a scenario's flow
# mapping body ("detour_range: 0, safety_margin: 0.02"): for measuring what
# an option changes (docs/performance.md).
OPTIONS = os.environ.get("PATHD_SIM_OPTIONS", "")
ARTEFACTS = os.environ.get("PATHD_SIM_ARTEFACTS", "")
EXAMPLES = os.path.join(ROOT, "examples", "simulate")


class Daemon:
    def __init__(self):
        self.dir = tempfile.TemporaryDirectory()
        self.proc = PathdProcess(
            PATHD, ["--map_dir=" + os.path.join(ROOT, "maps"), "--log_level=warn"],
            log_path=os.path.join(self.dir.name, "pathd.log"))
        self.address = self.proc.address

    def stop(self):
        code = self.proc.stop()
        self.dir.cleanup()
        return code


def simulate(daemon, scenario, workdir, picture=None, extra=()):
    """Runs pathctl simulate; (exit code, summary dict, trajectory path, stderr)."""
    base = os.path.join(workdir, os.path.splitext(os.path.basename(scenario))[0])
    trajectory = base + ".csv"
    args = [PATHCTL, "--server", daemon.address, "--timeout", "60s", "--json", "simulate",
            scenario, "--trajectory", trajectory, "--log_json", base + ".json", *extra]
    if picture:
        args += ["-o", picture]
    r = subprocess.run(args, capture_output=True, text=True, timeout=900)
    summary = json.loads(r.stdout) if r.stdout.strip() else None
    return r.returncode, summary, trajectory, r.stderr


def scenario_radii(text):
    """{robot name: radius} from the summary-independent scenario text we
    wrote or shipped (defaults.radius, robots' radius)."""
    import yaml  # python3-yaml: Debian's, in setup.sh
    doc = yaml.safe_load(text)
    default = (doc.get("defaults") or {}).get("radius", 0.25)
    radii = {}
    for i, robot in enumerate(doc["robots"]):
        radii[robot.get("name", f"r{i}")] = robot.get("radius", default)
    return radii, doc


class SimulateTest(unittest.TestCase):
    daemon = None

    @classmethod
    def setUpClass(cls):
        cls.daemon = Daemon()
        cls.tmp = tempfile.TemporaryDirectory()

    @classmethod
    def tearDownClass(cls):
        code = cls.daemon.stop()
        cls.tmp.cleanup()
        assert code == 0, f"pathd exited {code}"

    def judge(self, scenario_path, grid, min_arrival=1.0, picture=None):
        """Runs a scenario and checks it. Never allowed: two robots closer
        than the sum of their radii (by the independent referee or by the
        simulator), a robot over an obstacle cell, a command beyond the
        robot's limits, a non-arrival without a reason, or a log that does
        not integrate to itself."""
        with open(scenario_path) as f:
            radii, doc = scenario_radii(f.read())
        code, summary, trajectory, stderr = simulate(self.daemon, scenario_path, self.tmp.name,
                                                     picture=picture)
        self.assertIsNotNone(summary, f"no summary; exit {code}; stderr: {stderr}")
        period = doc.get("control_period", 0.1)
        problems, min_gap = sim_checker.check_run(trajectory, radii, grid, period)
        robot_pairs = sorted({tuple(sorted(p.split(" overlap")[0].split(" and ")))
                              for p in problems if " and " in p and " overlap by " in p})
        other = [p for p in problems if not (" and " in p and " overlap by " in p)]
        self.assertEqual(other, [], f"{scenario_path}: the referee found: {other[:5]}")
        reported = sorted({tuple(sorted(c.split(": ", 1)[1].split(" collide")[0].split(" and ")))
                           for c in summary["contacts"] if " collide at " in c})
        self.assertEqual([c for c in summary["contacts"] if " collide at " not in c], [],
                         "a robot touched the map or a moving obstacle")
        self.assertEqual(robot_pairs, [], f"{scenario_path}: robots touched: {problems[:5]}")
        self.assertEqual(reported, [], summary["contacts"])
        self.assertEqual(summary["collisions"], 0, summary["contacts"])
        self.assertEqual(code == 0, summary["arrived"] == len(radii) and summary["collisions"] == 0,
                         (code, summary["arrived"], summary["collisions"]))
        ends = [r["end"] for r in summary["robots"]]
        for r in summary["robots"]:
            self.assertIn(r["end"], ("arrived", "deadlock", "unreachable", "timed out"))
            if r["end"] != "arrived":
                self.assertTrue(r["detail"], f"{r['name']} did not arrive without a reason")
        arrived = ends.count("arrived")
        self.assertGreaterEqual(arrived, math.ceil(min_arrival * len(ends) - 1e-9),
                                f"{scenario_path}: {arrived}/{len(ends)} arrived: "
                                f"{[(r['name'], r['end'], r['detail']) for r in summary['robots'] if r['end'] != 'arrived']}")
        # Commands inside each robot's limits (ORCA and DWA respect the
        # accelerations; the referee reports the first that does not).
        self.assertEqual(summary["limit_violations"], 0,
                         [(r["name"], r["limit_violation"]) for r in summary["robots"]
                          if r["limit_violation"]])
        print(f"{os.path.basename(scenario_path)}: {arrived}/{len(ends)} arrived, "
              f"{summary['collisions']} contacts, min gap {min_gap:.3f} m", file=sys.stderr)
        return summary, min_gap

    def test_corridor_head_on(self):
        with open(os.path.join(EXAMPLES, "corridor.map")) as f:
            grid = sim_checker.Grid.from_movingai(f.read(), 0.1)
        summary, gap = self.judge(os.path.join(EXAMPLES, "corridor2.yaml"), grid)
        self.assertEqual(summary["arrived"], 2)
        self.assertGreaterEqual(gap, 0.0)

    def test_circle_swap(self):
        with open(os.path.join(EXAMPLES, "room.map")) as f:
            grid = sim_checker.Grid.from_movingai(f.read(), 0.1)
        picture = os.path.join(ARTEFACTS, "circle8.png") if ARTEFACTS else None
        summary, _ = self.judge(os.path.join(EXAMPLES, "circle8.yaml"), grid, picture=picture)
        self.assertEqual(summary["arrived"], 8)

    def test_warehouse20(self):
        # The bundled depot: map_server trinary, 0.05 m, origin (-10, -7.5).
        with open(os.path.join(ROOT, "maps", "depot.pgm"), "rb") as f:
            grid = sim_checker.Grid.from_pgm(f.read(), 0.05, (-10.0, -7.5))
        picture = os.path.join(ARTEFACTS, "warehouse20.png") if ARTEFACTS else None
        # Measured: 12-20 of 20 (18-19 in most runs) arrive within the
        # scenario's 120 s, the rest jammed in the staging area or still on
        # their way; no contact in 40 runs (docs/performance.md). The floor
        # is 10.
        self.judge(os.path.join(EXAMPLES, "warehouse20.yaml"), grid, picture=picture,
                   min_arrival=0.5)

    def test_random_scenarios(self):
        rng = random.Random(20261202)
        total = arrived = 0
        stride = max(1, 50 // max(1, CASES))
        for case in range(50):
            # Every case is drawn, so that a strided run meets the same ones.
            scenario, grid, n = random_scenario(rng, case)
            if case % stride:
                continue
            path = os.path.join(self.tmp.name, f"random{case}.yaml")
            with open(path, "w") as f:
                f.write(scenario)
            with open(os.path.join(self.tmp.name, f"random{case}.map"), "w") as f:
                f.write(grid_text(grid))
            summary, _ = self.judge(path, grid, min_arrival=0.0)
            total += n
            arrived += summary["arrived"]
            for r in summary["robots"]:
                # Starts and goals share one region of the inflated map:
                # nothing may be unreachable.
                self.assertNotEqual(r["end"], "unreachable", (case, r))
        print(f"random scenarios: {arrived}/{total} robots arrived", file=sys.stderr)
        # The issue asks for 95%; measured 98.9-99.4% (docs/performance.md).
        self.assertGreaterEqual(arrived, 0.95 * total, f"{arrived}/{total} robots arrived")


def grid_text(grid):
    rows = []
    for y in range(grid.height):
        rows.append("".join("@" if (x, y) in grid.blocked_cells else "." for x in range(grid.width)))
    return "type octile\nheight %d\nwidth %d\nmap\n%s\n" % (grid.height, grid.width, "\n".join(rows))


def random_scenario(rng, case):
    """A map of 10-14 m square at 0.1 m with 4-10 boxes, and 10-30 robots
    whose starts and goals lie in the largest free region of the map
    inflated by the largest radius plus 0.15 m."""
    res = 0.1
    size = rng.randint(100, 140)
    blocked = set()
    for x in range(size):
        blocked.add((x, 0))
        blocked.add((x, size - 1))
        blocked.add((0, x))
        blocked.add((size - 1, x))
    for _ in range(rng.randint(4, 10)):
        w, h = rng.randint(5, 20), rng.randint(5, 20)
        x0, y0 = rng.randint(15, size - 15 - w), rng.randint(15, size - 15 - h)
        for y in range(y0, y0 + h):
            for x in range(x0, x0 + w):
                blocked.add((x, y))
    grid = sim_checker.Grid(size, size, blocked, res, 0.0, 0.0)
    n = rng.randint(10, 30)
    radius = round(rng.uniform(0.15, 0.25), 2)
    clear = int(math.ceil((radius + 0.15) / res))
    # Free cells of the inflated map, and its largest 4-connected region.
    free = set()
    for y in range(size):
        for x in range(size):
            if all((x + dx, y + dy) not in blocked
                   for dy in range(-clear, clear + 1) for dx in range(-clear, clear + 1)
                   if dx * dx + dy * dy <= clear * clear):
                free.add((x, y))
    best = []
    seen = set()
    for c in free:
        if c in seen:
            continue
        region, queue = [], deque([c])
        seen.add(c)
        while queue:
            x, y = queue.popleft()
            region.append((x, y))
            for d in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                nb = (x + d[0], y + d[1])
                if nb in free and nb not in seen:
                    seen.add(nb)
                    queue.append(nb)
        if len(region) > len(best):
            best = region
    best.sort()

    def spread(count):
        points = []
        while len(points) < count:
            x, y = rng.choice(best)
            p = ((x + 0.5) * res, (y + 0.5) * res)
            if all(math.hypot(p[0] - q[0], p[1] - q[1]) > 2 * radius + 0.3 for q in points):
                points.append(p)
        return points

    starts, goals = spread(n), spread(n)
    planner = "orca"
    lines = [f"# random case {case}", f"map: sim_random{case}", f"map_file: random{case}.map",
             "map_resolution: 0.1", "duration: 120",
             "defaults:", f"  radius: {radius}", f"  local_planner: {planner}", "  max_v: 0.5",
             "  max_w: 2.0"] + ([f"  options: {{{OPTIONS}}}"] if OPTIONS else []) + ["robots:"]
    for i, (s, g) in enumerate(zip(starts, goals)):
        yaw = rng.uniform(-math.pi, math.pi)
        lines.append(f"  - {{name: r{i}, start: [{s[0]:.2f}, {s[1]:.2f}, {yaw:.3f}], "
                     f"goal: [{g[0]:.2f}, {g[1]:.2f}]}}")
    return "\n".join(lines) + "\n", grid, n


if __name__ == "__main__":
    if not os.path.exists(PATHCTL):
        print(f"simulate_test: {PATHCTL} not built", file=sys.stderr)
        sys.exit(1)
    unittest.main(argv=[sys.argv[0]])
