# SPDX-License-Identifier: Apache-2.0
# Sourced by the launchers of LCM's Java GUIs with the elaslam message types
# (tools/spy.sh, tools/logplayer.sh) after they set HERE, their own folder (symbolic
# links resolved). Installed as bin/elaslam-spy and bin/elaslam-logplayer-gui, they
# find this file in ../share/elaslam/tools.
#   PROG          the launcher's name as started, for messages
#   die MESSAGE   "PROG: MESSAGE" on stderr, exit 1
#   version       "<prog> (elaslam <version>, git <commit>)" from the build's
#                 share/elaslam/VERSION (installed: beside bin/; source tree: BUILD_DIR,
#                 else $ELASLAM_BUILD_DIR, else <repo>/build)
#   find_lcm_jar  LCM_JAR: LCM's Java library, from pkg-config (lcm-java) or
#                 /usr/share/java/lcm.jar; the caller checks that it exists
PROG="$(basename "$0")"
die() { echo "$PROG: $*" >&2; exit 1; }

version() {
  local f
  for f in "$HERE/../share/elaslam/VERSION" "${BUILD_DIR:-${ELASLAM_BUILD_DIR:-$HERE/../build}}/share/elaslam/VERSION"; do
    [ -f "$f" ] && { echo "${PROG%.sh} ($(cat "$f"))"; return; }
  done
  echo "${PROG%.sh} (elaslam, version unknown: no build's share/elaslam/VERSION)"
}

find_lcm_jar() {
  LCM_JAR=""
  if command -v pkg-config >/dev/null 2>&1; then
    LCM_JAR="$(pkg-config --variable=classpath lcm-java 2>/dev/null || true)"
  fi
  [ -n "$LCM_JAR" ] && [ -f "$LCM_JAR" ] || LCM_JAR=/usr/share/java/lcm.jar
}
