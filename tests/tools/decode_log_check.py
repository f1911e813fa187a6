# SPDX-License-Identifier: Apache-2.0
"""tools/decode_log.py on a recording made here (run by tests/tools/decode_log_check.sh
with the .venv's python): one event on a channel of every name and per-robot prefix of
common/include/elaslam/common/channels.hpp is counted as decoded and the run exits 0;
a corrupt event on one of them (here TEAM_MAP_2, CANDIDATES_1, LMAP_RESYNC, TRACKS_1 and
GLOBAL_TRACKS in turn)
is counted as failed and the run exits 1; a log with no elaslam channel exits 1.

    decode_log_check.py --root SRC --build BUILD --work DIR
"""
import argparse
import os
import re
import subprocess
import sys

def messages(T):
    """(channel, encoded message): one of each channel, with its type as log_summary.cpp reads it."""
    def enc(cls, **fields):
        m = cls()
        for k, v in fields.items():
            setattr(m, k, v)
        return m.encode()
    gmap = enc(T.global_map_t, frame=3, version=1, num_chunks=1, id_end=10)
    cand = T.landmark_estimate_t()
    cand.id, cand.x, cand.y, cand.cov = 7, 1.5, -2.0, [[0.1, 0.0], [0.0, 0.1]]
    track = T.track_t()
    track.id, track.x, track.y, track.vx, track.vy = 7, 1.5, -2.0, 0.5, 0.0
    track.cov, track.probabilities = [0.01, 0, 0, 0, 0.01, 0, 0, 0.04, 0, 0.04], [0.1, 0.2, 0.7]
    fused = T.global_track_t()
    fused.id, fused.x, fused.y, fused.contributors = 7, 1.5, -2.0, 3
    fused.cov, fused.probabilities = track.cov, track.probabilities
    return [
        ("SENSOR_1", enc(T.sensor_frame_t, robot_id=1, frame=3)),
        ("POSE_1", enc(T.pose_estimate_t, robot_id=1, frame=3, x=1.25)),
        ("STATUS_ROBOT_1", enc(T.node_status_t, node_kind=T.node_status_t.ROBOT, node_id=1)),
        ("TEAM_MAP_2", gmap),
        ("CANDIDATES_1", enc(T.candidate_list_t, robot_id=1, frame=3, num_candidates=1, candidates=[cand])),
        ("TRACKS_1", enc(T.track_list_t, robot_id=1, frame=3, num_chunks=1, num_tracks=1, tracks=[track])),
        ("GLOBAL_TRACKS", enc(T.global_tracks_t, frame=3, num_chunks=1, num_tracks=1, tracks=[fused])),
        ("GROUND_TRUTH", enc(T.ground_truth_t, frame=3)),
        ("LMAP_EVENT", enc(T.landmark_event_t, robot_id=1, frame=3)),
        ("LMAP_EVENTS", enc(T.lmap_events_t, robot_id=1, frame=3)),
        ("LMAP_SNAPSHOT", enc(T.lmap_snapshot_t, robot_id=1, frame=3)),
        ("LMAP_RESYNC", enc(T.resync_request_t, robot_id=1)),
        ("GLOBAL_MAP", gmap),
        ("GLOBAL_MOVING", gmap),
        ("DYNAMIC_NOTICE", enc(T.dynamic_notice_t, landmark_id=4, detected_by=1)),
        ("STATUS_MAIN", enc(T.node_status_t, node_kind=T.node_status_t.MAIN)),
        ("STATUS_SIM", enc(T.node_status_t, node_kind=T.node_status_t.SIMULATOR)),
        ("RUN_INFO", enc(T.run_info_t, source="test", scenario="made up", frames=3)),
    ]


def write_log(lcm, path, events):
    log = lcm.EventLog(path, "w", overwrite=True)
    for i, (ch, data) in enumerate(events):
        log.write_event(1_700_000_000_000_000 + i, ch, data)
    log.close()


def decode(a, path):
    p = subprocess.run([sys.executable, os.path.join(a.root, "tools", "decode_log.py"), path, "--build-dir", a.build],
                       capture_output=True, text=True, timeout=120)
    return p.returncode, p.stdout, p.stderr


def counts(out):
    """{channel: (decoded, failed)} from decode_log.py's per-channel lines."""
    got = {}
    for line in out.splitlines():
        m = re.fullmatch(r"(\S+)\s+(\d+) decoded(?:, (\d+) failed)?", line)
        if m:
            got[m.group(1)] = (int(m.group(2)), int(m.group(3) or 0))
    return got


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--root", required=True)
    ap.add_argument("--build", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    import lcm
    sys.path.insert(0, os.path.join(a.build, "lcmgen", "python"))
    import elaslam as T

    fails = []
    events = messages(T)
    good = os.path.join(a.work, "all.lcmlog")
    write_log(lcm, good, events)
    rc, out, err = decode(a, good)
    if rc != 0:
        fails.append(f"every channel decodes: exit {rc}\n{out}{err}")
    got = counts(out)
    for ch, _ in events:
        if got.get(ch) != (1, 0):
            fails.append(f"{ch}: 1 decoded expected, got {got.get(ch)}")
    for brief in ("last POSE_1: frame 3, x 1.250", "run info: source test, scenario made up",
                  "last GLOBAL_TRACKS chunk: frame 3, chunk 1 of 1, 1 fused tracks (0 left out)"):
        if brief not in out:
            fails.append(f"'{brief}' not in the output\n{out}")

    for ch in ("TEAM_MAP_2", "CANDIDATES_1", "LMAP_RESYNC", "TRACKS_1", "GLOBAL_TRACKS"):
        bad = os.path.join(a.work, f"bad_{ch}.lcmlog")
        write_log(lcm, bad, events + [(ch, b"\x00" * 40)])
        rc, out, err = decode(a, bad)
        if rc != 1 or counts(out).get(ch) != (1, 1):
            fails.append(f"a corrupt {ch} event: exit 1 and '1 decoded, 1 failed' expected, got {rc}\n{out}{err}")

    other = os.path.join(a.work, "other.lcmlog")
    write_log(lcm, other, [("LCM_SELF_TEST", b"hello")])
    rc, out, err = decode(a, other)
    if rc != 1 or "no events on elaslam channels" not in err:
        fails.append(f"a log without elaslam channels: exit 1 expected, got {rc}\n{err}")

    for f in fails:
        print(f"FAIL: {f}")
    if fails:
        return 1
    print(f"decode_log_check: {len(events)} channels decoded, corrupt events on 3 counted as failed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
