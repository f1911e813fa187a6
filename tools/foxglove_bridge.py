#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Serve the live team to Foxglove (app.foxglove.dev, Foxglove Studio): subscribes to
the team's LCM channels and serves them over Foxglove's WebSocket protocol with
Foxglove's schemas (the PyPI `foxglove-sdk`). A plain listener: it never publishes
on LCM.

    tools/foxglove_bridge.py [--port 8765] [--bind 127.0.0.1] [--lcm-url URL]
                             [--channel-groups] [--robots 1,2,3] [--build-dir DIR]
                             [--ws-netns PATH] [--map-rate HZ] [--trail N]

Prints "foxglove_bridge: ws://HOST:PORT" once it listens (--port 0: any free port);
open that in Foxglove (docs/tools.md, "Foxglove"). Channels (topics):

  /map               foxglove.SceneUpdate     the global map (GLOBAL_MAP, CANDIDATES_<r>):
                                              landmarks as spheres coloured by status
                                              (static blue, moving red, candidate grey),
                                              3-sigma covariance ellipses, id labels;
                                              the tracks of moving landmarks (TRACKS_<r>,
                                              GLOBAL_TRACKS) as arrows of 1 s of motion
                                              coloured by model (static grey, bounded
                                              amber, constant velocity violet), the fused
                                              ones thicker
  /robots            foxglove.SceneUpdate     each robot's heading arrow, 3-sigma ellipse
  /tf                foxglove.FrameTransforms map -> robot<r> at each POSE_<r>
  /robot<r>/pose     foxglove.PoseInFrame     POSE_<r>, frame "map"
  /robot<r>/trail    foxglove.PosesInFrame    its last --trail poses
  /robot<r>/stats    elaslam.RobotStats (JSON) per frame: pose sigmas, covariance trace,
                                              the frame's NIS (POSE), NEES against
                                              GROUND_TRUTH, error, counts
  /truth             foxglove.SceneUpdate     GROUND_TRUTH: true landmarks and robots
  /notices           foxglove.Log             DYNAMIC_NOTICE: a landmark found moving
  /status/<node>     elaslam.NodeStatus (JSON) STATUS_ROBOT_<r>, STATUS_MAIN, STATUS_SIM
  /bridge            elaslam.BridgeStats (JSON) the bridge's own counters, once a second

Consistency per frame: the robot's NIS as POSE carries it (nis, nis_dof and nis_per_dof,
about 1 for a consistent filter; no ground truth needed), the consistency monitor's
verdict (`inconsistent`, from STATUS), and the pose NEES against ground truth when the
bus has it (a simulated run).

LCM is read by tools/lcm_udpm.py (not liblcm: one malformed datagram kills its
receive thread); malformed datagrams, undecodable and implausible messages are
counted and skipped (/bridge). The LCM URL is --lcm-url, else LCM_DEFAULT_URL;
--channel-groups listens on the ports of the groups it reads (tools/lcm_groups.sh).
--ws-netns PATH (root) serves WebSocket clients in another network namespace
(/proc/PID/ns/net) while LCM is read in this one, as viewer --http-netns.
Signed messages (a team key) are read without checking their signature.
Exit: 0 stopped by SIGINT/SIGTERM, 1 LCM or the server could not be opened, 2 bad input.
"""
# ---- start-up: standard library only, before any third-party import (tools/elaslam_tool.py)
import os
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path[:0] = [_here, os.path.join(_here, "..", "share", "elaslam", "tools")]
from elaslam_tool import doc_parser, need as _need, parse_args as _parse, run_in_venv  # noqa: E402

PROG = "foxglove_bridge"

if __name__ == "__main__":
    run_in_venv()
# ----------------------------------------------------------------------------------
import argparse  # noqa: E402
import collections  # noqa: E402
import ctypes  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import re  # noqa: E402
import signal  # noqa: E402
import threading  # noqa: E402
import time  # noqa: E402

from elaslam_tool import load_lcm_types  # noqa: E402
from lcm_udpm import UdpmReceiver, parse_udpm_url  # noqa: E402

MAX_ROBOTS = 16              # contract::kMaxRobots
MAX_LANDMARK_ID = 1 << 16    # ids beyond are refused (memory bound)
WORLD_BOUND_M = 1e5          # positions beyond are refused
MAX_TRACK_CHUNKS = 6         # contract::kMaxTrackChunks: chunks of one TRACKS_<r> or GLOBAL_TRACKS
SIGMA = 3.0                  # ellipses at 3 sigma, as the viewer draws them
FAULT_INCONSISTENT = 8       # node_status_t.FAULT_INCONSISTENT
# Channel groups the bridge reads (channels.hpp's channel_group; the ctest channel_tables
# checks them against its handlers' channels): 0 team-wide (STATUS_*, DYNAMIC_NOTICE),
# 1 the robots' outputs (TRACKS_<r>), 2 GLOBAL_MAP and GLOBAL_TRACKS, 3 observers
# (GROUND_TRUTH, CANDIDATES_<r>), 4 POSE_<r>.
GROUPS = (0, 1, 2, 3, 4)
ROBOT_COLOURS = [(0.12, 0.47, 0.71), (1.0, 0.50, 0.05), (0.17, 0.63, 0.17), (0.58, 0.40, 0.74),
                 (0.55, 0.34, 0.29), (0.89, 0.47, 0.76), (0.50, 0.50, 0.50), (0.74, 0.74, 0.13)]
STATUS_COLOURS = {"static": (0.16, 0.38, 0.85), "moving": (0.85, 0.15, 0.12), "candidate": (0.55, 0.55, 0.55)}
# Track arrows by the likeliest model (track_t: STATIC 0, BOUNDED 1, CONSTANT_VELOCITY 2), as the viewer colours them.
TRACK_COLOURS = {0: (0.42, 0.45, 0.50), 1: (0.72, 0.53, 0.04), 2: (0.49, 0.23, 0.93)}
TRACK_SECONDS = 1.0  # an arrow is this long in motion


def json_schema(name, props):
    """A foxglove Schema for a JSON channel whose fields Foxglove's Plot panel offers."""
    fg = sys.modules["foxglove"]
    body = {"title": name, "type": "object",
            "properties": {k: ({"type": t} if isinstance(t, str) else {"type": list(t)}) for k, t in props.items()}}
    return fg.Schema(name=name, encoding="jsonschema", data=json.dumps(body).encode())


