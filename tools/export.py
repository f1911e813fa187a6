#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Export an elaslam LCM recording as a ROS 2 bag (MCAP storage, standard message
types), for Foxglove Studio, `ros2 bag play`, RViz and other ROS 2 tools.

    tools/export.py RECORDING -o OUTDIR [--force] [--channel-suffix S] [--build-dir DIR]

Topics (docs/tools.md "export"; frame `map` is the world frame W):
  /robot<r>/pose             geometry_msgs/msg/PoseWithCovarianceStamped  one per POSE_<r>
  /tf                        tf2_msgs/msg/TFMessage      map -> robot<r>, one per POSE_<r>
  /global_map                visualization_msgs/msg/MarkerArray  one per GLOBAL_MAP chunk
  /ground_truth/robots       geometry_msgs/msg/PoseArray         one per GROUND_TRUTH
  /ground_truth/landmarks    visualization_msgs/msg/MarkerArray  one per GROUND_TRUTH
  /robot<r>/status, /main_robot/status, /simulator/status
                             diagnostic_msgs/msg/DiagnosticArray one per STATUS_*
  /moving_landmark_notices   std_msgs/msg/String (JSON)          one per DYNAMIC_NOTICE
Header stamps are the messages' own times (POSE: the sensor frame's time,
source_utime; the others: utime); each message is recorded at its LCM event's time.
OUTDIR must not exist (--force replaces an earlier bag). Events that do not decode
are counted and reported, not fatal; a truncated log is exported as far as it goes.
Exit 0 done, 1 the bag could not be written, 2 a bad argument or recording.
In a source tree the script runs itself in the project's .venv (tools/setup.sh
installs rosbags there); an installed copy needs `rosbags` (PyPI) for its python3.
"""
# ---- start-up: standard library only, before any third-party import (tools/elaslam_tool.py)
import os
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path[:0] = [_here, os.path.join(_here, "..", "share", "elaslam", "tools")]
from elaslam_tool import add_version, load_lcm_types, need, parse_args, prog, run_in_venv  # noqa: E402

if __name__ == "__main__":
    run_in_venv()
# ----------------------------------------------------------------------------------
import argparse  # noqa: E402
import collections  # noqa: E402
import json  # noqa: E402
import mmap  # noqa: E402
import re  # noqa: E402
import shutil  # noqa: E402
import struct  # noqa: E402
import time  # noqa: E402

from export_markers import MarkerMaker, GlobalMapMarkers  # noqa: E402

LCM_MAGIC = 0xEDA1DA01
EVENT_HEADER = struct.Struct(">IqqII")  # magic, event number, timestamp [us], channel and data lengths
MAX_CHANNEL_BYTES = 1000  # liblcm's sanity bound, as logs/src/log_reader.cpp
ROS_DISTRO = "jazzy"      # the message definitions written into the bag (rosbags' typestore)


class BadInput(Exception):
    """The recording or an argument cannot be used: exit 2 with this message."""


class LcmLog:
    """The events of an LCM log, read as logs/src/log_reader.cpp (log_info) reads them:
    bytes between events are skipped and counted, a truncated last event ends the read."""

    def __init__(self, path):
        if not os.path.exists(path):
            raise BadInput(f"no such recording: {path}")
        if os.path.isdir(path):
            raise BadInput(f"{path} is a directory, not an LCM recording")
        if not os.path.isfile(path):  # a FIFO would block, a device never end
            raise BadInput(f"{path} is not a regular file, not an LCM recording")
        try:
            self._file = open(path, "rb")
        except OSError as e:
            raise BadInput(f"cannot open the recording {path}: {e.strerror}")
        self.size = os.fstat(self._file.fileno()).st_size
        self._map = mmap.mmap(self._file.fileno(), 0, access=mmap.ACCESS_READ) if self.size else b""
        head = bytes(self._map[:4])
        if self.size and head != struct.pack(">I", LCM_MAGIC):
            raise BadInput(f"{path} is not an LCM log: an LCM log starts with the event marker ed a1 da 01, "
                           f"this file starts with {head.hex(' ')}")
        self.skipped = 0    # bytes between events that were not an event
        self.end = 0        # where the read stopped

    def _event_at(self, off):
        if off + EVENT_HEADER.size > self.size:
            return None
        magic, _, utime, clen, dlen = EVENT_HEADER.unpack_from(self._map, off)
        start = off + EVENT_HEADER.size
        if magic != LCM_MAGIC or not 0 < clen < MAX_CHANNEL_BYTES or start + clen + dlen > self.size:
            return None
        try:
            channel = bytes(self._map[start:start + clen]).decode("ascii")
        except UnicodeDecodeError:
            return None
        return utime, channel, bytes(self._map[start + clen:start + clen + dlen]), start + clen + dlen

    def events(self):
        """(timestamp [us], channel, payload) of every whole event."""
        pos = 0
        marker = struct.pack(">I", LCM_MAGIC)
        while pos < self.size:
            at = pos
            ev = self._event_at(at)
            while ev is None:
                at = self._map.find(marker, at + 1)
                if at < 0:
                    self.end = pos
                    return
                ev = self._event_at(at)
            self.skipped += at - pos
            pos = ev[3]
            self.end = pos
            yield ev[0], ev[1], ev[2]

    def close(self):
        if self.size:
            self._map.close()
        self._file.close()


def robot_of(channel, prefix, suffix):
    """r of "<prefix><r><suffix>" (a positive decimal of at most 6 digits), else None (common/channels.hpp)."""
    m = re.fullmatch(re.escape(prefix) + r"([0-9]{1,6})" + re.escape(suffix), channel)
    return int(m.group(1)) if m and int(m.group(1)) > 0 else None


def stamp(utime_us):
    """builtin_interfaces/Time fields of a time in microseconds; None when it does not fit (int32 seconds)."""
    sec, usec = divmod(int(utime_us), 1_000_000)
    return (sec, usec * 1000) if -2**31 <= sec < 2**31 else None


class Exporter:
    """LCM events in, ROS 2 messages out: one converter per channel kind."""

    def __init__(self, writer, typestore, lcm_types, suffix):
        self.writer, self.ts, self.T, self.sfx = writer, typestore, lcm_types, suffix
        self.M = MarkerMaker(typestore)
        self.global_map = GlobalMapMarkers(self.M)
        self.connections = {}                        # topic -> (connection, msgtype)
        self.written = collections.Counter()         # topic -> messages
        self.sources = collections.defaultdict(set)  # topic -> LCM channels
        self.undecodable = collections.Counter()     # channel -> events that did not decode
        self.unusable = collections.Counter()        # channel -> decoded events with a time that fits no ROS stamp
        self.skipped = collections.Counter()         # channel -> events of channels not exported
        self.last_pose = {}                          # robot -> (x, y, theta, stamp ns), for the summary
        self.fault_names, self.error_bits = status_tables(lcm_types.node_status_t)

    # ---- dispatch ------------------------------------------------------------------
    def route(self, channel):
        """(LCM type, converter, robot id or None) for a channel, None when it is not exported."""
        T, s = self.T, self.sfx
        for prefix, cls, conv in (("POSE_", T.pose_estimate_t, self.on_pose),
                                  ("STATUS_ROBOT_", T.node_status_t, self.on_status)):
            r = robot_of(channel, prefix, s)
            if r is not None:
                return cls, conv, r
        fixed = {"GLOBAL_MAP": (T.global_map_t, self.on_global_map), "GROUND_TRUTH": (T.ground_truth_t, self.on_truth),
                 "DYNAMIC_NOTICE": (T.dynamic_notice_t, self.on_notice),
                 "STATUS_MAIN": (T.node_status_t, self.on_status), "STATUS_SIM": (T.node_status_t, self.on_status)}
        if s == "" or channel.endswith(s):
            hit = fixed.get(channel[:len(channel) - len(s)] if s else channel)
            if hit:
                return hit[0], hit[1], None
        return None

    def add(self, log_utime, channel, data):
        route = self.route(channel)
        if route is None:
            self.skipped[channel] += 1
            return
        cls, conv, robot = route
        try:
            msg = cls.decode(data)
        except Exception:  # a corrupt, truncated or foreign event on our channel
            self.undecodable[channel] += 1
            return
        log_ns = log_utime * 1000
        out = conv(msg, robot, channel) if 0 <= log_ns < 2**63 else None
        if out is None:
            self.unusable[channel] += 1
            return
        for topic, msgtype, ros_msg in out:
            self.write(topic, msgtype, ros_msg, log_ns, channel)

    def write(self, topic, msgtype, msg, log_ns, channel):
        if topic not in self.connections:
            self.connections[topic] = (self.writer.add_connection(topic, msgtype, typestore=self.ts), msgtype)
        conn, msgtype = self.connections[topic]
        self.writer.write(conn, log_ns, self.ts.serialize_cdr(msg, msgtype))
        self.written[topic] += 1
        self.sources[topic].add(channel)

    # ---- converters: each returns [(topic, type, message)] or None (a time no stamp holds)
    def on_pose(self, p, robot, _channel):
        # The estimate is of the sensor frame's time (source_utime), not of its publication.
        t = stamp(p.source_utime if p.source_utime > 0 else p.utime)
        if t is None:
            return None
        M = self.M
        header = M.header(t)
        cov = M.np.zeros(36)
        for i, ri in enumerate((0, 1, 5)):      # (x, y, theta) -> (x, y, z, roll, pitch, yaw) rows
            for j, cj in enumerate((0, 1, 5)):
                cov[6 * ri + cj] = p.cov[i][j]
        pose = M.pose2d(p.x, p.y, p.theta)
        msg = M.T["geometry_msgs/msg/PoseWithCovarianceStamped"](
            header=header, pose=M.T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=cov))
        q = pose.orientation
        tf = M.T["geometry_msgs/msg/TransformStamped"](
            header=header, child_frame_id=f"robot{robot}",
            transform=M.T["geometry_msgs/msg/Transform"](translation=M.vec3(p.x, p.y, 0.0), rotation=q))
        self.last_pose[robot] = (p.x, p.y, p.theta, t[0] * 10**9 + t[1])
        return [(f"/robot{robot}/pose", "geometry_msgs/msg/PoseWithCovarianceStamped", msg),
                ("/tf", "tf2_msgs/msg/TFMessage", M.T["tf2_msgs/msg/TFMessage"](transforms=[tf]))]

    def on_global_map(self, g, _robot, _channel):
        t = stamp(g.utime)
        if t is None:
            return None
        return [("/global_map", "visualization_msgs/msg/MarkerArray", self.global_map.chunk(g, self.M.header(t)))]

    def on_truth(self, gt, _robot, _channel):
        t = stamp(gt.utime)
        if t is None:
            return None
        M = self.M
        header = M.header(t)
        n = max(0, min(gt.num_robots, len(gt.robots)))
        poses = M.T["geometry_msgs/msg/PoseArray"](header=header,
                                                   poses=[M.pose2d(r.x, r.y, r.theta) for r in gt.robots[:n]])
        return [("/ground_truth/robots", "geometry_msgs/msg/PoseArray", poses),
                ("/ground_truth/landmarks", "visualization_msgs/msg/MarkerArray", M.truth_markers(gt, header))]

    def on_notice(self, m, _robot, _channel):
        # std_msgs/String has no header: the notice's own time is in the JSON.
        text = json.dumps({"utime": m.utime, "frame": m.frame, "landmark_id": m.landmark_id,
                           "detected_by": m.detected_by, "seq": m.seq, "incarnation": m.incarnation})
        return [("/moving_landmark_notices", "std_msgs/msg/String", self.M.T["std_msgs/msg/String"](data=text))]

    def on_status(self, s, robot, channel):
        t = stamp(s.utime)
        if t is None:
            return None
        base = channel[:len(channel) - len(self.sfx)] if self.sfx else channel
        if robot is not None:
            topic, name, hw = f"/robot{robot}/status", f"robot_node {robot}", f"robot{robot}"
        elif base == "STATUS_MAIN":
            topic, name, hw = "/main_robot/status", "main_robot", "main_robot"
        else:
            topic, name, hw = "/simulator/status", "simulator", "simulator"
        M, cls = self.M, type(s)
        flags = s.fault_flags
        faults = [n for bit, n in self.fault_names if flags & bit] + \
                 [f"bit {b}" for b in range(31) if flags & (1 << b) and all(bit != 1 << b for bit, _ in self.fault_names)]
        level = 0 if flags == 0 else 2 if flags & self.error_bits else 1   # OK, WARN, ERROR
        values = [("faults", ", ".join(faults) or "none")] + status_values(s, cls)
        status = M.T["diagnostic_msgs/msg/DiagnosticStatus"](
            level=level, name=name, message=", ".join(faults) if faults else "OK", hardware_id=hw,
            values=[M.T["diagnostic_msgs/msg/KeyValue"](key=k, value=v) for k, v in values])
        return [(topic, "diagnostic_msgs/msg/DiagnosticArray",
                 M.T["diagnostic_msgs/msg/DiagnosticArray"](header=M.header(t, frame=""), status=[status]))]


# The FAULT_* bits by name (common/faults.hpp), and those that make a STATUS an ERROR:
# the node's results are no longer what its inputs say (a capacity exceeded, a lost
# robot's inconsistent filter) or two senders claim one identity. Every other bit is a WARN.
FAULT_NAMES = {"DUPLICATE_SENDER": "duplicate sender", "UNREPAIRED_GAP": "unrepaired gap", "CAPACITY": "capacity",
               "INCONSISTENT": "inconsistent", "FRAMES_LOST": "frames lost", "INPUT_REFUSED": "input refused",
               "SAVE_FAILED": "save failed", "MAIN_SILENT": "main silent", "INCARNATION": "incarnation refused",
               "PARTITION_HEALED": "partition healed", "RELOCALISED": "relocalised"}
ERROR_FAULTS = ("DUPLICATE_SENDER", "CAPACITY", "INCONSISTENT", "INCARNATION")


def status_tables(cls):
    """[(bit, name)] in bit order from the type's FAULT_* constants, and the mask of ERROR bits."""
    bits = sorted((getattr(cls, a), FAULT_NAMES.get(a[6:], a[6:].lower().replace("_", " ")))
                  for a in dir(cls) if a.startswith("FAULT_"))
    errors = 0
    for a in ERROR_FAULTS:
        errors |= getattr(cls, "FAULT_" + a, 0)
    return bits, errors


