#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test: the live team (separate processes over LCM in a private network
# namespace, recorded by lcm-logger) runs end to end, every robot publishes a pose
# for every frame, and its metrics agree with the in-process run of the same
# scenario and seed; the recorded tracks of moving landmarks (the robots' and main's
# fused ones) are scored. Exit 77 (skip) when namespaces are not available.
# With --hosts (test system_hosts): run_team.sh --hosts, one network namespace per
# process (simulator, main_robot, each robot, lcm-logger) joined by a bridge, LCM with
# TTL 1 across it, as separate onboard computers would be.
# With --team-map (test system_team_map): config/paper.yaml with the team map on
# (robot.team_map.fuse, main.team_map_period_frames 10): TEAM_MAP_<r> over LCM, held
# by each robot until its next frame, gives the in-process run's poses too.
# With --channel-groups (test system_team_groups): run_team.sh --channel-groups, one
# LCM port per channel group and one lcm-logger per group, merged (log_merge): the
# same poses, and the merged recording is as complete.
#   tests/system/team_live.sh BUILD_DIR [--hosts | --team-map | --channel-groups]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=tests/system/lib.sh
. "$ROOT/tests/system/lib.sh"
BUILD="$(cd "${1:?usage: team_live.sh BUILD_DIR [--hosts | --team-map | --channel-groups]}" && pwd)"
HOSTS="${2:-}"
needs_netns team_live
make_out team_live
CONFIG="$ROOT/config/paper.yaml"
if [ "$HOSTS" = --team-map ]; then
  CONFIG="$OUT/team_map.yaml"
  sed -e 's/^    fuse: false$/    fuse: true/' -e 's/^  team_map_period_frames: 0$/  team_map_period_frames: 10/' \
    "$ROOT/config/paper.yaml" > "$CONFIG"
  grep -q '^    fuse: true$' "$CONFIG" && grep -q '^  team_map_period_frames: 10$' "$CONFIG" ||
    { echo "team_live: could not turn the team map on in config/paper.yaml"; exit 1; }
fi
ARGS=(--config "$CONFIG" --dynamism 50 --speed 0.5 --seed 3)
# The default rate (10 Hz, 15 s): the rate is part of the scenario (motion per frame).
if [ "$HOSTS" = --hosts ]; then
  # --inside: no set-up or build (the test's build dir is used as it is); --hosts
  # makes the namespaces itself.
  "$ROOT/tools/run_team.sh" --inside --hosts --port 7699 --build-dir "$BUILD" --out "$OUT/live" "${ARGS[@]}" \
    > "$OUT/live.txt" 2>&1 || { cat "$OUT/live.txt"; exit 1; }
  grep "hosts on a bridge" "$OUT/live.txt"
elif [ "$HOSTS" = --channel-groups ]; then
  "$ROOT/tools/netns_run.sh" --port 7800 -- "$ROOT/tools/run_team.sh" --inside --channel-groups --build-dir "$BUILD" \
    --out "$OUT/live" "${ARGS[@]}" > "$OUT/live.txt" 2>&1 || { cat "$OUT/live.txt"; exit 1; }
  # Every process opened the groups; one recorder per group in use (5 + 3 robots).
  for p in simulator main_robot robot_node_1 robot_node_2 robot_node_3; do
    grep -q "LCM in channel groups" "$OUT/live/logs/$p.log" || { echo "$p: not in channel groups"; exit 1; }
  done
  [ "$(ls "$OUT/live/groups" | wc -l)" -eq 8 ] || { ls "$OUT/live/groups"; exit 1; }
  cat "$OUT/live/logs/log_merge.log"
else
  "$ROOT/tools/netns_run.sh" --port 7693 -- "$ROOT/tools/run_team.sh" --inside --build-dir "$BUILD" --out "$OUT/live" \
    "${ARGS[@]}" > "$OUT/live.txt" 2>&1 || { cat "$OUT/live.txt"; exit 1; }
fi
"$BUILD/bin/run_scenario" --out "$OUT/inproc" "${ARGS[@]}" > /dev/null
if [ "$HOSTS" = --team-map ]; then  # the robots fused the team map (their final line)
  for r in 1 2 3; do
    grep -rhE "robot_node $r: team_map chunks=[1-9][0-9]* .* fused=[1-9]" "$OUT/live" ||
      { echo "robot $r: no team map fused"; grep -rh "team_map" "$OUT/live" || true; exit 1; }
  done
