# SPDX-License-Identifier: Apache-2.0
# Sourced by the packaging checks (tests/packaging/*_check.sh): the source tree, their
# scratch folder, and how they report.
#   SRC             the source tree
#   scratch NAME    TMP: a new folder ${TMPDIR:-/tmp}/elaslam-NAME.XXXXXX, removed at exit
#   fail MESSAGE    exit 1;   skip MESSAGE: exit 77 (ctest: skipped);   note MESSAGE: progress
#   cache VAR       VAR's value in $BUILD/CMakeCache.txt
SRC="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
scratch() {
  TMP="$(mktemp -d "${TMPDIR:-/tmp}/elaslam-$1.XXXXXX")"
  trap 'rm -rf "$TMP"' EXIT
}
fail() { echo "FAIL: $*" >&2; exit 1; }
skip() { echo "skipped: $*"; exit 77; }
note() { echo "-- $*"; }
cache() { sed -n "s/^$1:[A-Z]*=//p" "$BUILD/CMakeCache.txt"; }
