#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The viewer's /state.json against the log it was shown (system_viewer): the last
POSE_<r> of each robot, the GLOBAL_MAP assembled from its chunks (each chunk stands
for its id range), the chunks of the newest TRACKS_<r> frame of each robot and of the newest
GLOBAL_TRACKS frame (when at most 20 frames old) and the highest frame, all as the viewer must have drawn them.

    viewer_check.py --build-dir DIR LOG STATE_JSON
Exit 0 when they agree, 1 (saying what differs) when not.
"""
import json
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..", "tools"))
from elaslam_tool import load_lcm_types  # noqa: E402  (finds the generated message types)
import lcm  # noqa: E402


def add_chunk(held, m):
    """(frame, {landmark ids}, utime) of a tracks publication's chunks so far, with
    chunk m added: a newer publication (frame, then utime: main may send a frame's
    GLOBAL_TRACKS twice) starts over, an older one is ignored."""
    if held is None or (m.frame, m.utime) > (held[0], held[2]):
        held = (m.frame, set(), m.utime)
    if (m.frame, m.utime) == (held[0], held[2]):
        held[1].update(t.id for t in m.tracks)
    return held


def main():
    args = sys.argv[1:]
    build = args[args.index("--build-dir") + 1]
    log_path, state_path = [a for i, a in enumerate(args) if a != "--build-dir" and (i == 0 or args[i - 1] != "--build-dir")]
    T = load_lcm_types(build, __file__)
    poses, lms, moving, frame = {}, {}, set(), -1
    tracks, fused = {}, None
    for ev in lcm.EventLog(log_path, "r"):
        if re.fullmatch(r"POSE_\d+", ev.channel):
            p = T.pose_estimate_t.decode(ev.data)
            poses[p.robot_id] = p
            frame = max(frame, p.frame)
        elif ev.channel == "GLOBAL_MAP":
            m = T.global_map_t.decode(ev.data)
            for i in range(m.id_begin, m.id_end):
                lms.pop(i, None)
                moving.discard(i)
            for l in m.landmarks:
                lms[l.id] = l
                if l.status == T.global_landmark_t.MOVING:
                    moving.add(l.id)
            moving.update(m.moving_ids)
            frame = max(frame, m.frame)
        elif re.fullmatch(r"TRACKS_\d+", ev.channel):
            t = T.track_list_t.decode(ev.data)
            tracks[t.robot_id] = add_chunk(tracks.get(t.robot_id), t)
            frame = max(frame, t.frame)
        elif ev.channel == "GLOBAL_TRACKS":
            g = T.global_tracks_t.decode(ev.data)
            fused = add_chunk(fused, g)
            frame = max(frame, g.frame)
        elif ev.channel == "GROUND_TRUTH":
            frame = max(frame, T.ground_truth_t.decode(ev.data).frame)
    state = json.load(open(state_path))
    bad = []
    if state["frame"] != frame:
        bad.append(f"frame {state['frame']} against the log's {frame}")
    robots = {r["id"]: r for r in state["robots"] if r.get("x") is not None}
    if set(robots) != set(poses):
        bad.append(f"robots {sorted(robots)} against the log's {sorted(poses)}")
    for rid, p in poses.items():
        r = robots.get(rid)
        if r and max(abs(r["x"] - p.x), abs(r["y"] - p.y), abs(r["theta"] - p.theta)) > 1e-9:
            bad.append(f"robot {rid}: ({r['x']}, {r['y']}, {r['theta']}) against ({p.x}, {p.y}, {p.theta})")
    drawn = {l["id"]: l for l in state["landmarks"]}
    static_ids = {i for i in lms if i not in moving}
    drawn_static = {i for i, l in drawn.items() if l["status"] == "static"}
    if drawn_static != static_ids:
        bad.append(f"static landmarks {sorted(drawn_static ^ static_ids)} differ")
    drawn_moving = {i for i, l in drawn.items() if l["status"] == "moving"}
    if not drawn_moving <= moving:
        bad.append(f"landmarks drawn moving that the map does not say move: {sorted(drawn_moving - moving)}")
    for i in static_ids & set(drawn):
        if max(abs(drawn[i]["x"] - lms[i].x), abs(drawn[i]["y"] - lms[i].y)) > 1e-9:
            bad.append(f"landmark {i} at ({drawn[i]['x']}, {drawn[i]['y']}) against ({lms[i].x}, {lms[i].y})")
    def ids(held):
        return sorted(held[1]) if held is not None and frame - held[0] <= 20 else []
    for rid, r in robots.items():
        want = ids(tracks.get(rid))
        if sorted(t["id"] for t in r.get("tracks", [])) != want:
            bad.append(f"robot {rid}: tracks {[t['id'] for t in r.get('tracks', [])]} against the log's {want}")
    if sorted(t["id"] for t in state["global_tracks"]) != ids(fused):
        bad.append(f"fused tracks {[t['id'] for t in state['global_tracks']]} against the log's {ids(fused)}")
    print(f"viewer_check: frame {frame}, {len(poses)} robots, {len(static_ids)} static and {len(drawn_moving)} "
          f"moving landmarks drawn ({len(moving)} moving in the map)")
    for b in bad:
        print("viewer_check: MISMATCH " + b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
