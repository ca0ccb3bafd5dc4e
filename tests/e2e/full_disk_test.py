#!/usr/bin/env python3
"""Full disk under pathd --data_dir: a version is shown only once durable.

The data dir lives on a small tmpfs which a filler file then fills. Single-cell
updates go in until one fails for lack of space. Then: the failed update
answered INTERNAL naming the disk error and is never visible (GetMap and a
WatchMap mirror stay at the last acknowledged version), later changes are
refused (UNAVAILABLE), and after space is freed and pathd restarted every
acknowledged update is there, the next update gets the version number the
failed one would have had (which nobody ever saw), and a mirror resuming
WatchMap from the version it holds ends up equal to the map: it never diverges.
Regression test for "a change is visible before it is durable, and a failed
write's version is reused".

Mounting a tmpfs needs root (CAP_SYS_ADMIN); otherwise the test is skipped
with exit code 77 and a message saying so.

Usage: full_disk_test.py PATHD PATHCTL
"""

import base64
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading

SKIP = 77
SIZE = 32


def pathctl(binary, address, *args):
    return subprocess.run([binary, "--server", address, *args],
                          capture_output=True, text=True, timeout=60)


class Daemon:
    def __init__(self, pathd, data_dir, log_path):
        self.log = open(log_path, "ab")
        self.proc = subprocess.Popen(
            [pathd, "--address=127.0.0.1:0", "--data_dir=" + data_dir,
             "--snapshot_log_bytes=1000000", "--snapshot_interval=0",
             "--threads=2", "--log_level=warn"],
            stdout=subprocess.PIPE, stderr=self.log)
        line = self.proc.stdout.readline().decode()
        if not line.startswith("pathd listening on "):
            self.proc.wait()
            raise RuntimeError("pathd did not start (exit %s); see %s" %
                               (self.proc.returncode, log_path))
        self.address = line.split()[-1]

    def stop(self):
        self.proc.send_signal(signal.SIGTERM)
        code = self.proc.wait(timeout=60)
        self.log.close()
        return code


class Mirror:
    """A WatchMap client applying every event to its own copy of the map."""

    def __init__(self):
        self.cells = None
        self.version = 0
        self.versions = []

    def apply(self, event):
        kind = event["kind"]
        version = int(event["version"])
        self.versions.append(version)
        if kind in ("MAP_EVENT_KIND_RESYNC", "MAP_EVENT_KIND_REPLACED"):
            self.cells = bytearray(base64.b64decode(event.get("cells", "")))
        elif kind == "MAP_EVENT_KIND_UPDATED":
            for change in event.get("changes", []):
                rect = change["rect"]
                x0, y0 = rect.get("xMin", 0), rect.get("yMin", 0)
                x1, y1 = rect.get("xMax", 0), rect.get("yMax", 0)
                costs = base64.b64decode(change.get("costs", ""))
                i = 0
                for y in range(y0, y1 + 1):
                    for x in range(x0, x1 + 1):
                        self.cells[y * SIZE + x] = costs[i]
                        i += 1
        else:
            raise AssertionError("unexpected event %s" % kind)
        self.version = version

    def follow(self, binary, address, count=None):
        """Starts `maps watch` from this mirror's version in a thread."""
        args = [binary, "--server", address, "--json", "maps", "watch", "m",
                "--from_version", str(self.version)]
        if count is not None:
            args += ["--count", str(count)]
        proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)
        def read():
            for line in proc.stdout:
                self.apply(json.loads(line))
        thread = threading.Thread(target=read)
        thread.start()
        return proc, thread


def get_map(binary, address):
    result = pathctl(binary, address, "--json", "maps", "get", "m", "--cells")
    if result.returncode != 0:
        raise AssertionError("maps get m: %s" % result.stderr)
    answer = json.loads(result.stdout)
    return int(answer["info"]["version"]), base64.b64decode(answer.get("cells", ""))


def cell_of(k):
    """Update k (1-based) sets this cell to this cost."""
    return (k * 7) % SIZE, (k * 3) % SIZE, 1 + k % 250


def fill(path):
    """Writes `path` until the file system is full."""
    chunk = b"\xa5" * 4096
    with open(path, "wb", buffering=0) as f:
        try:
            while True:
                f.write(chunk)
        except OSError:
            pass
        try:
            while True:
                f.write(b"\xa5")
        except OSError:
            pass


