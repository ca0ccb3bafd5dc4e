#!/usr/bin/env python3
"""The HTTP/JSON API (docs/http.md) against a real pathd.

Every route: its happy path, the gRPC error codes as HTTP statuses with a
google.rpc.Status body, bearer tokens, a deadline header, Server-Sent Event
streams that end cleanly (watch, planStream, navigate), a malformed and an
oversized body (after which the daemon still serves), the stream limit, and
the viewer's files. Only the standard library: urllib and http.client.

    tests/e2e/http_api_test.py build/server/pathd
"""

import base64
import http.client
import json
import os
import sys
import tempfile
import time
import unittest
import urllib.error
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "testing"))
from pathd_process import PathdProcess  # pylint: disable=wrong-import-position

PATHD = sys.argv[1] if len(sys.argv) > 1 else "build/server/pathd"
READ_TOKEN = "read-token-0123456789abcdef"
WRITE_TOKEN = "write-token-0123456789abcdef"
MAX_BODY = 2_000_000

# 16 x 10, a wall at x = 7 with a gap at y = 8.
ROWS = [
    "................",
    "................",
    ".......@........",
    ".......@........",
    ".......@........",
    ".......@........",
    ".......@........",
    ".......@........",
    "................",
    ".......@........",
]
MOVINGAI = "type octile\nheight %d\nwidth %d\nmap\n%s\n" % (len(ROWS), len(ROWS[0]), "\n".join(ROWS))


class Daemon:
    """pathd with tokens, a small body limit and the HTTP API on a free port."""

    def __init__(self, *flags):
        self.dir = tempfile.TemporaryDirectory()
        tokens = os.path.join(self.dir.name, "tokens.yaml")
        with open(tokens, "w") as f:
            f.write("tokens:\n"
                    f"  - {{name: reader, role: read, token: {READ_TOKEN}}}\n"
                    f"  - {{name: writer, role: write, token: {WRITE_TOKEN}}}\n")
        os.chmod(tokens, 0o600)
        self.proc = PathdProcess(
            PATHD, ["--http_address=127.0.0.1:0", "--auth_tokens=" + tokens,
                    f"--max_message_bytes={MAX_BODY}", "--threads=2", "--log_level=warn", *flags],
            log_path=os.path.join(self.dir.name, "pathd.log"))
        self.http = self.proc.http_address

    def stop(self):
        code = self.proc.stop()
        self.dir.cleanup()
        return code


def request(daemon, method, path, body=None, token=WRITE_TOKEN, headers=None, raw=None):
    """(HTTP status, parsed JSON or text body, headers)."""
    data = raw if raw is not None else (None if body is None else json.dumps(body).encode())
    req = urllib.request.Request(f"http://{daemon.http}{path}", data=data, method=method)
    if token:
        req.add_header("Authorization", f"Bearer {token}")
    for k, v in (headers or {}).items():
        req.add_header(k, v)
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            status, text, hdrs = r.status, r.read().decode(), r.headers
    except urllib.error.HTTPError as e:
        status, text, hdrs = e.code, e.read().decode(), e.headers
    ctype = hdrs.get("Content-Type", "")
    return status, (json.loads(text) if "json" in ctype and text else text), hdrs


class EventStream:
    """A Server-Sent Events reader over http.client."""

    def __init__(self, daemon, method, path, body=None, token=WRITE_TOKEN):
        host, port = daemon.http.rsplit(":", 1)
        self.conn = http.client.HTTPConnection(host, int(port), timeout=30)
        headers = {"Accept": "text/event-stream"}
        if token:
            headers["Authorization"] = f"Bearer {token}"
        self.conn.request(method, path, body=None if body is None else json.dumps(body),
                          headers=headers)
        self.response = self.conn.getresponse()
        self.status = self.response.status

    def next(self):
        """The next event as (name, data dict, id); None at the end of the body."""
        name, data, ident = "message", [], None
        while True:
            line = self.response.readline()
            if not line:
                return None
            line = line.decode().rstrip("\n")
            if line == "":
                if data:
                    return name, json.loads("\n".join(data)), ident
                continue
            if line.startswith(":"):
                continue
            field, _, value = line.partition(": ")
            if field == "event":
                name = value
            elif field == "data":
                data.append(value)
            elif field == "id":
                ident = value

    def close(self):
        self.conn.close()


class HttpApiTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.d = Daemon("--http_max_streams=3")
        status, body, _ = request(cls.d, "PUT", "/v1/maps/room",
                                  {"movingaiText": MOVINGAI, "resolution": 0.5})
        assert status == 200, body

    @classmethod
    def tearDownClass(cls):
        assert cls.d.stop() == 0

    def assertStatus(self, result, http_status, code=None):
        status, body, _ = result
        self.assertEqual(status, http_status, body)
        if code is not None:
            self.assertEqual(body["code"], code, body)
            self.assertIsInstance(body["message"], str)
            self.assertEqual(body["details"], [])
        return body

    def plan_body(self, **extra):
        return {"start": {"cell": {"x": 1, "y": 1}}, "goal": {"cell": {"x": 14, "y": 1}}, **extra}

    # --- happy paths of every unary route ---------------------------------

    def test_maps(self):
        body = self.assertStatus(request(self.d, "GET", "/v1/maps", token=READ_TOKEN), 200)
        self.assertIn("room", [m["name"] for m in body["maps"]])
        body = self.assertStatus(request(self.d, "GET", "/v1/maps/room?include_cells=true",
                                         token=READ_TOKEN), 200)
        self.assertEqual(body["info"]["width"], 16)
        self.assertEqual(len(base64.b64decode(body["cells"])), 160)
        # Create, update, delete a second map; POST /v1/maps takes the name in the body.
        self.assertStatus(request(self.d, "POST", "/v1/maps",
                                  {"name": "scratch", "movingaiText": MOVINGAI}), 200)
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/scratch:update",
                                         {"changes": [{"cell": {"x": 0, "y": 0}, "cost": 254}]}), 200)
        self.assertEqual(body["version"], "2")
        body = self.assertStatus(request(self.d, "DELETE", "/v1/maps/scratch"), 200)
        self.assertEqual(body["lastVersion"], "2")
        self.assertStatus(request(self.d, "GET", "/v1/maps/scratch", token=READ_TOKEN), 404, 5)

    def test_plan_json_and_geojson(self):
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:plan",
                                         self.plan_body(planner="PLANNER_ASTAR"), token=READ_TOKEN), 200)
        self.assertTrue(body["found"])
        self.assertEqual(body["path"][0], {"x": 1, "y": 1})
        self.assertEqual(body["path"][-1], {"x": 14, "y": 1})
        # The wall is at x = 7 for y in 2..7 and 9: the path must go round it.
        self.assertTrue(all(not (c["x"] == 7 and c["y"] in (2, 3, 4, 5, 6, 7, 9)) for c in body["path"]))
        self.assertAlmostEqual(body["lengthM"], body["length"] * 0.5, places=6)
        # The same JSON shape as the gRPC answer: proto field names in lowerCamelCase,
        # every field present.
        self.assertIn("expansions", body)
        self.assertIn("worldPath", body)
        status, geo, headers = request(self.d, "POST", "/v1/maps/room:plan?format=geojson",
                                       self.plan_body(), token=READ_TOKEN)
        self.assertEqual(status, 200)
        self.assertIn("geo+json", headers["Content-Type"])
        feature = geo["features"][0]
        self.assertEqual(feature["geometry"]["type"], "LineString")
        coords = feature["geometry"]["coordinates"]
        self.assertEqual(len(coords), len(body["worldPath"]))
        self.assertAlmostEqual(coords[0][0], body["worldPath"][0]["x"], places=5)
        self.assertEqual(feature["properties"]["map"], "room")
        status, pretty, _ = request(self.d, "POST", "/v1/maps/room:plan?pretty=true",
                                    self.plan_body(), token=READ_TOKEN)
        self.assertEqual(pretty["path"], body["path"])

    def test_planner_queries(self):
        goal = {"cell": {"x": 14, "y": 1}}
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:costToGo",
                                         {"goal": goal}, token=READ_TOKEN), 200)
        self.assertEqual(len(body["cost"]), 160)
        self.assertEqual(body["cost"][14 + 16 * 1], 0)
        path = [{"cell": {"x": x, "y": 0}} for x in range(0, 10)]
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:isPathValid",
                                         {"path": path}, token=READ_TOKEN), 200)
        self.assertTrue(body["valid"], body)
        body = self.assertStatus(request(
            self.d, "POST", "/v1/maps/room:table",
            {"sources": [{"cell": {"x": 0, "y": 0}}], "destinations": [goal, {"cell": {"x": 0, "y": 9}}]},
            token=READ_TOKEN), 200)
        self.assertEqual(len(body["entries"]), 2)
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:nearest",
                                         {"point": {"cell": {"x": 7, "y": 4}}}, token=READ_TOKEN), 200)
        self.assertTrue(body["found"])
        body = self.assertStatus(request(
            self.d, "POST", "/v1/maps/room:trip",
            {"waypoints": [{"cell": {"x": 0, "y": 0}}, goal, {"cell": {"x": 15, "y": 9}}]},
            token=READ_TOKEN), 200)
        self.assertEqual(sorted(body["order"]), [0, 1, 2])
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:isochrone",
                                         {"start": {"cell": {"x": 1, "y": 1}}, "budgetCells": 4},
                                         token=READ_TOKEN), 200)
        self.assertGreater(int(body["reachableCells"]), 0)
        status, geo, _ = request(self.d, "POST", "/v1/maps/room:isochrone?format=geojson",
                                 {"start": {"cell": {"x": 1, "y": 1}}, "budgetCells": 4},
                                 token=READ_TOKEN)
        self.assertEqual(geo["features"][0]["geometry"]["type"], "MultiPolygon")
        body = self.assertStatus(request(
            self.d, "POST", "/v1/maps/room:planFleet",
            {"robots": [{"start": {"cell": {"x": 0, "y": 0}}, "goal": {"cell": {"x": 15, "y": 0}}},
                        {"start": {"cell": {"x": 15, "y": 0}}, "goal": {"cell": {"x": 0, "y": 0}}}],
             "solver": "FLEET_SOLVER_CBS"}, token=READ_TOKEN), 200)
        self.assertTrue(body["found"], body)
        self.assertEqual(len(body["paths"]), 2)
        body = self.assertStatus(request(self.d, "GET", "/v1/cacheStats", token=READ_TOKEN), 200)
        self.assertIn("caches", body)
        body = self.assertStatus(request(self.d, "GET", "/v1/planners", token=None), 200)
        self.assertIn({"value": "PLANNER_JPS", "name": "jps"}, body["planners"])
        self.assertEqual(self.assertStatus(request(self.d, "GET", "/healthz", token=None), 200),
                         {"status": "SERVING"})

    def test_plan_batch(self):
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:planBatch", {"requests": [
            {"requestId": "a", "request": self.plan_body()},
            {"requestId": "b", "request": {"start": {"cell": {"x": 7, "y": 3}},
                                           "goal": {"cell": {"x": 1, "y": 1}}}},
        ]}, token=READ_TOKEN), 200)
        answers = {r["requestId"]: r for r in body["responses"]}
        self.assertTrue(answers["a"]["result"]["found"])
        self.assertIn("blocked", answers["b"]["error"]["message"])
        self.assertStatus(request(self.d, "POST", "/v1/maps/room:planBatch", {"items": []},
                                  token=READ_TOKEN), 400, 3)

    # --- errors ------------------------------------------------------------

    def test_errors(self):
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/nowhere:plan", self.plan_body(),
                                         token=READ_TOKEN), 404, 5)
        self.assertIn("nowhere", body["message"])
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:plan",
                                         {"start": {"cell": {"x": 7, "y": 3}}, "goal": {"cell": {"x": 1, "y": 1}}},
                                         token=READ_TOKEN), 400, 3)
        self.assertIn("blocked", body["message"])
        self.assertStatus(request(self.d, "PUT", "/v1/maps/room", {"movingaiText": MOVINGAI}), 409, 6)
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:plan", raw=b"{not json",
                                         token=READ_TOKEN), 400, 3)
        self.assertIn("not a JSON PlanRequest", body["message"])
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:plan", {"strat": {}},
                                         token=READ_TOKEN), 400, 3)
        self.assertIn("strat", body["message"])
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:plan",
                                         {"map": "other", **self.plan_body()}, token=READ_TOKEN), 400, 3)
        self.assertIn("differs from the URL", body["message"])
        self.assertStatus(request(self.d, "POST", "/v1/maps/room:plan?planner=astar", self.plan_body(),
                                  token=READ_TOKEN), 400, 3)
        self.assertStatus(request(self.d, "POST", "/v1/maps/room:plan?format=csv", self.plan_body(),
                                  token=READ_TOKEN), 400, 3)
        status, body, headers = request(self.d, "PATCH", "/v1/maps", token=READ_TOKEN)
        self.assertEqual(status, 405)
        self.assertEqual(headers["Allow"], "GET, POST")
        self.assertStatus(request(self.d, "GET", "/v1/nothing", token=READ_TOKEN), 404, 5)
        self.assertStatus(request(self.d, "POST", "/v1/maps/room:fly", {}, token=READ_TOKEN), 404, 5)
        # Oversized: refused before parsing, and the daemon keeps serving.
        big = b'{"name": "big", "movingaiText": "' + b"." * (MAX_BODY + 10) + b'"}'
        body = self.assertStatus(request(self.d, "POST", "/v1/maps", raw=big), 413, 8)
        self.assertIn("max_message_bytes", body["message"])
        self.assertStatus(request(self.d, "GET", "/v1/maps", token=READ_TOKEN), 200)

    def test_auth(self):
        body = self.assertStatus(request(self.d, "GET", "/v1/maps", token=None), 401, 16)
        self.assertIn("authorization", body["message"])
        self.assertStatus(request(self.d, "GET", "/v1/maps", token="wrong-token-0123456789"), 401, 16)
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:update",
                                         {"changes": [{"cell": {"x": 0, "y": 0}, "cost": 0}]},
                                         token=READ_TOKEN), 403, 7)
        self.assertIn("write", body["message"])

    def test_deadline(self):
        # A nanosecond is over before the plan can run.
        self.assertStatus(request(self.d, "POST", "/v1/maps/room:plan", self.plan_body(),
                                  token=READ_TOKEN, headers={"Grpc-Timeout": "1n"}), 504, 4)
        body = self.assertStatus(request(self.d, "POST", "/v1/maps/room:plan", self.plan_body(),
                                         token=READ_TOKEN, headers={"Grpc-Timeout": "soon"}), 400, 3)
        self.assertIn("Grpc-Timeout", body["message"])
        self.assertStatus(request(self.d, "POST", "/v1/maps/room:plan", self.plan_body(),
                                  token=READ_TOKEN, headers={"Grpc-Timeout": "10S"}), 200)

    # --- streams -------------------------------------------------------------

    def test_watch_follows_updates_and_ends_on_delete(self):
        self.assertStatus(request(self.d, "PUT", "/v1/maps/watched", {"movingaiText": MOVINGAI}), 200)
        stream = EventStream(self.d, "GET", "/v1/maps/watched:watch", token=READ_TOKEN)
        self.assertEqual(stream.status, 200)
        self.assertEqual(stream.response.getheader("Content-Type"), "text/event-stream")
        name, event, ident = stream.next()
        self.assertEqual(event["kind"], "MAP_EVENT_KIND_RESYNC")
        self.assertEqual(ident, "1")
        self.assertStatus(request(self.d, "POST", "/v1/maps/watched:update",
                                  {"changes": [{"cell": {"x": 3, "y": 4}, "cost": 254}]}), 200)
        name, event, ident = stream.next()
        self.assertEqual(event["kind"], "MAP_EVENT_KIND_UPDATED")
        self.assertEqual(event["changes"][0]["rect"], {"xMin": 3, "yMin": 4, "xMax": 3, "yMax": 4})
        self.assertEqual(ident, "2")
        self.assertStatus(request(self.d, "DELETE", "/v1/maps/watched"), 200)
        name, event, _ = stream.next()
        self.assertEqual(event["kind"], "MAP_EVENT_KIND_DELETED")
        name, event, _ = stream.next()
        self.assertEqual((name, event["code"]), ("end", 0))
        self.assertIsNone(stream.next())  # the chunked body ends: a clean end
        stream.close()
        # A stream refused before its first event is a plain HTTP error.
        stream = EventStream(self.d, "GET", "/v1/maps/absent:watch", token=READ_TOKEN)
        self.assertEqual(stream.status, 404)
        stream.close()

    def test_plan_stream(self):
        stream = EventStream(self.d, "POST", "/v1/maps/room:planStream",
                             {**self.plan_body(), "planner": "PLANNER_DIJKSTRA"}, token=READ_TOKEN)
        self.assertEqual(stream.status, 200)
        events = []
        while (e := stream.next()) is not None:
            events.append(e)
        stream.close()
        self.assertEqual(events[-1][0], "end")
        self.assertEqual(events[-1][1]["code"], 0)
        self.assertTrue(events[-2][1]["result"]["found"])

    def test_navigate_session(self):
        opened = EventStream(self.d, "POST", "/v1/maps/room:navigate",
                             {"seq": 1, "open": {"start": {"cell": {"x": 1, "y": 1}},
                                                 "goal": {"cell": {"x": 14, "y": 1}}}},
                             token=READ_TOKEN)
        self.assertEqual(opened.status, 200)
        _, first, _ = opened.next()
        self.assertEqual(first["event"], "NAVIGATE_EVENT_OPENED")
        session = first["sessionId"]
        listed = self.assertStatus(request(self.d, "GET", "/v1/maps/room/sessions", token=READ_TOKEN), 200)
        mine = [s for s in listed["sessions"] if s["sessionId"] == session]
        self.assertEqual(len(mine), 1)
        self.assertEqual(mine[0]["last"]["plan"]["path"][0], {"x": 1, "y": 1})
        # Only the opener's token may drive it.
        self.assertStatus(request(self.d, "POST", f"/v1/sessions/{session}:send",
                                  {"seq": 2, "pose": {"cell": {"x": 2, "y": 1}}}), 403, 7)
        self.assertStatus(request(self.d, "POST", f"/v1/sessions/{session}:send",
                                  {"seq": 2, "pose": {"cell": {"x": 2, "y": 1}}}, token=READ_TOKEN), 200)
        _, moved, _ = opened.next()
        self.assertEqual((moved["event"], moved["seq"]), ("NAVIGATE_EVENT_MOVED", "2"))
        self.assertEqual(moved["plan"]["path"][0], {"x": 2, "y": 1})
        listed = self.assertStatus(request(self.d, "GET", "/v1/sessions", token=READ_TOKEN), 200)
        mine = [s for s in listed["sessions"] if s["sessionId"] == session]
        self.assertEqual(mine[0]["last"]["plan"]["path"][0], {"x": 2, "y": 1})
        self.assertStatus(request(self.d, "DELETE", f"/v1/sessions/{session}", token=READ_TOKEN), 200)
        name, end, _ = opened.next()
        self.assertEqual((name, end["code"]), ("end", 0))
        self.assertIsNone(opened.next())
        opened.close()
        self.assertStatus(request(self.d, "POST", f"/v1/sessions/{session}:send",
                                  {"seq": 3, "pose": {"cell": {"x": 3, "y": 1}}}, token=READ_TOKEN), 404, 5)

    def test_navigate_session_control_state_through_send(self):
        # A control session (issue 20) over HTTP: its states go through
        # :send like any NavigateRequest and come back as CONTROL events.
        opened = EventStream(self.d, "POST", "/v1/maps/room:navigate",
                             {"seq": 1, "open": {"start": {"cell": {"x": 1, "y": 1}},
                                                 "goal": {"cell": {"x": 14, "y": 1}},
                                                 "options": {"robotRadiusM": 0.3},
                                                 "control": {"localPlanner": "LOCAL_PLANNER_ORCA",
                                                             "limits": {"maxV": 0.5}}}},
                             token=READ_TOKEN)
        self.assertEqual(opened.status, 200)
        _, first, _ = opened.next()
        self.assertEqual(first["event"], "NAVIGATE_EVENT_OPENED")
        session = first["sessionId"]
        self.assertStatus(request(self.d, "POST", f"/v1/sessions/{session}:send",
                                  {"seq": 2, "state": {"pose": {"worldPose": {"x": 1.5, "y": 1.5}},
                                                       "stamp": 7.5}},
                                  token=READ_TOKEN), 200)
        _, answer, _ = opened.next()
        self.assertEqual((answer["event"], answer["seq"]), ("NAVIGATE_EVENT_CONTROL", "2"))
        command = answer["command"]
        self.assertEqual(command["outcome"], "LOCAL_OUTCOME_OK")
        self.assertEqual(command["stamp"], 7.5)
        self.assertLessEqual(command.get("v", 0.0), 0.5)
        self.assertAlmostEqual(command["trajectory"][0]["x"], 1.5)
        self.assertIn("plan", answer)  # the first answer carries the global path
        # ListSessions shows the last command (the viewer draws the robot).
        listed = self.assertStatus(request(self.d, "GET", "/v1/maps/room/sessions",
                                           token=READ_TOKEN), 200)
        mine = [s for s in listed["sessions"] if s["sessionId"] == session]
        self.assertEqual(mine[0]["last"]["command"]["trajectory"][0]["x"], 1.5)
        # A bad state ends the session with the field named.
        self.assertStatus(request(self.d, "POST", f"/v1/sessions/{session}:send",
                                  {"seq": 3, "state": {"pose": {"worldPose": {"x": 1.5, "y": 1.5}},
                                                       "vy": 0.2}},
                                  token=READ_TOKEN), 200)
        name, end, _ = opened.next()
        self.assertEqual((name, end["code"]), ("end", 3))
        self.assertIn("state.vy", end["message"])
        opened.close()

    def test_stream_limit_and_vanished_client(self):
        streams = [EventStream(self.d, "GET", "/v1/maps/room:watch", token=READ_TOKEN) for _ in range(3)]
        for s in streams:
            self.assertEqual(s.status, 200)
            s.next()
        refused = request(self.d, "GET", "/v1/maps/room:watch", token=READ_TOKEN)
        body = self.assertStatus(refused, 429, 8)
        self.assertIn("http_max_streams", body["message"])
        # Clients that vanish free their slots: the next update's write fails
        # and the watch is cancelled.
        for s in streams:
            s.close()
        deadline = time.time() + 30
        while True:
            request(self.d, "POST", "/v1/maps/room:update",
                    {"changes": [{"cell": {"x": 0, "y": 9}, "cost": 0}]})
            s = EventStream(self.d, "GET", "/v1/maps/room:watch", token=READ_TOKEN)
            ok = s.status == 200
            s.close()
            if ok or time.time() > deadline:
                break
            time.sleep(0.2)
        self.assertTrue(ok, "closed streams never freed their slots")

    def test_http_clients_are_callers_by_address(self):
        # Without tokens, memory shares count an HTTP client by its address
        # (carried to the service as x-pathd-http-peer), not as the gateway.
        plain = PathdProcess(PATHD, ["--http_address=127.0.0.1:0", "--max_watchers=2",
                                     "--caller_memory_share=0.5", "--log_level=warn"])
        try:
            d = type("Plain", (), {"http": plain.http_address})()
            self.assertStatus(request(d, "PUT", "/v1/maps/m", {"movingaiText": MOVINGAI},
                                      token=None), 200)
            first = EventStream(d, "GET", "/v1/maps/m:watch", token=None)
            self.assertEqual(first.status, 200)
            first.next()
            body = self.assertStatus(request(d, "GET", "/v1/maps/m:watch", token=None), 429, 8)
            self.assertIn("this caller (http:127.0.0.1)", body["message"])
            first.close()
        finally:
            plain.stop()

    def test_viewer_files(self):
        status, page, headers = request(self.d, "GET", "/", token=None)
        self.assertEqual(status, 200)
        self.assertIn("text/html", headers["Content-Type"])
        self.assertIn('<script src="/viewer.js">', page)
        status, script, headers = request(self.d, "GET", "/viewer.js", token=None)
        self.assertIn("javascript", headers["Content-Type"])
        self.assertIn("EventSource", script)
        self.assertStatus(request(self.d, "GET", "/nothing.js", token=None), 404, 5)


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
