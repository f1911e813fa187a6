#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Start lcm-spy with the elaslam message types, so that every channel of the team
# (SENSOR_<r>, POSE_<r>, GLOBAL_MAP, ...) is decoded field by field.
#
#   tools/spy.sh [--lcm-url URL] [--build-dir DIR] [--version] [-h|--help]
#
#   --lcm-url URL    the LCM network to watch (default: $LCM_DEFAULT_URL, else
#                    LCM's default udpm://239.255.76.67:7667)
#   --build-dir DIR  the build whose elaslam_types.jar to use (default:
#                    $ELASLAM_BUILD_DIR, else <repo>/build); installed, it only
#                    points at another jar (no build)
#
# From a source tree it runs tools/setup.sh --with-spy when Java, jchart2d or lcm.jar
# is missing or the build directory is not configured (quietly; it installs the
# packages), then builds the jar target (elaslam_lcmtypes_jar). Installed (as
# elaslam-spy from the elaslam-tools package; no CMakeLists.txt next to the script)
# it uses <prefix>/share/elaslam/java/elaslam_types.jar and installs or builds
# nothing.
#
# Debian's own `lcm-spy` launcher passes -Xincgc, which Java 17 refuses ("Unrecognized
# option: -Xincgc"), so this script starts lcm.spy.Spy with java directly instead.
# lcm-spy is a GUI: it needs DISPLAY (ssh -X, or xvfb-run for a headless run).
set -euo pipefail

SELF="$(readlink -f "${BASH_SOURCE[0]}")"
HERE="$(dirname "$SELF")"

usage() {
  cat <<EOF
usage: $PROG [--lcm-url URL] [--build-dir DIR] [--version] [-h|--help]

Start lcm-spy (a GUI) with the elaslam message types.

  --lcm-url URL    LCM URL to watch (default: \$LCM_DEFAULT_URL, else LCM's default
                   udpm://239.255.76.67:7667)
  --build-dir DIR  build directory with elaslam_types.jar (default: \$ELASLAM_BUILD_DIR,
                   else <repo>/build); from a source tree the jar is built there first
  --version        print the version and the source commit, then exit
  -h, --help       print this help and exit

Needs a display (DISPLAY): run it on a desktop, over ssh -X, or headless with
xvfb-run $PROG.
EOF
}
bad_arg() { echo "$PROG: $*" >&2; echo "see $PROG --help" >&2; exit 2; }
# PROG, die, version, find_lcm_jar: beside this script, or installed in ../share/elaslam/tools.
LIB="$HERE/lcm_java_lib.sh"
[ -f "$LIB" ] || LIB="$HERE/../share/elaslam/tools/lcm_java_lib.sh"
# shellcheck source=tools/lcm_java_lib.sh
. "$LIB"

URL=""
URL_SET=0
BUILD_DIR=""
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --version) version; exit 0 ;;
    --lcm-url|--build-dir)
      [ $# -ge 2 ] && [ -n "$2" ] || bad_arg "option '$1' needs a value"
      if [ "$1" = --lcm-url ]; then URL="$2"; URL_SET=1; else BUILD_DIR="$2"; fi
      shift 2 ;;
    --lcm-url=*) URL="${1#--lcm-url=}"; URL_SET=1
      [ -n "$URL" ] || bad_arg "option '--lcm-url' needs a value"; shift ;;
    --build-dir=*) BUILD_DIR="${1#--build-dir=}"
      [ -n "$BUILD_DIR" ] || bad_arg "option '--build-dir' needs a value"; shift ;;
    *) bad_arg "unknown argument '$1'" ;;
  esac
done
if [ "$URL_SET" -eq 0 ] && [ -n "${LCM_DEFAULT_URL:-}" ]; then
  URL="$LCM_DEFAULT_URL"
fi

if [ -z "${DISPLAY:-}" ]; then
  die "lcm-spy is a GUI: needs a display (DISPLAY is not set); e.g. xvfb-run $0, or ssh -X to this machine"
fi

