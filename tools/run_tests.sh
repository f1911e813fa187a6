#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The test command: set-up (installs what is missing, the test tools included:
# tools/setup.sh --with-test-tools), build, run every test (ctest).
#   tools/run_tests.sh [--sanitize] [CTEST ARGS...]     e.g. -L unit, -LE system, -R Ekf
# --sanitize: the same in build/sanitize with AddressSanitizer + UBSan.
# Labels: unit, golden (seeded results against tests/golden/reference), system
# (processes over LCM in network namespaces; root), package (install, Debian
# packages, systemd units), readme (every command of README.md, docs/usage.md,
# docs/results.md).
# Exit status: ctest's (0 when every test passed); 2 on a bad argument.
set -euo pipefail
case "${1:-}" in
  -h|--help) sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
esac
# The real source tree, also when started through a symbolic link (a scratch copy).
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
BUILD_DIR="$ROOT/build"
SETUP_ARGS=(--with-test-tools)
if [ "${1:-}" = "--sanitize" ]; then
  BUILD_DIR="$ROOT/build/sanitize"; SETUP_ARGS=(--sanitize --no-python); shift
fi
# ctest ignores options it does not know (and would then run everything): check them.
prev=""
for arg in "$@"; do
  case "$prev" in -L|-LE|-R|-E|-j|-I|--timeout|--repeat|--label-regex|--label-exclude|--tests-regex|--exclude-regex|--parallel)
    prev=""; continue ;; esac
  case "$arg" in
    -L|-LE|-R|-E|-j|-I|--timeout|--repeat|--label-regex|--label-exclude|--tests-regex|--exclude-regex|--parallel) prev="$arg" ;;
    -j[0-9]*|-V|-VV|-N|--verbose|--extra-verbose|--output-on-failure|--rerun-failed|--stop-on-failure|--show-only*|--schedule-random|--repeat=*|--timeout=*|--parallel=*|--no-tests=*) ;;
    *) echo "run_tests.sh: unknown argument '$arg' (see --help; ctest options: -L, -LE, -R, -E, -j, -V, --output-on-failure, ...)" >&2; exit 2 ;;
  esac
done
[ -z "$prev" ] || { echo "run_tests.sh: $prev needs a value (see --help)" >&2; exit 2; }
"$ROOT/tools/setup.sh" --build-dir "$BUILD_DIR" "${SETUP_ARGS[@]}"
cmake --build "$BUILD_DIR" -j "$(nproc)"
# The real recording for the tests that use it (data/mrclam/dataset6): fetched and
# checked once; without network or a local copy ($ELASLAM_MRCLAM_SRC) those tests
# say they were skipped.
"$ROOT/tools/get_mrclam.sh" --if-available
cd "$BUILD_DIR"
ctest --output-on-failure -j "$(nproc)" "$@"
