"""An independent referee for `pathctl simulate` runs.

Reads the trajectory CSV that simulate writes (one row per robot and control
period: the pose at the period's start and the command held over it),
re-integrates every command itself at a fine step, and checks what the
issue asks of the local planners through the real server:

- the log is consistent: integrating a row's command over one period from
  its pose gives the next row's pose;
- no two robots ever closer than the sum of their radii;
- no robot's disc over a blocked cell (or off the map).

Written apart from the simulator's own referee (client/pathctl/simulate.cc)
and from the server's local planners; shares only the CSV format.
"""

import csv
import math


def integrate(x, y, yaw, v, vy, w, dt):
    """Exact motion at a constant body-frame velocity for dt seconds."""
    if abs(w) < 1e-9:
        c, s = math.cos(yaw), math.sin(yaw)
        return x + (v * c - vy * s) * dt, y + (v * s + vy * c) * dt, yaw
    # Numerically, in many small straight pieces with the midpoint heading:
    # a different method from the simulator's closed form.
    steps = max(1, int(math.ceil(abs(w) * dt / 0.002)))
    h = dt / steps
    for _ in range(steps):
        mid = yaw + 0.5 * w * h
        c, s = math.cos(mid), math.sin(mid)
        # The chord of an arc is shorter than the arc by (1 - sinc); tiny at
        # 0.002 rad per piece.
        x += (v * c - vy * s) * h
        y += (v * s + vy * c) * h
        yaw += w * h
    return x, y, yaw


class Grid:
    """Blocked cells of a map: blocked(x, y) for cell indices; world
    coordinates through origin and resolution (no origin yaw)."""

    def __init__(self, width, height, blocked_cells, resolution, origin_x, origin_y):
        self.width, self.height = width, height
        self.blocked_cells = blocked_cells  # set of (x, y)
        self.resolution = resolution
        self.origin_x, self.origin_y = origin_x, origin_y

    @staticmethod
    def from_movingai(text, resolution, origin=(0.0, 0.0)):
        lines = text.splitlines()
        height = int(lines[1].split()[1])
        width = int(lines[2].split()[1])
        rows = lines[4:4 + height]
        blocked = set()
        for y, row in enumerate(rows):
            for x, ch in enumerate(row):
                if ch not in ".G":
                    blocked.add((x, y))
        return Grid(width, height, blocked, resolution, origin[0], origin[1])

    @staticmethod
    def from_pgm(pgm_bytes, resolution, origin, occupied_thresh=0.65, free_thresh=0.196):
        """A map_server trinary PGM (negate 0): rows stored bottom row first
        in pathd, so image row r is grid row height - 1 - r."""
        parts = pgm_bytes.split(b"\n", 3)
        width, height = map(int, parts[1].split())
        pixels = parts[3]
        blocked = set()
        for r in range(height):
            for x in range(width):
                p = pixels[r * width + x]
                occ = (255 - p) / 255.0
                if occ > free_thresh:  # occupied or unknown: not free
                    blocked.add((x, height - 1 - r))
        return Grid(width, height, blocked, resolution, origin[0], origin[1])

    def blocked(self, x, y):
        if x < 0 or y < 0 or x >= self.width or y >= self.height:
            return True
        return (x, y) in self.blocked_cells

    def _steps_to_blocked(self):
        """4-connected steps from each cell to the nearest blocked cell (or
        the map's outside), by breadth-first search; built once."""
        if getattr(self, "_steps", None) is None:
            from collections import deque
            inf = 1 << 30
            steps = [[inf] * self.width for _ in range(self.height)]
            queue = deque()
            for y in range(self.height):
                for x in range(self.width):
                    if self.blocked(x, y) or x in (0, self.width - 1) or y in (0, self.height - 1):
                        steps[y][x] = 0 if self.blocked(x, y) else 1
                        queue.append((x, y))
            while queue:
                x, y = queue.popleft()
                for nx, ny in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
                    if 0 <= nx < self.width and 0 <= ny < self.height and steps[ny][nx] > steps[y][x] + 1:
                        steps[ny][nx] = steps[y][x] + 1
                        queue.append((nx, ny))
            self._steps = steps
        return self._steps

    def disc_hits(self, wx, wy, radius):
        """Whether a disc (world metres) overlaps a blocked cell."""
        cx = (wx - self.origin_x) / self.resolution
        cy = (wy - self.origin_y) / self.resolution
        rc = radius / self.resolution
        ix, iy = int(math.floor(cx)), int(math.floor(cy))
        if 0 <= ix < self.width and 0 <= iy < self.height:
            # A blocked cell D 4-connected steps away is at least D / 2 - 1
            # cells from any point of this cell (Chebyshev >= D / 2).
            if self._steps_to_blocked()[iy][ix] / 2.0 - 1.0 > rc:
                return False
        for y in range(int(math.floor(cy - rc)), int(math.floor(cy + rc)) + 1):
            for x in range(int(math.floor(cx - rc)), int(math.floor(cx + rc)) + 1):
                if not self.blocked(x, y):
                    continue
                dx = max(x - cx, 0.0, cx - (x + 1))
                dy = max(y - cy, 0.0, cy - (y + 1))
                if dx * dx + dy * dy < rc * rc - 1e-9:
                    return True
        return False


