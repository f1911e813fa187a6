#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# sensor_driver end to end: two seconds of readings at 10 Hz published into an LCM
# log (LCM's file:// provider, no network), read back by log_info: 21 frames on
# SENSOR_2 (the last flushed at the end of the input); a bad command line exits 2.
#   tests/examples/sensor_driver_log.sh BUILD_DIR
set -euo pipefail
BIN="$(cd "${1:?usage: sensor_driver_log.sh BUILD_DIR}" && pwd)/bin"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
python3 - > "$OUT/readings.txt" <<'PY'
import math
for i in range(200):  # odometry at 100 Hz, a tag every 50 ms, 2 s
    t = 1000.0 + 0.01 * i
    print(f"odom {t:.3f} {0.2 * 0.01 * i:.4f} 0 {0.1 * 0.01 * i:.4f}")
    if i % 5 == 2:
        print(f"det {t + 0.001:.3f} {3 + i % 2} {2.0 + 0.001 * i:.4f} {math.sin(i):.4f}")
print("odom 1002.000 0.4 0 0.2")
PY
out="$("$BIN/sensor_driver" --robot 2 --input "$OUT/readings.txt" --lcm-url "file://$OUT/run.lcmlog?mode=w")"
echo "$out"
grep -q "^sensor_driver: 21 frames on SENSOR_2 (1 empty, 0 before any odometry), 40 detections" <<<"$out" ||
  { echo "FAIL: unexpected summary"; exit 1; }
info="$("$BIN/log_info" --json "$OUT/run.lcmlog")"
python3 - "$info" <<'PY'
import json, sys
j = json.loads(sys.argv[1])
chans = {c["name"]: c for c in j["channels"]}
assert list(chans) == ["SENSOR_2"], chans.keys()
s = chans["SENSOR_2"]
assert s["count"] == 21 and s["type"] == "sensor_frame_t" and s["decode_errors"] == 0, s
print("sensor_driver_log: SENSOR_2 holds", chans["SENSOR_2"]["count"], "frames")
PY
set +e
"$BIN/sensor_driver" --robot 0 --input "$OUT/readings.txt" > /dev/null 2>&1; rc=$?
set -e
[ "$rc" -eq 2 ] || { echo "FAIL: --robot 0 exited $rc, expected 2"; exit 1; }
"$BIN/sensor_driver" --robot 1 --input "$OUT/missing.txt" > /dev/null 2>&1 && { echo "FAIL: a missing input was accepted"; exit 1; }
echo "sensor_driver_log: passed"