NUM = ("number", "null")
ROBOT_STATS = {"robot": "integer", "frame": "integer", "x_m": "number", "y_m": "number", "theta_rad": "number",
               "sigma_x_m": "number", "sigma_y_m": "number", "sigma_theta_rad": "number", "pose_cov_trace": "number",
               "mean_diag_p": "number", "num_obs": "integer", "num_accepted": "integer", "num_rejected": "integer",
               "num_landmarks": "integer", "processing_us": "integer", "nis": NUM, "nis_dof": "integer",
               "nis_per_dof": NUM, "nees": NUM, "error_m": NUM,
               "inconsistent": "integer", "fault_flags": "integer", "latency_ms": NUM}


def enter_netns(path):
    """This process's threads from now on in the network namespace at `path` (root).
    Called while the process has one thread: new threads inherit the namespace."""
    if len(os.listdir("/proc/self/task")) != 1:
        raise OSError("more than one thread already runs: cannot move the process")
    libc = ctypes.CDLL(None, use_errno=True)
    fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
    try:
        if libc.setns(fd, 0x40000000) != 0:  # CLONE_NEWNET
            raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
    finally:
        os.close(fd)


def finite(*xs):
    return all(isinstance(x, (int, float)) and math.isfinite(x) for x in xs)


def clean(v):
    """JSON without NaN or infinities (not JSON): null instead."""
    return v if not isinstance(v, float) or math.isfinite(v) else None


def ellipse(cxx, cxy, cyy):
    """(diameter major, diameter minor, angle [rad]) of the SIGMA ellipse of a 2x2 covariance."""
    h = 0.5 * (cxx + cyy)
    d = math.sqrt(max(0.0, 0.25 * (cxx - cyy) ** 2 + cxy * cxy))
    angle = 0.5 * math.atan2(2 * cxy, cxx - cyy)
    return 2 * SIGMA * math.sqrt(max(0.0, h + d)), 2 * SIGMA * math.sqrt(max(0.0, h - d)), angle


def nees3(e, P):
    """e^T P^-1 e for a 3-vector and a 3x3 covariance; None when P is singular."""
    (a, b, c), (d, f, g), (h, i, j) = P
    det = a * (f * j - g * i) - b * (d * j - g * h) + c * (d * i - f * h)
    if not math.isfinite(det) or det <= 0:
        return None
    inv = [[(f * j - g * i), -(b * j - c * i), (b * g - c * f)],
           [-(d * j - g * h), (a * j - c * h), -(a * g - c * d)],
           [(d * i - f * h), -(a * i - b * h), (a * f - b * d)]]
    return sum(e[r] * inv[r][k] * e[k] for r in range(3) for k in range(3)) / det


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


