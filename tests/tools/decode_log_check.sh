#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/decode_log.py on recordings made here (tests/tools/decode_log_check.py): every
# channel of channels.hpp decodes, corrupt events are counted as failed (exit 1).
#   tests/tools/decode_log_check.sh BUILD_DIR
# Exit 77 (skipped) when the .venv has no lcm (tools/setup.sh installs it from
# tools/requirements.txt).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="$(cd "${1:?usage: decode_log_check.sh BUILD_DIR}" && pwd)"
PY="$ROOT/.venv/bin/python"
"$PY" -c "import lcm" 2>/dev/null ||
  { echo "decode_log_check: skipped: no .venv with lcm (tools/setup.sh installs tools/requirements.txt)"; exit 77; }
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$PY" "$ROOT/tests/tools/decode_log_check.py" --root "$ROOT" --build "$BUILD" --work "$OUT"
