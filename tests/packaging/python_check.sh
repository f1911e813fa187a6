#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The Python message types as a package (python/pyproject.toml, docs/embedding.md;
# ctest label `package`):
#   python_check.sh BUILD_DIR VERSION
# 1. without the network: a fresh venv, `pip install --no-index --no-deps BUILD/python`
#    (the in-tree backend needs no setuptools or wheel); `import elaslam`, every type of
#    lcmtypes/*.lcm is there, a pose_estimate_t encodes and decodes; the metadata names
#    the version and the dependency on lcm; nothing written into BUILD/python
# 2. without the network, from the source tree: `pip install --no-index --no-deps
#    ./python` in a second venv (the backend runs lcm-gen on lcmtypes/*.lcm); every
#    type's fingerprint and a pose_estimate_t's bytes equal those of step 1's package;
#    nothing written into python/
# 3. with lcm from the package index: `pip install BUILD/python` (the dependency
#    resolved), a pose_estimate_t through LCM's memq:// transport
# Exit 77 (skipped) when python3 cannot make a venv, or when step 1 passed and lcm
# cannot be installed (no index reachable and no wheel in pip's find-links).
set -euo pipefail
BUILD="$(cd "${1:?usage: python_check.sh BUILD_DIR VERSION}" && pwd)"
VERSION="${2:?VERSION}"
# shellcheck source=tests/packaging/lib.sh
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
scratch py

PKG="$BUILD/python"
[ -f "$PKG/pyproject.toml" ] && [ -f "$PKG/elaslam/__init__.py" ] || fail "$PKG: not built (cmake --build: elaslam_python_package)"
command -v python3 >/dev/null 2>&1 || skip "python3 not found"
python3 -m venv "$TMP/venv" > "$TMP/venv.log" 2>&1 || { cat "$TMP/venv.log"; skip "python3 -m venv failed (Debian: python3-venv)"; }
V="$TMP/venv/bin"
before="$(cd "$PKG" && find . | sort)"

# ---- 1. no network -------------------------------------------------------------------
t0=$(date +%s)
"$V/pip" install --no-index --no-deps --disable-pip-version-check "$PKG" > "$TMP/pip1.log" 2>&1 \
  || { cat "$TMP/pip1.log"; fail "pip install --no-index --no-deps $PKG"; }
t1=$(date +%s)
note "pip install --no-index --no-deps: $((t1 - t0)) s"
types=()
for f in "$SRC"/lcmtypes/elaslam_*.lcm; do f="$(basename "$f" .lcm)"; types+=("${f#elaslam_}"); done
(cd "$TMP" && "$V/python" - "$VERSION" "${types[@]}") <<'PY' || exit 1
import sys
from importlib import metadata
import elaslam
version, types = sys.argv[1], sys.argv[2:]
missing = [t for t in types if not hasattr(elaslam, t)]
if missing:
    sys.exit(f"FAIL: elaslam lacks {missing}")
if not elaslam.__file__.startswith(sys.prefix):
    sys.exit(f"FAIL: elaslam imported from {elaslam.__file__}, not the venv")
m = elaslam.pose_estimate_t()
m.utime, m.frame, m.robot_id, m.x, m.y, m.theta = 1_000_000, 7, 3, 1.5, -2.25, 0.125
d = elaslam.pose_estimate_t.decode(m.encode())
if (d.utime, d.frame, d.robot_id, d.x, d.y, d.theta) != (1_000_000, 7, 3, 1.5, -2.25, 0.125):
    sys.exit("FAIL: pose_estimate_t does not round-trip")
md = metadata.metadata("elaslam-msgs")
if md["Version"] != version:
    sys.exit(f"FAIL: elaslam-msgs version {md['Version']}, the project's is {version}")
if "lcm" not in (metadata.requires("elaslam-msgs") or []):
    sys.exit(f"FAIL: elaslam-msgs does not require lcm: {metadata.requires('elaslam-msgs')}")
print(f"-- import elaslam: {len(types)} types, pose_estimate_t round-trips, elaslam-msgs {version} requires lcm")
PY
after="$(cd "$PKG" && find . | sort)"
[ "$before" = "$after" ] || fail "pip wrote into $PKG: $(diff <(echo "$before") <(echo "$after") || true)"

# ---- 2. pip install ./python, no network ----------------------------------------------
# What each package says of the types: fingerprints and one message's bytes.
describe() {
  (cd "$TMP" && "$1/python" - "${types[@]}") <<'PY'
import sys
import elaslam
m = elaslam.pose_estimate_t()
m.utime, m.frame, m.robot_id, m.x, m.nis, m.nis_dof = 5, 7, 3, 1.5, 12.25, 8
print(" ".join(f"{t}:{getattr(elaslam, t)._get_packed_fingerprint().hex()}" for t in sys.argv[1:]))
print(m.encode().hex())
PY
}
python3 -m venv "$TMP/venv2" > "$TMP/venv2.log" 2>&1 || { cat "$TMP/venv2.log"; fail "second venv"; }
src_before="$(cd "$SRC/python" && find . | sort)"
t0=$(date +%s)
"$TMP/venv2/bin/pip" install --no-index --no-deps --disable-pip-version-check "$SRC/python" > "$TMP/pip_src.log" 2>&1 \
  || { cat "$TMP/pip_src.log"; fail "pip install --no-index --no-deps $SRC/python"; }
note "pip install ./python (lcm-gen at install): $(( $(date +%s) - t0 )) s"
[ "$(cd "$SRC/python" && find . | sort)" = "$src_before" ] || fail "pip wrote into $SRC/python"
a="$(describe "$V")" || fail "the build tree's package: $a"
b="$(describe "$TMP/venv2/bin")" || fail "the source tree's package: $b"
[ "$a" = "$b" ] || fail "./python and build/python differ: $(diff <(echo "$a" | tr ' ' '\n') <(echo "$b" | tr ' ' '\n') || true)"
note "./python and build/python: the same ${#types[@]} fingerprints, the same bytes"

# ---- 3. with lcm ---------------------------------------------------------------------
t0=$(date +%s)
if ! "$V/pip" install --disable-pip-version-check --timeout 20 --retries 1 "$PKG" > "$TMP/pip2.log" 2>&1; then
  cat "$TMP/pip2.log"
  skip "step 1 passed; lcm could not be installed (no package index reachable): step 2 not run"
fi
t1=$(date +%s)
note "pip install (lcm from the index): $((t1 - t0)) s, $("$V/pip" show lcm 2>/dev/null | sed -n 's/^Version: /lcm /p')"
"$V/pip" check > "$TMP/check.log" 2>&1 || { cat "$TMP/check.log"; fail "pip check"; }
(cd "$TMP" && "$V/python" -) <<'PY' || exit 1
import sys
import lcm
import elaslam
got = []
lc = lcm.LCM("memq://")
lc.subscribe("POSE_3", lambda channel, data: got.append(elaslam.pose_estimate_t.decode(data)))
m = elaslam.pose_estimate_t()
m.robot_id, m.x = 3, 4.5
lc.publish("POSE_3", m.encode())
lc.handle_timeout(1000)
if len(got) != 1 or got[0].x != 4.5 or got[0].robot_id != 3:
    sys.exit(f"FAIL: pose_estimate_t through memq://: {got}")
print("-- lcm: pose_estimate_t published and received over memq://")
PY
echo "python: ok"