class Scene:
    """Builders of Foxglove messages (foxglove.messages) from the team's state."""

    def __init__(self, fg):
        self.m = fg.messages

    def ts(self, utime_us):
        return self.m.Timestamp(int(utime_us // 1_000_000), int(utime_us % 1_000_000) * 1000)

    def yaw(self, theta):
        return self.m.Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2))

    def pose(self, x, y, theta, z=0.0):
        return self.m.Pose(position=self.m.Vector3(x=x, y=y, z=z), orientation=self.yaw(theta))

    def colour(self, rgb, a=1.0):
        return self.m.Color(r=rgb[0], g=rgb[1], b=rgb[2], a=a)

    def disc(self, x, y, cxx, cxy, cyy, rgb, alpha, z=0.0):
        """The SIGMA covariance ellipse as a flattened sphere."""
        major, minor, angle = ellipse(cxx, cxy, cyy)
        return self.m.SpherePrimitive(pose=self.pose(x, y, angle, z), size=self.m.Vector3(x=major, y=minor, z=0.01),
                                      color=self.colour(rgb, alpha))

    def dot(self, x, y, rgb, size=0.25, z=0.0):
        return self.m.SpherePrimitive(pose=self.pose(x, y, 0.0, z), size=self.m.Vector3(x=size, y=size, z=size),
                                      color=self.colour(rgb))

    def track_arrow(self, x, y, vx, vy, model, fused):
        """A track: an arrow from its position along TRACK_SECONDS of its velocity."""
        return self.m.ArrowPrimitive(pose=self.pose(x, y, math.atan2(vy, vx), 0.05),
                                     shaft_length=max(0.01, TRACK_SECONDS * math.hypot(vx, vy)),
                                     shaft_diameter=0.06 if fused else 0.03, head_length=0.15,
                                     head_diameter=0.16 if fused else 0.1, color=self.colour(TRACK_COLOURS[model]))

    def label(self, x, y, text, rgb=(0.1, 0.1, 0.1)):
        return self.m.TextPrimitive(pose=self.pose(x, y, 0.0, 0.3), billboard=True, font_size=12.0,
                                    scale_invariant=True, color=self.colour(rgb), text=text)

    def entity(self, stamp, eid, **prims):
        return self.m.SceneEntity(timestamp=stamp, frame_id="map", id=eid, **prims)


