#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""A Foxglove WebSocket client for the system test `system_foxglove`
(tests/system/foxglove.sh): connects to tools/foxglove_bridge.py with the
`foxglove.sdk.v1` subprotocol (websocket-client, the project's .venv), reads the
advertised channels, subscribes to every one (also those advertised later) and counts
what arrives until the server closes the connection (the team ended) or --timeout.

  foxglove_client.py URL --robots 1 2 3 [--timeout S] [--connect-timeout S]
                     [--flowing FILE] [--churn N] [--min-rate R] [--json OUT] [--dump DIR]

Checks (exit 1 when one fails, 0 when all pass):
  - the channels exist with these schema names: /map, /robots, /truth
    foxglove.SceneUpdate; /tf foxglove.FrameTransforms; /notices foxglove.Log;
    /bridge elaslam.BridgeStats; per robot /robot<r>/pose foxglove.PoseInFrame,
    /robot<r>/trail foxglove.PosesInFrame, /robot<r>/stats elaslam.RobotStats;
    /status/robot<r> and /status/main elaslam.NodeStatus;
  - poses per robot per second over the steady part of the run (from 2 s after the
    robot's first pose to 1 s before its last, whole seconds of receive time): every
    second has at least --min-rate (9) poses of every robot;
  - /robot<r>/stats carries a NEES (ground truth on the bus) and pose sigmas; /map
    messages arrive and name landmarks and the tracks' entities (tracks/robots, tracks/fused);
  - --churn N: meanwhile N other clients connect, subscribe to everything, read a
    little and drop their connection without a close frame, one after another.
--flowing FILE is written once every robot's 20th pose has arrived (the test then
sends malformed datagrams). Prints the figures; --json writes them; --dump DIR writes
the last /robot<first>/stats and /bridge messages (robot_stats.json, bridge.json).
"""
import argparse
import json
import socket
import struct
import sys
import threading
import time

try:
    import websocket  # websocket-client
except ImportError:
    print("foxglove_client: no websocket-client (tools/setup.sh makes .venv with it)", file=sys.stderr)
    sys.exit(77)

SUBPROTOCOL = "foxglove.sdk.v1"


def expected(robots):
    e = {"/map": "foxglove.SceneUpdate", "/robots": "foxglove.SceneUpdate", "/truth": "foxglove.SceneUpdate",
         "/tf": "foxglove.FrameTransforms", "/notices": "foxglove.Log", "/bridge": "elaslam.BridgeStats",
         "/status/main": "elaslam.NodeStatus"}
    for r in robots:
        e.update({f"/robot{r}/pose": "foxglove.PoseInFrame", f"/robot{r}/trail": "foxglove.PosesInFrame",
                  f"/robot{r}/stats": "elaslam.RobotStats", f"/status/robot{r}": "elaslam.NodeStatus"})
    return e


def connect(url, deadline):
    """A connected WebSocket, retried until deadline (the bridge starts with the team)."""
    last = None
    while time.monotonic() < deadline:
        try:
            return websocket.create_connection(url, subprotocols=[SUBPROTOCOL], timeout=5)
        except (OSError, websocket.WebSocketException) as e:
            last = e
            time.sleep(0.2)
    raise SystemExit(f"foxglove_client: FAIL cannot connect to {url}: {last}")


class Session:
    """One client: channels advertised, subscriptions, messages per channel."""

    def __init__(self, ws):
        self.ws = ws
        self.channels = {}      # id -> advertisement
        self.sub_of = {}        # subscription id -> channel id
        self.next_sub = 1
        self.times = {}         # topic -> receive times (monotonic)
        self.last = {}          # topic -> last payload
        self.nis = {}           # /robot<r>/stats topic -> [sum of nis, sum of nis_dof, messages with nis_dof > 0]
        self.protocol = ws.getsubprotocol() if hasattr(ws, "getsubprotocol") else None
        self.server_info = None

    def subscribe_new(self, chans):
        subs = []
        for c in chans:
            self.channels[c["id"]] = c
            self.sub_of[self.next_sub] = c["id"]
            subs.append({"id": self.next_sub, "channelId": c["id"]})
            self.next_sub += 1
        if subs:
            self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))

    def read_one(self):
        """Handle one frame; False when the server closed the connection."""
        try:
            op, data = self.ws.recv_data()
        except websocket.WebSocketTimeoutException:
            return True
        except (websocket.WebSocketConnectionClosedException, OSError):
            return False
        if op == websocket.ABNF.OPCODE_CLOSE:
            return False
        now = time.monotonic()
        if op == websocket.ABNF.OPCODE_TEXT:
            msg = json.loads(data)
            if msg.get("op") == "serverInfo":
                self.server_info = msg
            elif msg.get("op") == "advertise":
                self.subscribe_new(msg["channels"])
        elif op == websocket.ABNF.OPCODE_BINARY and data[:1] == b"\x01" and len(data) >= 13:
            sub, = struct.unpack_from("<I", data, 1)
            ch = self.channels.get(self.sub_of.get(sub))
            if ch is not None:
                self.times.setdefault(ch["topic"], []).append(now)
                self.last[ch["topic"]] = bytes(data[13:])
                if ch["topic"].endswith("/stats"):
                    st = json.loads(bytes(data[13:]))
                    acc = self.nis.setdefault(ch["topic"], [0.0, 0, 0])
                    if st.get("nis_dof", 0) > 0:
                        acc[0] += st["nis"]
                        acc[1] += st["nis_dof"]
                        acc[2] += 1
        return True


def churn(url, n, stop, result):
    """n clients, one after another: connect, subscribe to all, read 0.3 s, drop the TCP connection."""
    for k in range(n):
        if stop.is_set():
            break
        try:
            s = Session(connect(url, time.monotonic() + 5))
            s.ws.settimeout(0.1)
            end = time.monotonic() + 0.3
            while time.monotonic() < end and s.read_one():
                pass
            s.ws.sock.shutdown(socket.SHUT_RDWR)  # no close frame: as a crashed client
            s.ws.sock.close()
            result["churned"] += 1
            result["churn_messages"] += sum(len(v) for v in s.times.values())
        except (SystemExit, OSError, websocket.WebSocketException) as e:
            result["churn_errors"].append(str(e))
        time.sleep(0.4)


def per_second(times):
    """Counts per whole second of the steady part: 2 s after the first, 1 s before the last."""
    if len(times) < 2:
        return []
    start, end = times[0] + 2.0, times[-1] - 1.0
    n = int(end - start)
    counts = [0] * max(0, n)
    for t in times:
        k = int(t - start) if t >= start else -1
        if 0 <= k < n:
            counts[k] += 1
    return counts


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("url")
    ap.add_argument("--robots", type=int, nargs="+", required=True)
    ap.add_argument("--timeout", type=float, default=120)
    ap.add_argument("--connect-timeout", type=float, default=90)
    ap.add_argument("--flowing", help="file written once every robot's 20th pose arrived")
    ap.add_argument("--churn", type=int, default=0)
    ap.add_argument("--min-rate", type=float, default=9)
    ap.add_argument("--json")
    ap.add_argument("--dump", help="a directory for the last /robot<r>/stats and /bridge messages")
    args = ap.parse_args()

    s = Session(connect(args.url, time.monotonic() + args.connect_timeout))
    s.ws.settimeout(0.2)
    stop = threading.Event()
    churned = {"churned": 0, "churn_messages": 0, "churn_errors": []}
    churner = None
    flowing = False
    deadline = time.monotonic() + args.timeout
    closed = False
    while time.monotonic() < deadline:
        if not s.read_one():
            closed = True
            break
        if not flowing and all(len(s.times.get(f"/robot{r}/pose", [])) >= 20 for r in args.robots):
            flowing = True
            if args.flowing:
                open(args.flowing, "w").close()
            if args.churn:
                churner = threading.Thread(target=churn, args=(args.url, args.churn, stop, churned), daemon=True)
                churner.start()
    stop.set()
    if churner:
        churner.join(timeout=10)

    fails = []
    topics = {c["topic"]: c for c in s.channels.values()}
    for topic, schema in expected(args.robots).items():
        c = topics.get(topic)
        if c is None:
            fails.append(f"no channel {topic}")
        elif c.get("schemaName") != schema:
            fails.append(f"{topic} has schema {c.get('schemaName')}, expected {schema}")
    rates = {}
    for r in args.robots:
        t = s.times.get(f"/robot{r}/pose", [])
        counts = per_second(t)
        rates[r] = {"poses": len(t), "per_second": counts,
                    "mean_per_s": round(len([x for x in t if t[0] + 2 <= x < t[0] + 2 + len(counts)]) / len(counts), 2)
                    if counts else 0}
        if len(counts) < 3:
            fails.append(f"robot {r}: only {len(counts)} steady seconds of poses ({len(t)} poses)")
        elif min(counts) < args.min_rate:
            fails.append(f"robot {r}: a second with {min(counts)} poses (< {args.min_rate}): {counts}")
        stats = s.last.get(f"/robot{r}/stats")
        st = json.loads(stats) if stats else {}
        if st.get("nees") is None or st.get("sigma_x_m") is None:
            fails.append(f"robot {r}: /robot{r}/stats has no nees or sigma_x_m: {st}")
        # The robots' NIS from POSE: present in most frames, and near 1 per dof (a filter
        # with movers accepted before they are found runs above 1; 3 is far beyond).
        nis, dof, with_nis = s.nis.get(f"/robot{r}/stats", [0.0, 0, 0])
        rates[r]["nis_per_dof"] = round(nis / dof, 3) if dof else None
        if with_nis < len(t) // 2 or not dof or not 0.3 < nis / dof < 3.0:
            fails.append(f"robot {r}: NIS in {with_nis} of {len(t)} stats, nis/dof {rates[r]['nis_per_dof']}")
    bridge = json.loads(s.last["/bridge"]) if "/bridge" in s.last else {}
    if len(s.times.get("/map", [])) < 3 or b"landmarks/static" not in s.last.get("/map", b""):
        fails.append(f"/map: {len(s.times.get('/map', []))} messages, the last without landmarks/static")
    if b"tracks/robots" not in s.last.get("/map", b"") or b"tracks/fused" not in s.last.get("/map", b""):
        fails.append("/map: the last without the tracks' entities (tracks/robots, tracks/fused)")
    if not closed:
        fails.append(f"the server did not close the connection within {args.timeout} s (the team should have ended)")
    if args.churn and churned["churned"] < args.churn:
        fails.append(f"churn: {churned['churned']} of {args.churn} clients came and went: {churned['churn_errors'][:3]}")
    out = {"protocol": s.protocol, "channels": {t: c.get("schemaName") for t, c in sorted(topics.items())},
           "counts": {t: len(v) for t, v in sorted(s.times.items())}, "rates": rates, "bridge": bridge,
           "closed_by_server": closed, **churned, "failures": fails}
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)
    if args.dump:  # the last message of each JSON channel whose keys docs/data_dictionary.md lists
        for topic, name in ((f"/robot{args.robots[0]}/stats", "robot_stats.json"), ("/bridge", "bridge.json")):
            if topic in s.last:
                with open(f"{args.dump}/{name}", "wb") as f:
                    f.write(s.last[topic])
    print(f"foxglove_client: subprotocol {s.protocol}; {len(topics)} channels: "
          + ", ".join(f"{t} ({c})" for t, c in out["channels"].items()))
    print("foxglove_client: messages: " + ", ".join(f"{t} {n}" for t, n in out["counts"].items()))
    for r, v in rates.items():
        print(f"foxglove_client: robot {r}: {v['poses']} poses, {v['mean_per_s']} per second over "
              f"{len(v['per_second'])} steady seconds, per second {v['per_second']}")
    print(f"foxglove_client: bridge: {json.dumps({k: bridge.get(k) for k in ('datagrams', 'messages', 'malformed_datagrams', 'decode_errors', 'invalid_messages', 'handler_errors', 'clients_served')})}")
    if args.churn:
        print(f"foxglove_client: churn: {churned['churned']} clients connected and dropped their connection, "
              f"{churned['churn_messages']} messages among them")
    for f in fails:
        print(f"foxglove_client: FAIL {f}")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
