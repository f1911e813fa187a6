#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Start LCM's log player (lcm-logplayer-gui) on Java 17, with the elaslam message
# types on the classpath: a recorded run (tools/record, lcm-logger) played back onto
# an LCM network, for lcm-spy, the viewer or live nodes to hear.
#
#   tools/logplayer.sh [--build-dir DIR] [--version] [-h|--help] [LOGPLAYER ARGS...] [LOG]
#
# Installed as elaslam-logplayer-gui (package elaslam-spy). The player's options go to
# it as they are (quoted): --lcm-url=URL, --paused, --filter=REGEX, --invert-filter,
# and the log file; any other option is refused (exit 2).
#
# Why not Debian's /usr/bin/lcm-logplayer-gui: it runs `java -server -Xincgc ...`, and
# Java 9 and later (here 17) refuse -Xincgc (the incremental CMS mode was removed,
# JEP 214): "Unrecognized option: -Xincgc. Error: Could not create the Java Virtual
# Machine". Nothing else is needed on Java 17: the player uses no reflection into the
# JDK's modules (no --add-opens; played 15 s of a log under Xvfb without an
# exception). It also passes its arguments unquoted ($*): a log path with a space broke.
# It is a GUI: it needs DISPLAY (ssh -X, or xvfb-run for a headless run).
set -euo pipefail

SELF="$(readlink -f "${BASH_SOURCE[0]}")"
HERE="$(dirname "$SELF")"

usage() {
  cat <<EOF
usage: $PROG [--build-dir DIR] [--version] [-h|--help] [--lcm-url=URL] [--paused] [--filter=REGEX] [LOG]

Start LCM's log player (a GUI) with the elaslam message types, on Java 17.

  --build-dir DIR  build directory with elaslam_types.jar (default: \$ELASLAM_BUILD_DIR,
                   else <repo>/build; installed: <prefix>/share/elaslam/java)
  --version        print the version and the source commit, then exit
  -h, --help       print this help and exit
  Other arguments go to the player: --lcm-url=URL (default \$LCM_DEFAULT_URL, else
  LCM's), --paused, --filter=REGEX, --invert-filter, and the log file.

Needs a display (DISPLAY): a desktop, ssh -X, or xvfb-run $PROG.
EOF
}
# PROG, die, version, find_lcm_jar: beside this script, or installed in ../share/elaslam/tools.
LIB="$HERE/lcm_java_lib.sh"
[ -f "$LIB" ] || LIB="$HERE/../share/elaslam/tools/lcm_java_lib.sh"
# shellcheck source=tools/lcm_java_lib.sh
. "$LIB"

BUILD_DIR=""
ARGS=()
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --version) version; exit 0 ;;
    --build-dir) [ $# -ge 2 ] && [ -n "$2" ] || { echo "$PROG: option '--build-dir' needs a value" >&2; exit 2; }
      BUILD_DIR="$2"; shift 2 ;;
    --build-dir=*) BUILD_DIR="${1#--build-dir=}"; shift ;;
    --lcm-url=*|--filter=*|--paused|--invert-filter) ARGS+=("$1"); shift ;;  # the player's own
    -*) echo "$PROG: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) ARGS+=("$1"); shift ;;  # the log file
  esac
done

[ -n "${DISPLAY:-}" ] || die "the log player is a GUI: needs a display (DISPLAY is not set); e.g. xvfb-run $0, or ssh -X"

# The types jar: a given build, an installed one beside bin/, else the source tree's build.
if [ -n "$BUILD_DIR" ]; then
  TYPES_JAR="$BUILD_DIR/elaslam_types.jar"
elif [ -f "$HERE/../share/elaslam/java/elaslam_types.jar" ] && [ ! -f "$HERE/../CMakeLists.txt" ]; then
  TYPES_JAR="$(cd "$HERE/.." && pwd)/share/elaslam/java/elaslam_types.jar"
else
  TYPES_JAR="${ELASLAM_BUILD_DIR:-$HERE/../build}/elaslam_types.jar"
fi
[ -f "$TYPES_JAR" ] || die "the message types jar $TYPES_JAR is missing (installed: apt-get install elaslam-spy; a source tree: cmake --build build --target elaslam_lcmtypes_jar, or pass --build-dir)"

JAVA="$(command -v java || true)"
[ -n "$JAVA" ] || die "no Java runtime (java) found: apt-get install default-jre"
find_lcm_jar
[ -f "$LCM_JAR" ] || die "lcm.jar (LCM's Java library with the log player) not found: apt-get install liblcm-java"

# --lcm-url from $LCM_DEFAULT_URL unless given (the player reads only its option).
have_url=0
for a in "${ARGS[@]+"${ARGS[@]}"}"; do case "$a" in --lcm-url=*) have_url=1 ;; esac; done
if [ "$have_url" -eq 0 ] && [ -n "${LCM_DEFAULT_URL:-}" ]; then ARGS=("--lcm-url=$LCM_DEFAULT_URL" "${ARGS[@]+"${ARGS[@]}"}"); fi

# As Debian's launcher, less -Xincgc and -server; IPv4 for multicast.
exec "$JAVA" -Djava.net.preferIPv4Stack=true -Xms32m -Xmx128m -ea \
  -cp "$LCM_JAR:$TYPES_JAR" lcm.logging.LogPlayer "${ARGS[@]+"${ARGS[@]}"}"
