#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/logplayer.sh (elaslam-logplayer-gui) starts LCM's log player on this Java
# under Xvfb and plays a small log (made here: 100 events on one channel, 5 s) on
# memq:// (no network): it loads the log ("Total seconds: 5.000000") and is still running
# after 6 s, without an exception. Debian's own launcher fails here on Java 9+
# ("Unrecognized option: -Xincgc"): shown, for the record, when it does.
# Exit 77 (skipped) without xvfb-run, java or lcm.jar (tools/setup.sh --with-test-tools).
#   tests/tools/logplayer_headless.sh BUILD_DIR
set -euo pipefail
BUILD="$(cd "${1:?usage: logplayer_headless.sh BUILD_DIR}" && pwd)"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
skip() { echo "logplayer_headless: skipped: $*"; exit 77; }
for t in xvfb-run java python3; do command -v "$t" >/dev/null || skip "'$t' is missing"; done
[ -f /usr/share/java/lcm.jar ] || skip "no /usr/share/java/lcm.jar (liblcm-java)"
[ -f "$BUILD/elaslam_types.jar" ] || skip "the build has no elaslam_types.jar (no JDK at configure time)"
TMP="$(mktemp -d "${TMPDIR:-/tmp}/elaslam-logplayer.XXXXXX")"
trap 'rm -rf "$TMP"' EXIT

# An LCM log: sync word, event number, utime [us], channel and data lengths, channel, data.
python3 - "$TMP/small.lcmlog" <<'PY'
import struct, sys
with open(sys.argv[1], "wb") as f:
    for i in range(100):
        ch, data = b"LOGPLAYER_TEST", bytes(8)
        f.write(struct.pack(">IqqII", 0xEDA1DA01, i, 1_000_000 + 50_000 * i, len(ch), len(data)) + ch + data)
PY

if command -v lcm-logplayer-gui >/dev/null && ! timeout 10 lcm-logplayer-gui --help > "$TMP/debian.log" 2>&1; then
  grep -q "Xincgc" "$TMP/debian.log" && echo "-- Debian's lcm-logplayer-gui on this Java: $(head -1 "$TMP/debian.log")"
fi

set +e
timeout 6 xvfb-run -a "$ROOT/tools/logplayer.sh" --build-dir "$BUILD" --lcm-url=memq:// "$TMP/small.lcmlog" \
  > "$TMP/player.log" 2>&1
rc=$?
set -e
cat "$TMP/player.log"
[ "$rc" -eq 124 ] || { echo "FAIL: the player exited ($rc) before 6 s"; exit 1; }
grep -q "^Total seconds: [45]\." "$TMP/player.log" || { echo "FAIL: the player did not load the log"; exit 1; }
! grep -qiE "exception|error" "$TMP/player.log" || { echo "FAIL: the player printed an exception or error"; exit 1; }
echo "PASS: elaslam-logplayer-gui ran 6 s on $(java -version 2>&1 | head -1)"