fi
"$BUILD/bin/log_info" --json "$OUT/live/run.lcmlog" > "$OUT/log_info.json"
python3 - "$OUT/live" "$OUT/inproc" "$OUT/log_info.json" <<'PY'
import csv, json, math, sys
live_dir, ref_dir, info_path = sys.argv[1:4]
live, ref = (json.load(open(d + "/metrics.json")) for d in (live_dir, ref_dir))
logged = {c["name"]: c["count"] for c in json.load(open(info_path))["channels"]}
fails = []
def close(name, a, b, tol=1e-6):
    if abs(a - b) > tol:
        fails.append(f"{name}: live {a} vs in-process {b}")
# The live figures are over the frames whose GROUND_TRUTH the recorder kept: all 150
# unless lcm-logger (a 30-message queue) lost one under load, which is accounted for,
# not a failure (the in-process run has them all).
assert ref["frames"] == 150, ref["frames"]
assert live["frames"] == logged["GROUND_TRUTH"] >= 145, (live["frames"], logged["GROUND_TRUTH"])
# Every robot processed every frame: none dropped, none before it started. A POSE the
# recorder lost is accounted for the same way.
for key in ("frames_dropped", "frames_not_started"):
    if live[key] != 0:
        fails.append(f"{key}: {live[key]}")
missing = live["poses_missing_from_log"]
for r in live["robots"]:
    # Each evaluated frame without this robot's POSE is one the recorder lost.
    if not 0 <= live["frames"] - r["frames"] <= r["poses_missing_from_log"] <= 5:
        fails.append(f"robot {r['id']}: {r['frames']} poses evaluated of {live['frames']} frames, "
                     f"{r['poses_missing_from_log']} missing from the log")
# Frame by frame: each logged pose's error equals the in-process run's.
rows = lambda d: {int(row["frame"]): row for row in csv.DictReader(open(d + "/frames.csv"))}
live_rows, ref_rows = rows(live_dir), rows(ref_dir)
for k, row in live_rows.items():
    for key, value in row.items():
        if key.endswith("_error") and key.startswith("robot") and not math.isnan(float(value)):
            close(f"frame {k} {key}", float(value), float(ref_rows[k][key]))
close("precision", live["detection"]["precision"], ref["detection"]["precision"])
close("recall", live["detection"]["recall"], ref["detection"]["recall"])
if missing == 0 and live["frames"] == 150:  # whole-run figures average over the same frames only then
    for r_live, r_ref in zip(live["robots"], ref["robots"]):
        close(f"robot {r_live['id']} error_mean", r_live["error_mean"], r_ref["error_mean"])
        close(f"robot {r_live['id']} final_uncertainty", r_live["final_uncertainty"], r_ref["final_uncertainty"], 1e-9)
    close("landmark error", live["landmark_error"]["mean_euclidean"], ref["landmark_error"]["mean_euclidean"])
else:
    print(f"note: {missing} POSEs and {150 - live['frames']} GROUND_TRUTHs missing from the recording "
          "(the recorder's loss): compared frame by frame")
# The recorded tracks of moving landmarks (TRACKS_<r>, GLOBAL_TRACKS) are scored: at
# 50 % dynamism the robots track movers for most of the run.
for key in ("tracks", "global_tracks"):
    t = live.get(key)
    if t is None or t["samples"] < 100 or t["position_rms_m"] is None:
        fails.append(f"metrics.json {key}: {t}")
# Provenance: what ran, from the log and the config.
if live["config"] is None or live["config"]["scenario"]["dynamism_percent"] != 50:
    fails.append(f"metrics.json config: {live['config'] and live['config']['scenario']}")
if live["run_info"] is None or live["run_info"]["seed"] != 3 or live["mode"] != "ela":
    fails.append(f"run_info {live['run_info']}, mode {live['mode']}")
