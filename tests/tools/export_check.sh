#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/export.py (elaslam-export: an LCM recording as a ROS 2 bag in MCAP storage).
#   tests/tools/export_check.sh BUILD_DIR unit     (test export_bag)
#   tests/tools/export_check.sh BUILD_DIR system   (test system_export_bag)
# unit: a recording made here with the generated Python types, every converter's
# output checked value by value, and bad inputs (exit 2 naming the problem).
# system: a live team run (run_team.sh in a private network namespace, 60 frames)
# exported; per-topic counts against log_info, each robot's last pose against its
# .tum file, the bag read by both the mcap and the rosbags readers, and `ros2 bag
# info` when ros2 is on PATH (tests/tools/export_check.py).
# Exit 77 (skipped) when the .venv has no rosbags or mcap (tools/setup.sh installs
# them from tools/requirements.txt) and, for system, when not root (namespaces).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="$(cd "${1:?usage: export_check.sh BUILD_DIR unit|system}" && pwd)"
MODE="${2:?usage: export_check.sh BUILD_DIR unit|system}"
PY="$ROOT/.venv/bin/python"
"$PY" -c "import rosbags, mcap" 2>/dev/null ||
  { echo "export_check: skipped: no .venv with rosbags and mcap (tools/setup.sh installs tools/requirements.txt)"; exit 77; }
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
export ELASLAM_BUILD_DIR="$BUILD"
if [ "$MODE" = system ]; then
  [ "$(id -u)" -eq 0 ] || { echo "export_check: skipped (the live team needs root for a network namespace)"; exit 77; }
  ip netns list >/dev/null 2>&1 || { echo "export_check: skipped (no ip netns)"; exit 77; }
  "$ROOT/tools/netns_run.sh" --port 7862 -- "$ROOT/tools/run_team.sh" --inside --build-dir "$BUILD" --out "$OUT/live" \
    --frames 60 --seed 2 --no-baseline --no-progress > "$OUT/live.txt" 2>&1 || { cat "$OUT/live.txt"; exit 1; }
  "$BUILD/bin/log_info" --json "$OUT/live/run.lcmlog" > "$OUT/log_info.json"
  exec "$PY" "$ROOT/tests/tools/export_check.py" system --root "$ROOT" --build "$BUILD" --work "$OUT" \
    --log "$OUT/live/run.lcmlog" --tum-dir "$OUT/live/trajectories"
fi
exec "$PY" "$ROOT/tests/tools/export_check.py" unit --root "$ROOT" --build "$BUILD" --work "$OUT"
