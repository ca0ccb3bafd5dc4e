#!/usr/bin/env python3
"""Crash test of pathd --data_dir: kill -9 during concurrent updates, restart,
and check every acknowledged update survived and nothing else is half there.

One client thread per map sends updates through the real `pathctl`, one at a
time: update k of a map fills a 4 x 4 rectangle with a cost derived from k
(every 10th update of map crash0 replaces the map with an empty one instead),
so the map after n updates is known exactly and has version n + 1. The daemon
is killed with SIGKILL at a random moment (fixed seed), each client's update
in flight then fails, and after the restart every map must hold exactly the
state after n updates with n = the acknowledged ones, or one more when an
update was in flight: it may be wholly applied, never partly.

A second phase aims the kills at checkpoints: while the four maps are
updated, map "churn" is created, replaced and deleted in a loop, so with the
4 KiB --snapshot_log_bytes a checkpoint (new segment, snapshots, CHECKPOINT,
removal of deleted maps' snapshots and old segments) runs every second or
so. Most restarts set PATHD_TEST_CHECKPOINT_EXIT=STEP:N, which makes pathd
exit (as a kill -9 would leave its files) right after step STEP of its N-th
checkpoint, cycling through every step; the others are kill -9s sent when a
checkpoint's temporary files appear. Every restart must succeed, every
acknowledged change be there, and an in-flight one be wholly there or absent.

Usage: crash_test.py PATHD PATHCTL [--kills N] [--checkpoint_kills N] [--seed S]
"""

import argparse
import base64
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "..", "testing"))
from pathd_process import ExitedBeforeListening, PathdProcess  # pylint: disable=wrong-import-position

SIZE = 32
MAPS = 4
RECT = 4


def op_is_replace(map_index, k):
    return map_index == 0 and k % 10 == 0


def op_rect(k):
    """The rectangle and cost update k (1-based) writes."""
    x0 = (k * 7) % (SIZE - RECT)
    y0 = (k * 13) % (SIZE - RECT)
    return x0, y0, x0 + RECT - 1, y0 + RECT - 1, 1 + (k * 37) % 252


def expected_cells(map_index, n):
    """Row-major cost bytes of map `map_index` after its first n updates."""
    cells = bytearray(SIZE * SIZE)
    for k in range(1, n + 1):
        if op_is_replace(map_index, k):
            cells = bytearray(SIZE * SIZE)
            continue
        x0, y0, x1, y1, cost = op_rect(k)
        for y in range(y0, y1 + 1):
            for x in range(x0, x1 + 1):
                cells[y * SIZE + x] = cost
    return bytes(cells)


# pathd's exit code for PATHD_TEST_CHECKPOINT_EXIT (server/storage/durable_store.h).
CHECKPOINT_EXIT = 86
CHECKPOINT_STEPS = 8


class DiedAtCheckpoint(Exception):
    """pathd recovered, then exited at its checkpoint hook before listening."""


class Daemon:
    """pathd on --data_dir, through the tests' launcher; its log appended to
    log_path across restarts. With `checkpoint_exit` ("STEP:N") pathd exits
    with CHECKPOINT_EXIT after step STEP of its N-th checkpoint."""

    def __init__(self, pathd, data_dir, log_path, checkpoint_exit=None):
        env = {"PATHD_TEST_CHECKPOINT_EXIT": checkpoint_exit} if checkpoint_exit else {}
        try:
            self.process = PathdProcess(
                pathd, ["--data_dir=" + data_dir, "--snapshot_log_bytes=4096",
                        "--snapshot_interval=0", "--threads=2", "--log_level=warn"],
                log_path=log_path, extra_env=env)
        except ExitedBeforeListening as e:
            if e.code == CHECKPOINT_EXIT:
                raise DiedAtCheckpoint() from None
            raise
        self.address = self.process.address

    def exited(self, timeout):
        """Waits up to `timeout` s for pathd to exit by itself; its code or None."""
        return self.process.wait(timeout)

    def kill(self):
        self.process.kill()

    def stop(self):
        return self.process.stop()


def pathctl(binary, address, *args):
    return subprocess.run([binary, "--server", address, *args],
                          capture_output=True, text=True)


