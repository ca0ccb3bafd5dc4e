#!/usr/bin/env python3
"""The viewer page in a real browser: headless Chromium against a real pathd.

Chromium is driven over the DevTools protocol (python3-websocket): the test
clicks a start and a goal on the canvas like a person, then checks the drawn
pixels against the plan it asks the HTTP API for itself; changes a cell with
pathctl and checks the page shows it without a reload; opens a Navigate
session and checks its robot is drawn; and loads a 2048 x 2048 map, printing
how long the first draw and a redraw take (figures, not assertions).
Screenshots go to the artefact directory.

    tests/e2e/viewer_browser_test.py build/server/pathd build/client/pathctl/pathctl ARTEFACT_DIR

Exits 77 (skipped, said on stderr) when chromium or python3-websocket is
missing; scripts/setup.sh test installs both.
"""

import base64
import http.client
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "testing"))
from pathd_process import PathdProcess  # pylint: disable=wrong-import-position

SKIP = 77
PATHD, PATHCTL, ARTEFACTS = sys.argv[1], sys.argv[2], sys.argv[3]

ROWS = [
    "................................",
    "................................",
    "...........@@@@@@@@@@...........",
    "...........@........@...........",
    "...........@........@...........",
    "...........@........@...........",
    "...........@.................@..",
    "...........@@@@@@@@@@........@..",
    "..............................@.",
    "................................",
    "................................",
    "................................",
]
PATH_RGB = (224, 0, 122)   # viewer.js PATH_COLOUR
ROBOT_RGB = (31, 119, 180)  # viewer.js ROBOT_COLOURS[0]
CONTROL_RGB = (44, 160, 44)  # viewer.js ROBOT_COLOURS[1]
LETHAL_RGB = (25, 25, 25)   # viewer.js palette[254]
FREE_RGB = (255, 255, 255)


def skip(why):
    print(f"SKIPPED: {why}", file=sys.stderr)
    sys.exit(SKIP)


try:
    import websocket  # python3-websocket
except ImportError:
    skip("python3-websocket is not installed (scripts/setup.sh test installs it)")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None:
    skip("chromium is not installed (scripts/setup.sh test installs it)")


def close(rgb, want, tolerance=40):
    return all(abs(a - b) <= tolerance for a, b in zip(rgb, want))


class Pathd:
    def __init__(self, workdir):
        self.proc = PathdProcess(PATHD, ["--http_address=127.0.0.1:0", "--threads=2",
                                         "--log_level=warn"],
                                 log_path=os.path.join(workdir, "pathd.log"))
        self.grpc = self.proc.address
        self.http = self.proc.http_address

    def call(self, method, path, body=None):
        req = urllib.request.Request(f"http://{self.http}{path}", method=method,
                                     data=None if body is None else json.dumps(body).encode())
        with urllib.request.urlopen(req, timeout=60) as r:
            return json.loads(r.read())

    def stop(self):
        self.proc.stop()


