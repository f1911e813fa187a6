# SPDX-License-Identifier: Apache-2.0
# Sourced by the packaging checks (tests/packaging/*_check.sh): the source tree, their
# scratch folder, and how they report.
#   SRC             the source tree
#   scratch NAME    TMP: a new folder ${TMPDIR:-/tmp}/elaslam-NAME.XXXXXX, removed at exit
#   fail MESSAGE    exit 1;   skip MESSAGE: exit 77 (ctest: skipped);   note MESSAGE: progress
#   cache VAR       VAR's value in $BUILD/CMakeCache.txt
#   CMAKE           the cmake to run: ctest's (CMAKE_COMMAND), else cmake on PATH
#   dev_files P     the files of the dev component (packaging/dev.cmake) installed under
#                   prefix P, but for the licence and changelog every package has
SRC="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
scratch() {
  TMP="$(mktemp -d "${TMPDIR:-/tmp}/elaslam-$1.XXXXXX")"
  trap 'rm -rf "$TMP"' EXIT
}
fail() { echo "FAIL: $*" >&2; exit 1; }
skip() { echo "skipped: $*"; exit 77; }
note() { echo "-- $*"; }
cache() { sed -n "s/^$1:[A-Z]*=//p" "$BUILD/CMakeCache.txt"; }
CMAKE="${CMAKE_COMMAND:-cmake}"
dev_files() {
  local p="$1" libdir incdir build_type t d f
  libdir="$(cache CMAKE_INSTALL_LIBDIR)"; incdir="$(cache CMAKE_INSTALL_INCLUDEDIR)"
  build_type="$(cache CMAKE_BUILD_TYPE | tr '[:upper:]' '[:lower:]')"
  for t in common transport robot main; do echo "$p/$libdir/libelaslam_$t.a"; done
  for d in common transport robot_node main_robot; do
    (cd "$SRC/$d/include" && find . -name '*.hpp' | sed "s#^\./#$p/$incdir/#")
  done
  for f in "$SRC"/lcmtypes/elaslam_*.lcm; do f="$(basename "$f" .lcm)"; echo "$p/$incdir/elaslam/${f#elaslam_}.hpp"; done
  for f in elaslamConfig elaslamConfigVersion elaslamTargets "elaslamTargets-${build_type:-noconfig}" lcm_library; do
    echo "$p/$libdir/cmake/elaslam/$f.cmake"
  done
  echo "$p/$libdir/pkgconfig/elaslam.pc"
}