class Bridge:
    """The team's state from LCM, and what goes out on the Foxglove channels."""

    def __init__(self, fg, T, args):
        self.fg, self.T, self.args = fg, T, args
        self.s = Scene(fg)
        ch = fg.channels
        self.ch_map = ch.SceneUpdateChannel("/map")
        self.ch_robots = ch.SceneUpdateChannel("/robots")
        self.ch_tf = ch.FrameTransformsChannel("/tf")
        self.ch_truth = ch.SceneUpdateChannel("/truth")
        self.ch_notices = ch.LogChannel("/notices")
        self.ch_bridge = fg.Channel("/bridge", message_encoding="json", schema=json_schema(
            "elaslam.BridgeStats", {"datagrams": "integer", "messages": "integer", "malformed_datagrams": "integer",
                                    "fragments_dropped": "integer", "decode_errors": "integer",
                                    "invalid_messages": "integer", "handler_errors": "integer", "clients": "integer",
                                    "subscriptions": "integer", "clients_served": "integer", "poses": "object",
                                    "refused_by_reason": "object", "decode_errors_by_channel": "object",
                                    "invalid_by_reason": "object"}))
        self.robot_ch = {}       # r -> (pose, trail, stats) channels
        self.status_ch = {}      # node name -> JSON channel
        self.trails = {}         # r -> deque of (x, y, theta)
        self.poses = collections.Counter()
        self.pending = {}        # r -> (frame, pose, cov, stats) waiting for the frame's ground truth
        self.inconsistent = {}   # r -> (fault bit, fault flags) of its last STATUS
        self.truth = collections.OrderedDict()   # frame -> {r: (x, y, theta)}, the last 200
        self.truth_landmarks = []
        self.landmarks = {}      # id -> [x, y, cxx, cxy, cyy, status]; status static | moving | gone
        self.candidates = {}     # r -> (frame, [(id, x, y, cxx, cxy, cyy)])
        # r -> ((frame, utime), num_chunks, {chunk}, [(id, x, y, vx, vy, model)]) of its newest TRACKS_<r>
        # publication (main may send a frame's GLOBAL_TRACKS twice: a publication is its frame and utime)
        self.tracks = {}
        self.fused_tracks = ((-1, 0), 0, set(), [])  # the same of the newest GLOBAL_TRACKS
        self.map_frame, self.map_dirty, self.map_sent = -1, False, 0.0
        self.truth_dirty, self.truth_sent = False, 0.0
        self.notices_seen = collections.OrderedDict()
        self.decode_errors, self.invalid, self.handler_errors = collections.Counter(), collections.Counter(), 0
        self.messages = 0
        self.lock = threading.Lock()
        self.subs = collections.defaultdict(set)  # client id -> channel ids (the server listener's threads)
        self.clients_seen = set()
        for r in args.robots:
            self.robot_channels(r)
        self.handlers = [(re.compile(r"POSE_(\d+)"), T.pose_estimate_t, self.on_pose),
                         (re.compile(r"GLOBAL_MAP"), T.global_map_t, self.on_global_map),
                         (re.compile(r"CANDIDATES_(\d+)"), T.candidate_list_t, self.on_candidates),
                         (re.compile(r"TRACKS_(\d+)"), T.track_list_t, self.on_tracks),
                         (re.compile(r"GLOBAL_TRACKS"), T.global_tracks_t, self.on_global_tracks),
                         (re.compile(r"GROUND_TRUTH"), T.ground_truth_t, self.on_truth),
                         (re.compile(r"DYNAMIC_NOTICE"), T.dynamic_notice_t, self.on_notice),
                         (re.compile(r"STATUS_(ROBOT_\d+|MAIN|SIM)"), T.node_status_t, self.on_status)]

    # ---- the server listener (called on the server's threads) ------------------------
    def on_subscribe(self, client, channel):
        with self.lock:
            self.subs[client.id].add(channel.id)
            self.clients_seen.add(client.id)

    def on_unsubscribe(self, client, channel):
        with self.lock:
            self.subs[client.id].discard(channel.id)
            if not self.subs[client.id]:
                del self.subs[client.id]

    # ---- LCM in -----------------------------------------------------------------------
    def dispatch(self, channel, payload):
        for pattern, cls, handler in self.handlers:
            m = pattern.fullmatch(channel)
            if m is None:
                continue
            try:
                msg = cls.decode(payload)
            except Exception:  # a corrupt or foreign message on our channel
                self.decode_errors[channel] += 1
                return
            self.messages += 1
            try:
                why = handler(msg, *m.groups())
            except Exception as e:  # never out of the loop: counted, said once in a while
                self.handler_errors += 1
                if self.handler_errors <= 20 or self.handler_errors % 1000 == 0:
                    print(f"{PROG}: {channel}: {type(e).__name__}: {e} (skipped)", file=sys.stderr, flush=True)
                return
            if why:
                self.invalid[f"{channel.split('_')[0]}: {why}"] += 1
            return

    def robot_channels(self, r):
        if r not in self.robot_ch:
            ch = self.fg.channels
            self.robot_ch[r] = (ch.PoseInFrameChannel(f"/robot{r}/pose"), ch.PosesInFrameChannel(f"/robot{r}/trail"),
                                self.fg.Channel(f"/robot{r}/stats", message_encoding="json",
                                                schema=json_schema("elaslam.RobotStats", ROBOT_STATS)))
            self.trails[r] = collections.deque(maxlen=self.args.trail)
        return self.robot_ch[r]

    def on_pose(self, p, rid):
        r = int(rid)
        if p.robot_id != r or not 1 <= r <= MAX_ROBOTS:
            return "robot id differs from the channel's or is out of range"
        cov = p.cov
        if not finite(p.x, p.y, p.theta, *cov[0], *cov[1], *cov[2]) or abs(p.x) > WORLD_BOUND_M or abs(p.y) > WORLD_BOUND_M:
            return "pose or covariance not finite or out of bounds"
        if not finite(p.nis) or p.nis < 0 or p.nis_dof < 0 or p.nis_dof % 2:
            return "nis negative or not finite, or nis_dof not even"
        s, now = self.s, time.time_ns()
        stamp = s.ts(p.utime)
        ch_pose, ch_trail, _ = self.robot_channels(r)
        self.poses[r] += 1
        pose = s.pose(p.x, p.y, p.theta)
        ch_pose.log(s.m.PoseInFrame(timestamp=stamp, frame_id="map", pose=pose), log_time=now)
        trail = self.trails[r]
        trail.append((p.x, p.y, p.theta))
        ch_trail.log(s.m.PosesInFrame(timestamp=stamp, frame_id="map", poses=[s.pose(*q) for q in trail]), log_time=now)
        self.ch_tf.log(s.m.FrameTransforms(transforms=[s.m.FrameTransform(
            timestamp=stamp, parent_frame_id="map", child_frame_id=f"robot{r}",
            translation=s.m.Vector3(x=p.x, y=p.y, z=0.0), rotation=s.yaw(p.theta))]), log_time=now)
        rgb = ROBOT_COLOURS[(r - 1) % len(ROBOT_COLOURS)]
        arrow = s.m.ArrowPrimitive(pose=pose, shaft_length=0.45, shaft_diameter=0.08, head_length=0.2,
                                   head_diameter=0.2, color=s.colour(rgb))
        self.ch_robots.log(s.m.SceneUpdate(entities=[s.entity(
            stamp, f"robot{r}", arrows=[arrow], spheres=[s.disc(p.x, p.y, cov[0][0], cov[0][1], cov[1][1], rgb, 0.3)],
            texts=[s.label(p.x, p.y, f"robot {r}", rgb)])]), log_time=now)
        bit, flags = self.inconsistent.get(r, (0, 0))
        stats = {
            "robot": r, "frame": p.frame, "x_m": p.x, "y_m": p.y, "theta_rad": p.theta,
            "sigma_x_m": math.sqrt(max(0.0, cov[0][0])), "sigma_y_m": math.sqrt(max(0.0, cov[1][1])),
            "sigma_theta_rad": math.sqrt(max(0.0, cov[2][2])), "pose_cov_trace": cov[0][0] + cov[1][1] + cov[2][2],
            "mean_diag_p": clean(p.mean_diag_p), "num_obs": p.num_obs, "num_accepted": p.num_accepted,
            "num_rejected": p.num_rejected, "num_landmarks": p.num_landmarks, "processing_us": p.processing_us,
            "nis": p.nis if p.nis_dof > 0 else None, "nis_dof": p.nis_dof,
            "nis_per_dof": p.nis / p.nis_dof if p.nis_dof > 0 else None, "nees": None, "error_m": None, "inconsistent": bit, "fault_flags": flags,
            "latency_ms": clean((now / 1000 - p.source_utime) / 1000) if p.source_utime > 0 else None}
        # Consistency against ground truth (NEES, 3 dof): the frame's GROUND_TRUTH may come
        # after the pose (the robots are quicker than the simulator's last message): the
        # stats wait for it while the bus has ground truth, until the robot's next pose.
        if r in self.pending:
            self.send_stats(r, None)
        self.pending[r] = (p.frame, (p.x, p.y, p.theta), [list(row) for row in cov], stats)
        if p.frame in self.truth or not self.truth or max(self.truth) < p.frame - 5:
            self.send_stats(r, self.truth.get(p.frame, {}).get(r))
        return None

    def send_stats(self, r, truth):
        """Robot r's pending stats, with the NEES and error against `truth` (x, y, theta) when given."""
        frame, (x, y, theta), cov, stats = self.pending.pop(r)
        if truth is not None:
            e = (x - truth[0], y - truth[1], wrap(theta - truth[2]))
            stats["nees"], stats["error_m"] = clean(nees3(e, cov)), math.hypot(e[0], e[1])
        self.robot_ch[r][2].log(stats, log_time=time.time_ns())

    def on_global_map(self, m):
        if not (0 <= m.id_begin < m.id_end <= MAX_LANDMARK_ID) or not 0 <= m.chunk < m.num_chunks:
            return "id range or chunk out of range"
        lms = m.landmarks[:max(0, m.num_landmarks)]
        for l in lms:
            if not m.id_begin <= l.id < m.id_end or not finite(l.x, l.y, l.cov[0][0], l.cov[0][1], l.cov[1][1]) \
                    or abs(l.x) > WORLD_BOUND_M or abs(l.y) > WORLD_BOUND_M or l.cov[0][0] < 0 or l.cov[1][1] < 0:
                return "a landmark outside its chunk, not finite or out of bounds"
        moving = [i for i in m.moving_ids[:max(0, m.num_moving)]]
        if any(not m.id_begin <= i < m.id_end for i in moving):
            return "a moving id outside its chunk"
        # The chunk stands alone for its id range: what it does not list is not in the map;
        # a moving landmark has no estimate: it is drawn where it was last mapped.
        for i, l in self.landmarks.items():
            if m.id_begin <= i < m.id_end:
                l[5] = "gone"
        for l in lms:
            self.landmarks[l.id] = [l.x, l.y, l.cov[0][0], l.cov[0][1], l.cov[1][1],
                                    "moving" if l.status == self.T.global_landmark_t.MOVING else "static"]
        for i in moving:
            if i in self.landmarks:
                self.landmarks[i][5] = "moving"
        self.map_frame = max(self.map_frame, m.frame)
        self.map_dirty = True
        return None

    def on_candidates(self, m, rid):
        r = int(rid)
        if m.robot_id != r or not 1 <= r <= MAX_ROBOTS:
            return "robot id differs from the channel's"
        cs = [(c.id, c.x, c.y, c.cov[0][0], c.cov[0][1], c.cov[1][1]) for c in m.candidates[:max(0, m.num_candidates)]
              if finite(c.x, c.y, c.cov[0][0], c.cov[0][1], c.cov[1][1]) and abs(c.x) <= WORLD_BOUND_M
              and abs(c.y) <= WORLD_BOUND_M]
        self.candidates[r] = (m.frame, cs)
        self.map_dirty = True
        return None

    @staticmethod
    def track_rows(tracks, n):
        """[(id, x, y, vx, vy, model)] of a message's tracks; None when one is out of range or not finite."""
        rows = []
        for t in tracks[:max(0, n)]:
            if not 0 <= t.id < MAX_LANDMARK_ID or not finite(t.x, t.y, t.vx, t.vy) or t.likeliest not in TRACK_COLOURS \
                    or max(abs(t.x), abs(t.y), abs(t.vx), abs(t.vy)) > WORLD_BOUND_M:
                return None
            rows.append((t.id, t.x, t.y, t.vx, t.vy, t.likeliest))
        return rows

    @staticmethod
    def add_chunk(held, m, rows):
        """The chunks of the newest frame of a tracks publication with chunk m added
        (a newer frame starts over, an older frame or a chunk held already changes
        nothing); a str saying why when m is at odds with the chunks held."""
        if not 1 <= m.num_chunks <= MAX_TRACK_CHUNKS or not 0 <= m.chunk < m.num_chunks:
            return "chunk out of range"
        stamp, num_chunks, chunks, held_rows = held
        if (m.frame, m.utime) < stamp:
            return held
        if (m.frame, m.utime) > stamp:
            return ((m.frame, m.utime), m.num_chunks, {m.chunk}, rows)
        if m.num_chunks != num_chunks:
            return "num_chunks differs from its frame's other chunks"
        if m.chunk in chunks:
            return held
        if {r[0] for r in rows} & {r[0] for r in held_rows}:
            return "a landmark id in two chunks"
        return (frame, num_chunks, chunks | {m.chunk}, held_rows + rows)

    def on_tracks(self, m, rid):
        r = int(rid)
        if m.robot_id != r or not 1 <= r <= MAX_ROBOTS:
            return "robot id differs from the channel's"
        rows = self.track_rows(m.tracks, m.num_tracks)
        if rows is None:
            return "a track out of range or not finite"
        held = self.add_chunk(self.tracks.get(r, ((-1, 0), 0, set(), [])), m, rows)
        if isinstance(held, str):
            return held
        self.tracks[r] = held
        self.map_dirty = True
        return None

    def on_global_tracks(self, m):
        rows = self.track_rows(m.tracks, m.num_tracks)
        if rows is None:
            return "a fused track out of range or not finite"
        held = self.add_chunk(self.fused_tracks, m, rows)
        if isinstance(held, str):
            return held
        self.fused_tracks = held
        self.map_dirty = True
        return None

    def on_truth(self, m):
        n = max(0, m.num_robots)
        self.truth[m.frame] = {rid: (q.x, q.y, q.theta) for rid, q in zip(m.robot_ids[:n], m.robots[:n])
                               if finite(q.x, q.y, q.theta)}
        while len(self.truth) > 200:
            self.truth.popitem(last=False)
        for r in [r for r, pend in self.pending.items() if pend[0] <= m.frame]:
            self.send_stats(r, self.truth[m.frame].get(r) if self.pending[r][0] == m.frame else None)
        self.truth_landmarks = [(l.id, l.x, l.y, bool(l.moving)) for l in m.landmarks[:max(0, m.num_landmarks)]
                                if finite(l.x, l.y)]
        self.truth_dirty = True
        return None

    def on_notice(self, m):
        key = (m.landmark_id, m.frame, m.detected_by)
        if key in self.notices_seen:  # main repeats its notices: listed once
            return None
        self.notices_seen[key] = True
        while len(self.notices_seen) > 1000:
            self.notices_seen.popitem(last=False)
        self.ch_notices.log(self.s.m.Log(
            timestamp=self.s.ts(m.utime), level=self.s.m.LogLevel.Info, name="DYNAMIC_NOTICE",
            message=f"landmark {m.landmark_id} moves (found by robot {m.detected_by} at frame {m.frame})"),
            log_time=time.time_ns())
        return None

    def on_status(self, m, node):
        name = node.lower().replace("robot_", "robot")
        if name.startswith("robot"):
            r = int(name[5:])
            if not 1 <= r <= MAX_ROBOTS:
                return "robot id out of range"
            self.inconsistent[r] = (1 if m.fault_flags & FAULT_INCONSISTENT else 0, m.fault_flags)
        ch = self.status_ch.get(name)
        if ch is None:
            ch = self.status_ch[name] = self.fg.Channel(f"/status/{name}", message_encoding="json", schema=json_schema(
                "elaslam.NodeStatus", {k: "array" if k == "refused" else NUM for k in self.T.node_status_t.__slots__}))
        ch.log({k: clean(getattr(m, k)) if not isinstance(getattr(m, k), (list, tuple)) else list(getattr(m, k))
                for k in self.T.node_status_t.__slots__}, log_time=time.time_ns())
        return None

    # ---- out, at a bounded rate ---------------------------------------------------------
    def publish_map(self, now_s, force):
        if not (self.map_dirty or force):
            return
        s = self.s
        stamp = s.ts(int(now_s * 1e6))
        by = {"static": [], "moving": [], "candidate": []}
        discs, labels = [], []
        taken = {i for i, l in self.landmarks.items() if l[5] == "static"}
        shown = [(i, l[0], l[1], l[2], l[3], l[4], l[5]) for i, l in sorted(self.landmarks.items()) if l[5] != "gone"]
        for r in sorted(self.candidates):
            frame, cs = self.candidates[r]
            if self.map_frame - frame > 20:
                continue
            for c in cs:
                if c[0] not in taken:
                    taken.add(c[0])
                    shown.append((*c, "candidate"))
        for i, x, y, cxx, cxy, cyy, status in shown:
            rgb = STATUS_COLOURS[status]
            by[status].append(s.dot(x, y, rgb))
            discs.append(s.disc(x, y, cxx, cxy, cyy, rgb, 0.25))
            labels.append(s.label(x + 0.25, y + 0.25, str(i), rgb))
        ents = [s.entity(stamp, f"landmarks/{k}", spheres=v) for k, v in by.items()]
        ents += [s.entity(stamp, "landmarks/ellipses", spheres=discs), s.entity(stamp, "landmarks/labels", texts=labels)]
        # Tracks of moving landmarks: each robot's and main's fused ones, while not 20 frames stale.
        robot_arrows = [s.track_arrow(x, y, vx, vy, model, False) for r in sorted(self.tracks)
                        if self.map_frame - self.tracks[r][0][0] <= 20 for _, x, y, vx, vy, model in self.tracks[r][3]]
        (frame, _), _, _, fused = self.fused_tracks
        fused_arrows = [s.track_arrow(x, y, vx, vy, model, True) for _, x, y, vx, vy, model in fused
                        if self.map_frame - frame <= 20]
        ents += [s.entity(stamp, "tracks/robots", arrows=robot_arrows), s.entity(stamp, "tracks/fused", arrows=fused_arrows)]
        self.ch_map.log(s.m.SceneUpdate(entities=ents), log_time=time.time_ns())
        self.map_dirty, self.map_sent = False, now_s

    def publish_truth(self, now_s, force):
        if not (self.truth_dirty or (force and self.truth)):
            return
        s = self.s
        stamp = s.ts(int(now_s * 1e6))
        grey = (0.2, 0.2, 0.2)
        cubes = [s.m.CubePrimitive(pose=s.pose(x, y, math.pi / 4), size=s.m.Vector3(x=0.12, y=0.12, z=0.12),
                                   color=s.colour((0.85, 0.15, 0.12) if mv else grey, 0.8))
                 for _, x, y, mv in self.truth_landmarks]
        last = next(reversed(self.truth.values()), {})
        arrows = [s.m.ArrowPrimitive(pose=s.pose(*q), shaft_length=0.45, shaft_diameter=0.05, head_length=0.2,
                                     head_diameter=0.15, color=s.colour(grey, 0.6)) for q in last.values()]
        self.ch_truth.log(s.m.SceneUpdate(entities=[s.entity(stamp, "truth/landmarks", cubes=cubes),
                                                    s.entity(stamp, "truth/robots", arrows=arrows)]),
                          log_time=time.time_ns())
        self.truth_dirty, self.truth_sent = False, now_s

    def stats(self, rx):
        with self.lock:
            clients, subs = len(self.subs), sum(len(v) for v in self.subs.values())
        return {"datagrams": rx.datagrams, "messages": self.messages, "malformed_datagrams": sum(rx.refused.values()),
                "fragments_dropped": rx.dropped, "decode_errors": sum(self.decode_errors.values()),
                "invalid_messages": sum(self.invalid.values()), "handler_errors": self.handler_errors,
                "clients": clients, "subscriptions": subs, "clients_served": len(self.clients_seen),
                "poses": {str(r): n for r, n in sorted(self.poses.items())},
                "refused_by_reason": dict(rx.refused), "decode_errors_by_channel": dict(self.decode_errors),
                "invalid_by_reason": dict(self.invalid)}