def read_trajectory(path):
    """{robot: [(t, x, y, yaw, v, vy, w, outcome), ...]} in time order."""
    robots = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            robots.setdefault(row["robot"], []).append(
                (float(row["t"]), float(row["x"]), float(row["y"]), float(row["yaw"]),
                 float(row["v"]), float(row["vy"]), float(row["w"]), row["outcome"]))
    return robots


def check_run(trajectory_path, radii, grid, period, substeps=10, log_tolerance=2e-3):
    """Problems found (strings; empty when the run is clean) and the smallest
    gap between two robots' discs (metres). `radii`: {robot: metres}."""
    robots = read_trajectory(trajectory_path)
    problems = []
    names = sorted(robots)
    # The log's own consistency (CSV values are rounded to 1e-4).
    for name in names:
        rows = robots[name]
        for a, b in zip(rows, rows[1:]):
            x, y, _ = integrate(a[1], a[2], a[3], a[4], a[5], a[6], b[0] - a[0])
            if math.hypot(x - b[1], y - b[2]) > log_tolerance:
                problems.append(f"{name}: the command at t={a[0]:.2f} does not lead to the "
                                f"logged pose at t={b[0]:.2f} (off by "
                                f"{math.hypot(x - b[1], y - b[2]):.4f} m)")
                break
    # Fine re-integration from each row: poses at substeps per period. Pairs
    # farther apart at the period's start than their radii plus twice the
    # fastest robot's reach in one period cannot meet within it.
    vmax = max((math.hypot(r[4], r[5]) for name in names for r in robots[name]), default=0.0)
    reach = 2.0 * vmax * period + 1e-6
    times = sorted({r[0] for name in names for r in robots[name]})
    index = {name: {r[0]: r for r in robots[name]} for name in names}
    min_gap = math.inf
    reported = set()
    for t in times:
        states = {name: index[name][t] for name in names if t in index[name]}
        live = sorted(states)
        close = []
        for i, a in enumerate(live):
            ra = states[a]
            for b in live[i + 1:]:
                rb = states[b]
                gap = math.hypot(ra[1] - rb[1], ra[2] - rb[2]) - radii[a] - radii[b]
                min_gap = min(min_gap, gap)
                if gap < reach:
                    close.append((a, b))
        for k in range(1, substeps + 1):
            dt = period * k / substeps
            poses = {name: integrate(*row[1:7], dt) for name, row in states.items()}
            if grid is not None:
                for a, pa in poses.items():
                    if (a, "map") not in reported and grid.disc_hits(pa[0], pa[1], radii[a]):
                        reported.add((a, "map"))
                        problems.append(f"{a} overlaps a blocked cell at t={t + dt:.2f} "
                                        f"({pa[0]:.3f}, {pa[1]:.3f})")
            for a, b in close:
                pa, pb = poses[a], poses[b]
                gap = math.hypot(pa[0] - pb[0], pa[1] - pb[1]) - radii[a] - radii[b]
                min_gap = min(min_gap, gap)
                if gap < 0 and (a, b) not in reported:
                    reported.add((a, b))
                    problems.append(f"{a} and {b} overlap by {-gap:.3f} m at t={t + dt:.2f}")
    return problems, min_gap