class Browser:
    """One headless Chromium page, driven over the DevTools protocol."""

    def __init__(self, url, workdir):
        self.proc = subprocess.Popen(
            [CHROMIUM, "--headless=new", "--no-sandbox", "--disable-gpu",
             "--remote-debugging-port=0", f"--user-data-dir={workdir}/chromium",
             "--window-size=1200,800", "--no-first-run", "--no-default-browser-check",
             "--force-device-scale-factor=1", url],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        port = None
        deadline = time.time() + 60
        while port is None and time.time() < deadline:
            line = self.proc.stderr.readline().decode()
            if not line and self.proc.poll() is not None:
                raise RuntimeError("chromium exited before its DevTools port was known")
            m = re.search(r"DevTools listening on ws://[^:]+:(\d+)/", line)
            if m:
                port = int(m.group(1))
        threading.Thread(target=self.proc.stderr.read, daemon=True).start()
        page = None
        while page is None and time.time() < deadline:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as r:
                page = next((t for t in json.loads(r.read()) if t["type"] == "page"), None)
            time.sleep(0.1)
        self.ws = websocket.create_connection(page["webSocketDebuggerUrl"], timeout=60)
        self.next_id = 0

    def send(self, method, **params):
        self.next_id += 1
        self.ws.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            message = json.loads(self.ws.recv())
            if message.get("id") == self.next_id:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message["result"]

    def js(self, expression):
        result = self.send("Runtime.evaluate", expression=expression, awaitPromise=True,
                           returnByValue=True)
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def wait_for(self, expression, what, timeout=60):
        deadline = time.time() + timeout
        while time.time() < deadline:
            try:
                if self.js(expression):
                    return
            except RuntimeError:
                pass  # the page (or the viewer object) is not there yet
            time.sleep(0.05)
        status = self.js("document.getElementById('status')?.textContent")
        raise AssertionError(f"timed out waiting for {what}; status: {status}")

    def click_cell(self, x, y):
        at = self.js(f"pathdViewer.cellToClient({x}, {y})")
        for kind in ("mousePressed", "mouseReleased"):
            self.send("Input.dispatchMouseEvent", type=kind, x=at["x"], y=at["y"],
                      button="left", clickCount=1)

    def pixel(self, x, y):
        """The canvas colour at the centre of cell (x, y)."""
        return tuple(self.js(
            "(() => { const c = document.getElementById('canvas');"
            f" const p = pathdViewer.cellToClient({x}, {y});"
            " const r = c.getBoundingClientRect();"
            " const d = c.getContext('2d').getImageData(Math.floor(p.x - r.left),"
            " Math.floor(p.y - r.top), 1, 1).data; return [d[0], d[1], d[2]]; })()"))

    def screenshot(self, name):
        data = self.send("Page.captureScreenshot", format="png")["data"]
        path = os.path.join(ARTEFACTS, name)
        with open(path, "wb") as f:
            f.write(base64.b64decode(data))
        print(f"screenshot: {path}")

    def close(self):
        self.ws.close()
        self.proc.kill()
        self.proc.wait(timeout=30)


def state_is(s):
    return f"document.getElementById('status').dataset.state === '{s}'"


def main():
    os.makedirs(ARTEFACTS, exist_ok=True)
    workdir = tempfile.mkdtemp(prefix="pathd-viewer-")
    pathd = Pathd(workdir)
    browser = None
    try:
        text = "type octile\nheight %d\nwidth %d\nmap\n%s\n" % (len(ROWS), len(ROWS[0]), "\n".join(ROWS))
        pathd.call("PUT", "/v1/maps/room", {"movingaiText": text, "resolution": 0.25})
        browser = Browser(f"http://{pathd.http}/?map=room", workdir)
        browser.wait_for(state_is("ready") + " && pathdViewer.state.map === 'room'", "the map")
        browser.screenshot("viewer-1-map.png")
        assert close(browser.pixel(11, 4), LETHAL_RGB), browser.pixel(11, 4)
        assert close(browser.pixel(0, 0), FREE_RGB), browser.pixel(0, 0)

        # Click a start and a goal as a person would.
        start, goal = (2, 5), (16, 4)
        browser.click_cell(*start)
        browser.click_cell(*goal)
        browser.wait_for(state_is("planned"), "the plan")
        browser.screenshot("viewer-2-plan.png")
        # The independent reference: the same plan asked of the API directly.
        plan = pathd.call("POST", "/v1/maps/room:plan", {
            "start": {"cell": {"x": start[0], "y": start[1]}},
            "goal": {"cell": {"x": goal[0], "y": goal[1]}}})
        assert plan["found"], plan
        drawn = browser.js("pathdViewer.state.plan.path")
        assert drawn == plan["path"], (drawn, plan["path"])
        inner = plan["path"][2:-2]
        off = [c for c in inner if not close(browser.pixel(c["x"], c["y"]), PATH_RGB)]
        assert not off, f"path cells not drawn in the path colour: {off}"
        on_path = {(c["x"], c["y"]) for c in plan["path"]}
        far = [(x, y) for x in range(len(ROWS[0])) for y in range(len(ROWS))
               if ROWS[y][x] == "." and all(abs(x - px) > 1 or abs(y - py) > 1 for px, py in on_path)]
        assert far and all(close(browser.pixel(x, y), FREE_RGB) for x, y in far[:40]), \
            "cells away from the path are not free-coloured"

        # A map update made through pathctl appears without a reload, and the
        # page replans around it.
        version = browser.js("pathdViewer.state.version")
        mid = inner[len(inner) // 2]
        subprocess.run([PATHCTL, "--server", pathd.grpc, "maps", "set", "room",
                        str(mid["x"]), str(mid["y"]), "lethal"], check=True, capture_output=True)
        browser.wait_for(f"pathdViewer.state.version > {version}", "the update")
        browser.wait_for(state_is("planned") + " && pathdViewer.state.plan.mapVersion == "
                         f"pathdViewer.state.version", "the replan")
        browser.screenshot("viewer-3-update.png")
        assert close(browser.pixel(mid["x"], mid["y"]), LETHAL_RGB, 60), browser.pixel(mid["x"], mid["y"])
        replanned = browser.js("pathdViewer.state.plan.path")
        assert {"x": mid["x"], "y": mid["y"]} not in replanned

        # A Navigate session's robot is drawn where its path starts.
        host, port = pathd.http.rsplit(":", 1)
        conn = http.client.HTTPConnection(host, int(port), timeout=60)
        conn.request("POST", "/v1/maps/room:navigate", body=json.dumps(
            {"seq": 1, "open": {"start": {"cell": {"x": 28, "y": 10}},
                                "goal": {"cell": {"x": 1, "y": 10}}}}))
        events = conn.getresponse()
        assert events.status == 200
        browser.wait_for("pathdViewer.state.sessions.length === 1", "the session's robot")
        time.sleep(0.2)  # one more frame
        browser.screenshot("viewer-4-robot.png")
        assert close(browser.pixel(28, 10), ROBOT_RGB), browser.pixel(28, 10)

        # A control session's robot is drawn at the pose of its last state
        # (its answers carry no path once the first has).
        control = http.client.HTTPConnection(host, int(port), timeout=60)
        control.request("POST", "/v1/maps/room:navigate", body=json.dumps(
            {"seq": 1, "open": {"start": {"cell": {"x": 3, "y": 1}},
                                "goal": {"cell": {"x": 3, "y": 10}},
                                "options": {"robotRadiusM": 0.1}, "control": {}}}))
        control_events = control.getresponse()
        assert control_events.status == 200
        session = None
        while session is None:
            line = control_events.readline().decode()
            assert line, "the control session's stream ended"
            if line.startswith("data:"):
                session = json.loads(line[5:])["sessionId"]
        for seq, x in ((2, 3.5), (3, 5.5)):
            pathd.call("POST", f"/v1/sessions/{session}:send",
                       {"seq": seq, "state": {"pose": {"cellPose": {"x": x, "y": 1.5}}}})
        browser.wait_for("pathdViewer.state.sessions.length === 2 && pathdViewer.state.sessions"
                         ".some((s) => s.last && s.last.seq === '3')", "the control robot")
        time.sleep(0.2)  # one more frame
        browser.screenshot("viewer-4b-control-robot.png")
        assert close(browser.pixel(5, 1), CONTROL_RGB), browser.pixel(5, 1)
        control.close()
        conn.close()

        # Responsiveness on a 2048 x 2048 map: figures only.
        size = 2048
        cells = bytearray(size * size)
        for y in range(0, size, 64):
            cells[y * size:(y + 1) * size] = b"\xfe" * size
            for x in range(32, size, 256):
                cells[y * size + x] = 0
        pathd.call("PUT", "/v1/maps/big", {"raw": {"width": size, "height": size,
                                                   "cells": base64.b64encode(bytes(cells)).decode()}})
        t0 = time.time()
        browser.js("pathdViewer.selectMap('big')")
        browser.wait_for(state_is("ready") + " && pathdViewer.state.map === 'big'", "the big map", 120)
        loaded = time.time() - t0
        frame_ms = browser.js(
            "new Promise((done) => { const t = performance.now(); pathdViewer.state.view.scale *= 1.5;"
            " pathdViewer.redraw();"
            " requestAnimationFrame(() => requestAnimationFrame(() => done(performance.now() - t))); })")
        browser.screenshot("viewer-5-2048.png")
        print(f"2048x2048 map: loaded and drawn in {loaded:.2f} s; a zoomed redraw took {frame_ms:.1f} ms")
        print("viewer_browser_test: OK")
    finally:
        if browser is not None:
            browser.close()
        pathd.stop()
        shutil.rmtree(workdir, ignore_errors=True)


if __name__ == "__main__":
    main()