def constant_name(cls, prefix, value):
    names = [a[len(prefix):].lower() for a in dir(cls) if a.startswith(prefix) and getattr(cls, a) == value]
    return names[0] if names else str(value)


def status_values(s, cls):
    """Every field of a node_status_t but its time, as key-value text: counters as integers,
    the refused[] counters by reason, kinds and modes by name."""
    out = []
    for field in cls.__slots__:
        v = getattr(s, field)
        if field == "utime":
            continue
        if field == "refused":
            out += [(f"refused.{constant_name(cls, 'REFUSED_', i)}", str(n)) for i, n in enumerate(v)]
        elif field == "node_kind":
            out.append((field, constant_name(cls, "", v) if v in (cls.SIMULATOR, cls.ROBOT, cls.MAIN) else str(v)))
        elif field == "mode":
            out.append((field, constant_name(cls, "MODE_", v)))
        elif isinstance(v, float):
            out.append((field, f"{v:.9g}"))
        else:
            out.append((field, str(v)))
    return out


def main() -> int:
    doc = __doc__.split("\n\n")
    ap = argparse.ArgumentParser(prog=prog(), description=doc[0], epilog="\n\n".join(doc[2:]),
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    add_version(ap)
    ap.add_argument("recording", metavar="RECORDING", help="an LCM log (tools/run_team.sh: runs/team_<time>/run.lcmlog)")
    ap.add_argument("-o", "--out", metavar="OUTDIR", required=True, help="the bag directory to write (must not exist)")
    ap.add_argument("--force", action="store_true", help="replace OUTDIR when it is an earlier bag (has metadata.yaml)")
    ap.add_argument("--channel-suffix", metavar="S", default="", help="the team's channel suffix (POSE_1_SIM2: _SIM2)")
    ap.add_argument("--build-dir", metavar="DIR", help="the build directory whose lcmgen/python has the message types")
    args = parse_args(ap)
    started = time.monotonic()
    out = os.path.abspath(args.out)
    if os.path.lexists(out):
        if not args.force:
            raise BadInput(f"the output {args.out} exists already: give another -o, or --force to replace a bag")
        if not (os.path.isdir(out) and not os.path.islink(out) and os.path.isfile(os.path.join(out, "metadata.yaml"))):
            raise BadInput(f"--force replaces only a bag (a directory with metadata.yaml): {args.out} is not one")
    parent = os.path.dirname(out)
    if not os.path.isdir(parent):
        raise BadInput(f"the output's directory {parent} does not exist")
    log = LcmLog(args.recording)
    need("numpy", debian="python3-numpy")
    rosbag2 = need("rosbags.rosbag2")
    typesys = need("rosbags.typesys")
    T = load_lcm_types(args.build_dir, __file__)
    typestore = typesys.get_typestore(getattr(typesys.Stores, "ROS2_" + ROS_DISTRO.upper()))
    # Written beside OUTDIR under a temporary name, moved into place when complete.
    scratch = os.path.join(parent, f".{os.path.basename(out)}.partial-{os.getpid()}")
    tmp_bag = os.path.join(scratch, os.path.basename(out))
    try:
        os.mkdir(scratch)
        writer = rosbag2.Writer(tmp_bag, version=rosbag2.Writer.VERSION_LATEST, storage_plugin=rosbag2.StoragePlugin.MCAP)
        writer.open()
        ex = Exporter(writer, typestore, T, args.channel_suffix)
        events = 0
        for utime, channel, data in log.events():
            events += 1
            ex.add(utime, channel, data)
        writer.set_custom_data("elaslam.recording", os.path.abspath(args.recording))
        writer.close()
        if not ex.written:
            raise BadInput(f"nothing to export in {args.recording}: no decodable event on POSE_<r>, GLOBAL_MAP, "
                           f"GROUND_TRUTH, STATUS_*, DYNAMIC_NOTICE{' with suffix ' + args.channel_suffix if args.channel_suffix else ''}"
                           f" ({events} events read)")
        if args.force and os.path.isdir(out):
            shutil.rmtree(out)
        os.rename(tmp_bag, out)
    except OSError as e:
        raise RuntimeError(f"cannot write the bag {args.out}: {e.strerror or e}") from None
    except rosbag2.WriterError as e:
        raise RuntimeError(f"cannot write the bag {args.out}: {e}") from None
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
        log.close()
    report(args, log, events, ex, time.monotonic() - started)
    return 0


def report(args, log, events, ex, seconds):
    tail = log.size - log.end
    read = "read to the end" if tail == 0 else f"TRUNCATED: the last {tail} bytes are not a whole event"
    print(f"{prog()}: {args.recording} -> {args.out} (ROS 2 bag, MCAP storage, ROS 2 {ROS_DISTRO} message types)")
    print(f"  events: {events}, {read}" + (f"; {log.skipped} bytes between events skipped" if log.skipped else ""))
    print(f"  {'topic':26s} {'type':45s} {'messages':>8s}  from")
    for topic in sorted(ex.written):
        print(f"  {topic:26s} {ex.connections[topic][1]:45s} {ex.written[topic]:8d}  "
              f"{', '.join(sorted(ex.sources[topic]))}")
    for robot, (x, y, th, ns) in sorted(ex.last_pose.items()):
        print(f"  last /robot{robot}/pose: x {x:.3f} y {y:.3f} theta {th:.3f} at {ns / 1e9:.6f} s")
    if ex.skipped:
        print(f"  not exported: {sum(ex.skipped.values())} events on "
              + ", ".join(f"{c} ({n})" for c, n in sorted(ex.skipped.items())))
    print(f"  exported in {seconds:.2f} s")
    if tail:
        print(f"{prog()}: warning: {args.recording} is truncated: the last {tail} bytes are not a whole event "
              f"(a recorder killed or a copy cut short); exported up to there", file=sys.stderr)
    for what, counter in (("did not decode", ex.undecodable), ("had a time no ROS stamp holds", ex.unusable)):
        if counter:
            n = sum(counter.values())
            print(f"{prog()}: warning: {n} event{'s' if n != 1 else ''} {what}, not exported: "
                  + ", ".join(f"{c} ({n})" for c, n in sorted(counter.items())), file=sys.stderr)


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BadInput as e:
        print(f"{prog()}: {e}", file=sys.stderr)
        sys.exit(2)
    except RuntimeError as e:
        print(f"{prog()}: {e}", file=sys.stderr)
        sys.exit(1)
    except KeyboardInterrupt:
        print(f"{prog()}: interrupted: no bag written", file=sys.stderr)
        sys.exit(130)
    except Exception as e:  # never a traceback: say what failed
        print(f"{prog()}: internal error: {type(e).__name__}: {e}", file=sys.stderr)
        sys.exit(1)