def run(pathd, binary, disk, work):
    data_dir = os.path.join(disk, "data")
    log_path = os.path.join(work, "pathd.log")
    blank = os.path.join(work, "blank.map")
    with open(blank, "w") as f:
        f.write("type octile\nheight %d\nwidth %d\nmap\n" % (SIZE, SIZE))
        f.write(("." * SIZE + "\n") * SIZE)
    daemon = Daemon(pathd, data_dir, log_path)
    r = pathctl(binary, daemon.address, "maps", "create", "m", "--from", blank)
    if r.returncode != 0:
        raise AssertionError("create: %s" % r.stderr)
    mirror = Mirror()
    watch, watch_thread = mirror.follow(binary, daemon.address)
    expected = bytearray(SIZE * SIZE)
    fill(os.path.join(disk, "filler"))

    acked = 1  # version
    failure = None
    for k in range(1, 5000):
        x, y, cost = cell_of(k)
        r = pathctl(binary, daemon.address, "maps", "set", "m", str(x), str(y), str(cost))
        if r.returncode != 0:
            failure = r.stderr.strip()
            break
        version = int(r.stdout.split("version")[1].split()[0])
        if version != acked + 1:
            raise AssertionError("update %d acknowledged as version %d after %d" %
                                 (k, version, acked))
        acked = version
        expected[y * SIZE + x] = cost
    if failure is None:
        raise AssertionError("5000 updates fit on the full disk")
    if "No space left on device" not in failure:
        raise AssertionError("the failed update said %r, not the disk error" % failure)
    failed_version = acked + 1
    version, cells = get_map(binary, daemon.address)
    if version != acked or cells != expected:
        raise AssertionError("after the failed update GetMap shows version %d; the last "
                             "acknowledged is %d" % (version, acked))
    r = pathctl(binary, daemon.address, "maps", "set", "m", "0", "0", "9")
    if r.returncode == 0 or "refused" not in r.stderr:
        raise AssertionError("a change after the failure was not refused: %r %r" %
                             (r.stdout, r.stderr))
    if get_map(binary, daemon.address)[0] != acked:
        raise AssertionError("a refused change became visible")
    daemon.stop()
    watch.wait(timeout=60)
    watch_thread.join()
    if failed_version in mirror.versions or mirror.version != acked:
        raise AssertionError("the mirror saw versions %s; the last acknowledged is %d" %
                             (mirror.versions[-5:], acked))
    if mirror.cells != expected:
        raise AssertionError("the mirror's cells differ from the acknowledged map")

    os.remove(os.path.join(disk, "filler"))
    daemon = Daemon(pathd, data_dir, log_path)
    version, cells = get_map(binary, daemon.address)
    if version != acked or cells != expected:
        raise AssertionError("after the restart the map is at version %d (acknowledged %d) "
                             "or its cells differ" % (version, acked))
    # Other content under the number the failed update would have had: fine,
    # as long as nobody was ever shown that number for the failed content.
    r = pathctl(binary, daemon.address, "maps", "set", "m", "1", "1", "200")
    if r.returncode != 0 or int(r.stdout.split("version")[1].split()[0]) != failed_version:
        raise AssertionError("update after the restart: %r %r" % (r.stdout, r.stderr))
    expected[1 * SIZE + 1] = 200
    resumed, resumed_thread = mirror.follow(binary, daemon.address, count=1)
    resumed.wait(timeout=60)
    resumed_thread.join()
    version, cells = get_map(binary, daemon.address)
    if mirror.version != version or mirror.cells != cells or cells != expected:
        raise AssertionError("the resumed mirror is at version %d and %s the map (version %d)"
                             % (mirror.version,
                                "equals" if mirror.cells == cells else "differs from",
                                version))
    if daemon.stop() != 0:
        raise AssertionError("pathd did not exit 0 on SIGTERM")
    with open(log_path, "rb") as f:
        refused = f.read().decode(errors="replace").count("refused from now on")
    print("full disk test: %d updates acknowledged before the disk filled; the failed "
          "update (would-be version %d) answered %r; never visible to GetMap or the "
          "mirror (%d events); journal failures logged: %d; after the restart version %d "
          "went to a new change and the resumed mirror equals the map" %
          (acked - 1, failed_version, failure, len(mirror.versions), refused,
           failed_version))


def main():
    pathd, binary = sys.argv[1], sys.argv[2]
    if os.geteuid() != 0:
        print("SKIPPED full_disk_test: mounting a small tmpfs needs root; run as root "
              "(e.g. in the CI container) to test a full --data_dir disk")
        sys.exit(SKIP)
    with tempfile.TemporaryDirectory(prefix="pathd_full_disk_") as work:
        disk = os.path.join(work, "disk")
        os.makedirs(disk)
        mount = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", disk],
                               capture_output=True, text=True)
        if mount.returncode != 0:
            print("SKIPPED full_disk_test: cannot mount a tmpfs (%s); needs root with "
                  "CAP_SYS_ADMIN" % mount.stderr.strip())
            sys.exit(SKIP)
        try:
            run(pathd, binary, disk, work)
        except Exception:
            log = os.path.join(work, "pathd.log")
            if os.path.exists(log):
                with open(log, "rb") as f:
                    sys.stderr.write("pathd log (tail):\n%s\n" %
                                     f.read()[-4000:].decode(errors="replace"))
            raise
        finally:
            subprocess.run(["umount", "-l", disk], capture_output=True)


if __name__ == "__main__":
    main()