print("live:", live["landmark_error"]["mean_euclidean"], [r["error_mean"] for r in live["robots"]],
      "latency p50/p99 us:", live["latency_us"]["p50"], live["latency_us"]["p99"],
      "tracks (samples, position RMS m):", *[(live[k]["samples"], round(live[k]["position_rms_m"], 3))
                                             for k in ("tracks", "global_tracks") if live.get(k)])
if fails:
    print("\n".join(fails)); sys.exit(1)
PY
# The recording decodes in Python (PyPI lcm + the generated module), every event.
PY="$ROOT/.venv/bin/python"
if [ -x "$PY" ]; then
  "$PY" "$ROOT/tools/decode_log.py" "$OUT/live/run.lcmlog" --build-dir "$BUILD" > "$OUT/decoded.txt"
  # As many as the log holds, by the C++ reader's count (log_info.json, above): 150
  # each unless the recorder lost one (accounted for above), never fewer decoded.
  for ch in POSE_1 POSE_2 POSE_3 SENSOR_1 GROUND_TRUTH; do
    n=$(python3 -c 'import json, sys; print(next(c["count"] for c in json.load(open(sys.argv[1]))["channels"] if c["name"] == sys.argv[2]))' \
        "$OUT/log_info.json" "$ch")
    [ "$n" -ge 145 ] || { echo "python decode: only $n $ch in the log"; exit 1; }
    grep -q "^$ch  *$n decoded$" "$OUT/decoded.txt" || { echo "python decode: $ch (the log holds $n)"; cat "$OUT/decoded.txt"; exit 1; }
  done
  grep -q "^last GLOBAL_MAP chunk: frame 149" "$OUT/decoded.txt" || { cat "$OUT/decoded.txt"; exit 1; }
  # The tracks go out whole, in chunks: no TRACKS_<r> or GLOBAL_TRACKS chunk omits
  # any (a robot's pool and main's fused tracks stay within 6 chunks of 12), and the
  # chunks of a publication agree on num_chunks.
  "$PY" - "$OUT/live/run.lcmlog" "$BUILD" "$ROOT" <<'TRACKS' || exit 1
import collections, re, sys
sys.path.insert(0, sys.argv[3] + "/tools")
from elaslam_tool import load_lcm_types
import lcm
T = load_lcm_types(sys.argv[2], sys.argv[3] + "/tools/decode_log.py")
# (channel, frame, utime): one publication (its chunks share utime; main may send a
# frame's twice, with a timer's repeated map) -> [num_chunks, tracks, omitted]
pubs = collections.defaultdict(lambda: [None, 0, 0])
bad = []
for ev in lcm.EventLog(sys.argv[1], "r"):
    if ev.channel == "GLOBAL_TRACKS" or re.fullmatch(r"TRACKS_\d+", ev.channel):
        m = (T.global_tracks_t if ev.channel == "GLOBAL_TRACKS" else T.track_list_t).decode(ev.data)
        p = pubs[(ev.channel, m.frame, m.utime)]
        if p[0] not in (None, m.num_chunks):
            bad.append(f"{ev.channel} frame {m.frame}: num_chunks {m.num_chunks} against {p[0]}")
        p[0], p[1], p[2] = m.num_chunks, p[1] + m.num_tracks, max(p[2], m.num_omitted)
fused = [p for (ch, _, _), p in pubs.items() if ch == "GLOBAL_TRACKS"]
omitted = sum(p[2] for p in pubs.values())
if omitted or not fused:
    bad.append(f"{omitted} tracks omitted, {len(fused)} GLOBAL_TRACKS publications")
beyond = sum(1 for p in fused if p[1] > 12)
print(f"tracks: {len(fused)} GLOBAL_TRACKS publications, {beyond} with more than 12 fused tracks (at most "
      f"{max((p[1] for p in fused), default=0)}, in at most {max((p[0] for p in fused), default=0)} chunks; "
      f"{sum(p[1] for p in fused) / max(1, len(fused)):.1f} on average), {omitted} omitted; robots' TRACKS: at most "
      f"{max((p[1] for (ch, _, _), p in pubs.items() if ch != 'GLOBAL_TRACKS'), default=0)} tracks")
if bad:
    print("\n".join(bad)); sys.exit(1)
TRACKS
  echo "python decode: ok"
else
  echo "python decode: skipped (no .venv; tools/setup.sh makes it)"
fi
