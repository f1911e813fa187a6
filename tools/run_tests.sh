#!/usr/bin/env bash
# The test command: set-up (installs what is missing), build, run every test.
#   tools/run_tests.sh [--sanitize] [-L LABEL | -LE LABEL] ...   (extra args go to ctest)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="$ROOT/build"
SETUP_ARGS=()
if [ "${1:-}" = "--sanitize" ]; then
  BUILD_DIR="$ROOT/build-sanitize"; SETUP_ARGS=(--sanitize --no-python); shift
fi
"$ROOT/tools/setup.sh" --build-dir "$BUILD_DIR" "${SETUP_ARGS[@]}"
cmake --build "$BUILD_DIR" -j "$(nproc)"
cd "$BUILD_DIR"
ctest --output-on-failure -j "$(nproc)" "$@"