class MapClient:
    """The updates of one map: applied so far and the one in flight."""

    def __init__(self, index):
        self.index = index
        self.name = "crash%d" % index
        self.applied = 0  # updates known to be in the map
        self.in_flight = None  # k of an update whose answer never came
        self.error = None  # raised again by the main thread

    def run(self, *args):
        try:
            self.send_updates(*args)
        except Exception as e:  # pylint: disable=broad-except
            self.error = e

    def send_updates(self, binary, address, blank_file, stop, acked):
        while not stop.is_set():
            k = self.applied + 1
            if op_is_replace(self.index, k):
                result = pathctl(binary, address, "maps", "create", self.name,
                                 "--from", blank_file, "--replace")
            else:
                x0, y0, x1, y1, cost = op_rect(k)
                result = pathctl(binary, address, "maps", "rect", self.name,
                                 str(x0), str(y0), str(x1), str(y1), str(cost))
            if result.returncode != 0:
                self.in_flight = k
                return
            if not op_is_replace(self.index, k):
                version = int(result.stdout.split("version")[1].split()[0])
                if version != k + 1:
                    raise AssertionError("%s: update %d acknowledged as version %d" %
                                         (self.name, k, version))
            self.applied = k
            acked[0] += 1


def check_map(binary, address, client, counts):
    result = pathctl(binary, address, "--json", "maps", "get", client.name, "--cells")
    if result.returncode != 0:
        raise AssertionError("%s missing after restart: %s" % (client.name, result.stderr))
    answer = json.loads(result.stdout)
    n = int(answer["info"]["version"]) - 1
    cells = base64.b64decode(answer.get("cells", ""))
    low = client.applied
    high = client.applied + (1 if client.in_flight is not None else 0)
    if not low <= n <= high:
        raise AssertionError("%s: recovered after %d updates; acknowledged %d, in flight %s" %
                             (client.name, n, low, client.in_flight))
    if cells != expected_cells(client.index, n):
        raise AssertionError("%s: cells after %d updates differ from the expected map "
                             "(an update half applied?)" % (client.name, n))
    if client.in_flight is not None:
        counts["applied" if n == high else "absent"] += 1
    client.applied = n
    client.in_flight = None
    counts["checked_maps"] += 1


CHURN_PATTERN = "churn"
# 64 x 64: each creation's record (~4.1 KB) fills a 4 KiB segment, so every
# create and replace of churn starts a checkpoint.
CHURN_SIZE = 64