def parse_robots(text):
    try:
        rs = sorted({int(x) for x in text.replace(",", " ").split()})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected robot ids like 1,2,3, got '{text}'") from None
    if any(not 1 <= r <= MAX_ROBOTS for r in rs):
        raise argparse.ArgumentTypeError(f"robot ids must be in 1..{MAX_ROBOTS}, got '{text}'")
    return rs


def main() -> int:
    ap = doc_parser("foxglove_bridge.py", __doc__)
    ap.add_argument("--port", type=int, default=8765, help="WebSocket port (0: any free one; default 8765)")
    ap.add_argument("--bind", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine only)")
    ap.add_argument("--lcm-url", default=os.environ.get("LCM_DEFAULT_URL", ""), help="LCM URL (default LCM_DEFAULT_URL)")
    ap.add_argument("--channel-groups", action="store_true", help="the team runs in channel groups (one port each)")
    ap.add_argument("--robots", type=parse_robots, default=[], help="robot ids to advertise at once (others when heard)")
    ap.add_argument("--build-dir", help="the build directory whose lcmgen/python has the message types")
    ap.add_argument("--ws-netns", help="serve WebSocket clients in this network namespace (root; /proc/PID/ns/net)")
    ap.add_argument("--map-rate", type=float, default=5.0, help="most /map and /truth updates a second (default 5)")
    ap.add_argument("--trail", type=int, default=200, help="poses in /robot<r>/trail (default 200)")
    args = _parse(ap)
    if not 0 <= args.port <= 65535 or not 0.1 <= args.map_rate <= 100 or not 1 <= args.trail <= 10000:
        ap.error("--port must be in 0..65535, --map-rate in [0.1, 100], --trail in 1..10000")
    try:
        address = parse_udpm_url(args.lcm_url)
    except ValueError as e:
        ap.error(f"--lcm-url: {e}")
    T = load_lcm_types(args.build_dir, __file__)

    ports = [address[1] + g for g in GROUPS] if args.channel_groups else [address[1]]
    try:  # LCM here, in this namespace; the server perhaps in another
        rx = UdpmReceiver(address, ports)
    except OSError as e:
        print(f"{PROG}: cannot open LCM {args.lcm_url or 'default URL'}: {e}", file=sys.stderr)
        return 1
    if args.ws_netns:
        try:
            enter_netns(args.ws_netns)
        except OSError as e:
            print(f"{PROG}: cannot enter the network namespace {args.ws_netns}: {e}", file=sys.stderr)
            return 1
    fg = _need("foxglove")
    _need("foxglove.channels")
    _need("foxglove.messages")
    bridge = Bridge(fg, T, args)
    try:
        server = fg.start_server(name="elaslam", host=args.bind, port=args.port, server_listener=bridge)
    except Exception as e:  # port in use, address not here
        print(f"{PROG}: cannot serve on {args.bind}:{args.port}: {e}", file=sys.stderr)
        return 1
    if args.bind not in ("127.0.0.1", "localhost", "::1"):
        print(f"{PROG}: listening on {args.bind}: anyone who reaches it sees the team (the protocol has no "
              "authentication; prefer ssh -L PORT:127.0.0.1:PORT)", file=sys.stderr)
    url = f"ws://{args.bind}:{server.port}"
    print(f"{PROG}: {url}", flush=True)
    print(f"{PROG}: LCM {args.lcm_url or 'default URL'}, port(s) {', '.join(map(str, ports))} (pid {os.getpid()})",
          file=sys.stderr, flush=True)

    stop = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.append(1))
    period = 1.0 / args.map_rate
    last_stats = 0.0
    while not stop:
        for channel, payload in rx.poll(0.05):
            bridge.dispatch(channel, payload)
        now = time.time()
        try:
            if now - bridge.map_sent >= period:  # unchanged: again once a second, for clients that join
                bridge.publish_map(now, now - bridge.map_sent >= 1.0)
            if now - bridge.truth_sent >= period:
                bridge.publish_truth(now, now - bridge.truth_sent >= 1.0)
            if now - last_stats >= 1.0:
                bridge.ch_bridge.log(bridge.stats(rx), log_time=time.time_ns())
                last_stats = now
        except Exception as e:
            bridge.handler_errors += 1
            print(f"{PROG}: publishing: {type(e).__name__}: {e}", file=sys.stderr, flush=True)
    st = bridge.stats(rx)
    server.stop()
    rx.close()
    poses = " ".join(f"{r}:{n}" for r, n in st["poses"].items()) or "none"
    print(f"{PROG}: stopped: {url} served {st['clients_served']} client(s); "
          f"{st['messages']} messages, poses by robot {poses}; {st['malformed_datagrams']} malformed datagrams, "
          f"{st['decode_errors']} undecodable and {st['invalid_messages']} invalid messages skipped; "
          f"{time.process_time():.1f} s of CPU", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