# ---- the message types jar ----------------------------------------------------------
if [ -f "$HERE/../CMakeLists.txt" ]; then
  # Source tree: set-up (idempotent), then build the jar target.
  ROOT="$(cd "$HERE/.." && pwd)"
  BUILD_DIR="${BUILD_DIR:-${ELASLAM_BUILD_DIR:-$ROOT/build}}"
  LOG="$(mktemp)"
  trap 'rm -f "$LOG"' EXIT
  # The set-up when something is missing: a Java runtime with AWT, a JDK, lcm.jar,
  # jchart2d, or a configured build. Not otherwise: under CI=true setup.sh configures
  # an existing build again with its own options (it would turn a sanitizer build's
  # -DELASLAM_SANITIZE off, for instance), and that is not the spy's business; for the
  # same reason CI is unset for it. --no-python: lcm-spy needs no Python.
  spy_ready() {
    local j
    j="$(command -v java)" && command -v javac >/dev/null &&
      [ -e "$(dirname "$(dirname "$(readlink -f "$j")")")/lib/libawt_xawt.so" ] &&
      [ -f /usr/share/java/lcm.jar ] && [ -f /usr/share/java/jchart2d.jar ] &&
      [ -f "$BUILD_DIR/CMakeCache.txt" ]
  }
  if ! spy_ready; then
    if ! env -u CI "$ROOT/tools/setup.sh" --with-spy --no-python --build-dir "$BUILD_DIR" >"$LOG" 2>&1; then
      cat "$LOG" >&2
      die "tools/setup.sh --with-spy failed (above)"
    fi
  fi
  BUILD_DIR="$(cd "$BUILD_DIR" && pwd)"
  has_jar_target() {  # (grep on a variable: grep -q on the pipe would SIGPIPE cmake)
    local targets
    targets="$(cmake --build "$BUILD_DIR" --target help 2>/dev/null || true)"
    grep -q 'elaslam_lcmtypes_jar' <<<"$targets"
  }
  if ! has_jar_target; then
    # Configured before the JDK was there: configure again, CMake looks for it anew.
    cmake -S "$ROOT" -B "$BUILD_DIR" >"$LOG" 2>&1 || { cat "$LOG" >&2; die "configuring $BUILD_DIR failed (above)"; }
    has_jar_target || die "the build in $BUILD_DIR has no elaslam_lcmtypes_jar target: CMake found no JDK or /usr/share/java/lcm.jar (apt-get install openjdk-17-jdk-headless liblcm-java, then run this again)"
  fi
  if ! cmake --build "$BUILD_DIR" --target elaslam_lcmtypes_jar >"$LOG" 2>&1; then
    cat "$LOG" >&2
    die "building elaslam_types.jar in $BUILD_DIR failed (above)"
  fi
  rm -f "$LOG"
  trap - EXIT
  TYPES_JAR="$BUILD_DIR/elaslam_types.jar"
  [ -f "$TYPES_JAR" ] || die "the build did not make $TYPES_JAR"
  HOW_TO_INSTALL="tools/setup.sh --with-spy, or apt-get install"
else
  # Installed: nothing to set up or build.
  if [ -n "$BUILD_DIR" ]; then
    TYPES_JAR="$BUILD_DIR/elaslam_types.jar"
  else
    TYPES_JAR="$(cd "$HERE/.." && pwd)/share/elaslam/java/elaslam_types.jar"
  fi
  [ -f "$TYPES_JAR" ] || die "the message types jar $TYPES_JAR is missing (it comes with the elaslam-tools package: apt-get install --reinstall elaslam-tools; a package built without a JDK has none), or pass --build-dir of a build that made elaslam_types.jar"
  HOW_TO_INSTALL="apt-get install"
fi

# ---- Java runtime, lcm.jar, jchart2d --------------------------------------------------
JAVA="$(command -v java || true)"
[ -n "$JAVA" ] || die "no Java runtime (java) found: $HOW_TO_INSTALL openjdk-17-jre (or default-jre)"
JAVA_HOME_DIR="$(dirname "$(dirname "$(readlink -f "$JAVA")")")"
if [ -d "$JAVA_HOME_DIR/lib" ] && ! [ -e "$JAVA_HOME_DIR/lib/libawt_xawt.so" ]; then
  die "the Java runtime in $JAVA_HOME_DIR is headless (no AWT/X11), lcm-spy cannot open a window: $HOW_TO_INSTALL openjdk-17-jre"
fi

find_lcm_jar
[ -f "$LCM_JAR" ] || die "lcm.jar (LCM's Java library, with lcm-spy) not found: $HOW_TO_INSTALL liblcm-java"

JCHART_JAR=/usr/share/java/jchart2d.jar
if [ ! -f "$JCHART_JAR" ]; then
  JCHART_JAR="$(dpkg -L libjchart2d-java 2>/dev/null | grep -E '/jchart2d[^/]*\.jar$' | head -n1 || true)"
fi
[ -n "$JCHART_JAR" ] && [ -f "$JCHART_JAR" ] || die "jchart2d.jar (lcm-spy's charts) not found: $HOW_TO_INSTALL libjchart2d-java"

# ---- start lcm-spy ----------------------------------------------------------------------
ARGS=()
[ -n "$URL" ] && ARGS=(-l "$URL")
SHOWN_URL="$URL"
[ -n "$SHOWN_URL" ] || SHOWN_URL="LCM's default (udpm://239.255.76.67:7667)"
echo "$PROG: lcm-spy on $SHOWN_URL, types from $TYPES_JAR" >&2
# No -Xincgc (Java 17 refuses it); IPv4 for multicast; a bounded heap as Debian's launcher.
exec "$JAVA" -Djava.net.preferIPv4Stack=true -Xms64m -Xmx256m \
  -cp "$LCM_JAR:$JCHART_JAR:$TYPES_JAR" lcm.spy.Spy "${ARGS[@]}"