class ChurnClient:
    """Maps churn0 and churn1 in turn: cycle c (ops 3c+1..3c+3) creates
    churn<c % 2>, replaces it with the pattern map and deletes it, one op at a
    time. Alternating names makes the next creation's checkpoint find a
    deleted map with a snapshot, whose file the checkpoint then removes."""

    def __init__(self):
        self.applied = 0
        self.in_flight = None
        self.error = None

    @staticmethod
    def name(k):
        return "%s%d" % (CHURN_PATTERN, ((k - 1) // 3) % 2)

    @staticmethod
    def state(n):
        """{name: (version, cells)} of the churn maps present after n ops."""
        if n % 3 == 0:
            return {}
        if n % 3 == 1:
            return {ChurnClient.name(n): (1, bytes(CHURN_SIZE * CHURN_SIZE))}
        return {ChurnClient.name(n): (2, churn_cells())}

    def run(self, *args):
        try:
            self.send_ops(*args)
        except Exception as e:  # pylint: disable=broad-except
            self.error = e

    def send_ops(self, binary, address, pattern_dir, stop, acked):
        blank_file = os.path.join(pattern_dir, "churn_blank.map")
        pattern_file = os.path.join(pattern_dir, "churn.map")
        while not stop.is_set():
            k = self.applied + 1
            name = self.name(k)
            if k % 3 == 1:
                result = pathctl(binary, address, "maps", "create", name, "--from", blank_file)
            elif k % 3 == 2:
                result = pathctl(binary, address, "maps", "create", name,
                                 "--from", pattern_file, "--replace")
            else:
                result = pathctl(binary, address, "maps", "delete", name)
            if result.returncode != 0:
                if "UNAVAILABLE" not in result.stderr:
                    raise AssertionError("churn op %d failed: %s" % (k, result.stderr))
                self.in_flight = k
                return
            self.applied = k
            acked[1] += 1


def churn_cells():
    """The pattern map: a blocked diagonal band."""
    cells = bytearray(CHURN_SIZE * CHURN_SIZE)
    for y in range(CHURN_SIZE):
        for x in range(CHURN_SIZE):
            if abs(x - y) < 3:
                cells[y * CHURN_SIZE + x] = 254
    return bytes(cells)


def write_churn_maps(directory):
    """churn_blank.map (all free) and churn.map (the pattern)."""
    for name, band in (("churn_blank.map", -1), ("churn.map", 3)):
        with open(os.path.join(directory, name), "w") as f:
            f.write("type octile\nheight %d\nwidth %d\nmap\n" % (CHURN_SIZE, CHURN_SIZE))
            for y in range(CHURN_SIZE):
                f.write("".join("@" if abs(x - y) < band else "."
                                for x in range(CHURN_SIZE)) + "\n")


def check_churn(binary, address, client, counts):
    found = {}
    for index in range(2):
        name = "%s%d" % (CHURN_PATTERN, index)
        result = pathctl(binary, address, "--json", "maps", "get", name, "--cells")
        if result.returncode != 0:
            if "not found" not in result.stderr:
                raise AssertionError("maps get %s: %s" % (name, result.stderr))
            continue
        answer = json.loads(result.stdout)
        found[name] = (int(answer["info"]["version"]),
                       base64.b64decode(answer.get("cells", "")))
    candidates = [client.applied]
    if client.in_flight is not None:
        candidates.append(client.applied + 1)
    for n in candidates:
        if ChurnClient.state(n) == found:
            if client.in_flight is not None:
                counts["applied" if n != client.applied else "absent"] += 1
            client.applied = n
            client.in_flight = None
            counts["checked_maps"] += 2
            return
    raise AssertionError("churn maps after %d acknowledged ops (in flight: %s) recovered "
                         "as %s" % (client.applied, client.in_flight,
                                    {k: v[0] for k, v in found.items()}))


def checkpoint_phase(args, rng, data_dir, log_path, blank, clients, counts, acked):
    """Kills aimed at checkpoints while "churn" is created, replaced and deleted."""
    pattern_dir = os.path.dirname(blank)
    write_churn_maps(pattern_dir)
    churn = ChurnClient()
    figures = {"hook_exits": 0, "kill9": 0, "startup_exits": 0, "restarts": 0,
               "hook_missed": 0}
    step_hits = [0] * (CHECKPOINT_STEPS + 1)
    for i in range(args.checkpoint_kills):
        # Every restart is checked first, with no hook set.
        daemon = Daemon(args.pathd, data_dir, log_path)
        figures["restarts"] += 1
        for c in clients:
            check_map(args.pathctl, daemon.address, c, counts)
        check_churn(args.pathctl, daemon.address, churn, counts)
        # Three of four rounds then die at a checkpoint step (every step in
        # turn), the fourth by kill -9 when a checkpoint's temporary file shows.
        hook = None
        if i % 4 != 3:
            daemon.kill()
            step = 1 + (i * 3 // 4) % CHECKPOINT_STEPS
            hook = "%d:%d" % (step, rng.randint(1, 2))
            try:
                daemon = Daemon(args.pathd, data_dir, log_path, checkpoint_exit=hook)
            except DiedAtCheckpoint:
                # Recovered, then died in the start-up compaction.
                figures["startup_exits"] += 1
                step_hits[step] += 1
                continue
        stop = threading.Event()
        threads = [threading.Thread(target=c.run,
                                    args=(args.pathctl, daemon.address, blank, stop, acked))
                   for c in clients]
        threads.append(threading.Thread(
            target=churn.run, args=(args.pathctl, daemon.address, pattern_dir, stop, acked)))
        for t in threads:
            t.start()
        if hook is not None:
            code = daemon.exited(timeout=4.0)
            if code is None:
                daemon.kill()  # the step did not come in time: an ordinary kill
                figures["kill9"] += 1
                figures["hook_missed"] += 1
            elif code != CHECKPOINT_EXIT:
                raise AssertionError("pathd exited %d instead of at its checkpoint hook" % code)
            else:
                figures["hook_exits"] += 1
                step_hits[step] += 1
        else:
            deadline = time.monotonic() + 4.0
            while time.monotonic() < deadline and not any(
                    name.endswith(".tmp") for name in os.listdir(data_dir)):
                time.sleep(0.002)
            daemon.kill()
            figures["kill9"] += 1
        stop.set()
        for t in threads:
            t.join()
        for c in clients + [churn]:
            if c.error is not None:
                raise c.error
    daemon = Daemon(args.pathd, data_dir, log_path)
    for c in clients:
        check_map(args.pathctl, daemon.address, c, counts)
    check_churn(args.pathctl, daemon.address, churn, counts)
    figures["step_hits"] = step_hits[1:]
    figures["churn_ops"] = churn.applied
    return daemon, figures


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("pathd")
    parser.add_argument("pathctl")
    # The sanitizer run (Makefile ASAN_ENV) asks for fewer through the
    # environment: 20 checkpoint kills still die at every step at least once.
    parser.add_argument("--kills", type=int,
                        default=int(os.environ.get("PATHD_CRASH_KILLS", "12")))
    parser.add_argument("--checkpoint_kills", type=int,
                        default=int(os.environ.get("PATHD_CRASH_CHECKPOINT_KILLS", "40")))
    parser.add_argument("--seed", type=int, default=20240607)
    args = parser.parse_args()
    rng = random.Random(args.seed)
    started = time.monotonic()

    with tempfile.TemporaryDirectory(prefix="pathd_crash_") as work:
        data_dir = os.path.join(work, "data")
        log_path = os.path.join(work, "pathd.log")
        blank = os.path.join(work, "blank.map")
        with open(blank, "w") as f:
            f.write("type octile\nheight %d\nwidth %d\nmap\n" % (SIZE, SIZE))
            f.write(("." * SIZE + "\n") * SIZE)
        clients = [MapClient(i) for i in range(MAPS)]
        counts = {"applied": 0, "absent": 0, "checked_maps": 0}
        # Acknowledged updates of crash0..3, and churn ops.
        acked = [0, 0]
        try:
            daemon = Daemon(args.pathd, data_dir, log_path)
            for c in clients:
                r = pathctl(args.pathctl, daemon.address, "maps", "create", c.name,
                            "--from", blank)
                if r.returncode != 0:
                    raise AssertionError("create %s: %s" % (c.name, r.stderr))
            for _ in range(args.kills):
                stop = threading.Event()
                threads = [threading.Thread(target=c.run,
                                            args=(args.pathctl, daemon.address, blank,
                                                  stop, acked))
                           for c in clients]
                for t in threads:
                    t.start()
                time.sleep(rng.uniform(0.1, 1.0))
                daemon.kill()
                stop.set()
                for t in threads:
                    t.join()
                for c in clients:
                    if c.error is not None:
                        raise c.error
                daemon = Daemon(args.pathd, data_dir, log_path)
                for c in clients:
                    check_map(args.pathctl, daemon.address, c, counts)
            first_phase = time.monotonic() - started
            daemon.kill()
            # Two maps keep being updated beside churn (fewer pathctl calls
            # per round: the phase is about checkpoints, not throughput).
            daemon, figures = checkpoint_phase(args, rng, data_dir, log_path, blank,
                                               clients[:2], counts, acked)
            for c in clients[2:]:
                check_map(args.pathctl, daemon.address, c, counts)
            # A clean stop and start keeps everything too.
            if daemon.stop() != 0:
                raise AssertionError("pathd did not exit 0 on SIGTERM")
            daemon = Daemon(args.pathd, data_dir, log_path)
            for c in clients:
                check_map(args.pathctl, daemon.address, c, counts)
            daemon.stop()
        except Exception:
            with open(log_path, "rb") as f:
                tail = f.read()[-4000:].decode(errors="replace")
            sys.stderr.write("pathd log (tail):\n%s\n" % tail)
            raise
        with open(log_path, "rb") as f:
            log = f.read().decode(errors="replace")
        torn = log.count("cutting the log there")

    checkpoint_kills = figures["hook_exits"] + figures["startup_exits"] + figures["kill9"]
    print("crash test: %d random kills (%.1f s), then %d kills aimed at checkpoints while "
          "map churn was created, replaced and deleted (%d ops acknowledged): %d exits at a "
          "checkpoint step (%d of them in the start-up compaction; per step 1-%d: %s), "
          "%d kill -9 (%d of them after the hooked step did not come within 4 s); %d restarts, all "
          "recovered; %d acknowledged updates checked (%d map checks), in-flight changes "
          "found applied: %d, absent: %d; torn final records cut: %d; %.1f s" %
          (args.kills, first_phase, checkpoint_kills, figures["churn_ops"],
           figures["hook_exits"] + figures["startup_exits"], figures["startup_exits"],
           CHECKPOINT_STEPS, figures["step_hits"], figures["kill9"], figures["hook_missed"],
           figures["restarts"] + 1,
           acked[0], counts["checked_maps"], counts["applied"], counts["absent"], torn,
           time.monotonic() - started))
    if checkpoint_kills < args.checkpoint_kills:
        raise AssertionError("only %d kills at checkpoints, %d asked for" %
                             (checkpoint_kills, args.checkpoint_kills))


if __name__ == "__main__":
    main()
