#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The libraries from outside the project (docs/embedding.md; ctest label `package`).
#   embed_check.sh embed BUILD_DIR INTREE_PROGRAM
#       cmake --install --component dev into a scratch prefix: exactly the libraries,
#       headers, CMake package and pkg-config file; then examples/embed_robot configured
#       and built against it with find_package(elaslam CONFIG), and compiled again with
#       `pkg-config --cflags --libs elaslam`; both run on config/paper.yaml: ten frames,
#       a finite pose, the same output as INTREE_PROGRAM (the example built in this tree)
#   embed_check.sh superproject BUILD_DIR INTREE_PROGRAM
#       examples/embed_robot as a superproject with elaslam inside it
#       (-DELASLAM_SOURCE_DIR: add_subdirectory): configures, builds the message types
#       in its build tree (not the whole library: CI time), leaves the source tree alone
#   embed_check.sh fetchcontent BUILD_DIR INTREE_PROGRAM
#       the same with elaslam fetched by FetchContent from this clone's git repository
#       at its HEAD commit (-DELASLAM_GIT_REPOSITORY, -DELASLAM_GIT_TAG); skipped when
#       the source tree is not a git clone
# Everything happens in a temporary folder (removed at exit). Exit 77 (skipped) when a
# tool it needs is missing.
set -euo pipefail
MODE="${1:?usage: embed_check.sh embed|superproject|fetchcontent BUILD_DIR INTREE_PROGRAM}"
BUILD="$(cd "${2:?BUILD_DIR}" && pwd)"
INTREE="${3:?INTREE_PROGRAM}"
# shellcheck source=tests/packaging/lib.sh
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
EXAMPLE="$SRC/examples/embed_robot"
scratch embed
GENERATOR=()
command -v ninja >/dev/null 2>&1 && GENERATOR=(-G Ninja)

# The example's output: ten frames processed and a finite pose; prints the pose line.
check_output() { # LABEL FILE
  grep -q '^frames 10, landmarks [1-9]' "$2" || { cat "$2"; fail "$1: not ten frames with landmarks"; }
  [ "$(grep -c '^frame [0-9]: ' "$2")" -eq 10 ] || { cat "$2"; fail "$1: not ten frame lines"; }
  python3 - "$1" "$2" <<'PY' || exit 1
import math, sys
label, path = sys.argv[1:3]
pose = [float(v) for l in open(path) if l.startswith("pose ") for v in l.split()[1:]]
if len(pose) != 3 or not all(math.isfinite(v) for v in pose):
    sys.exit(f"FAIL: {label}: no finite pose: {pose}")
PY
}
# Same output as the in-tree program: identical text, else every pose within 1e-9.
same_as_intree() { # LABEL FILE
  if ! cmp -s "$2" "$TMP/intree.txt"; then
    python3 - "$1" "$2" "$TMP/intree.txt" <<'PY' || exit 1
import sys
label, a, b = sys.argv[1:4]
la, lb = open(a).read().splitlines(), open(b).read().splitlines()
def pose(lines): return [float(v) for l in lines if l.startswith("pose ") for v in l.split()[1:]]
rest = lambda lines: [l for l in lines if not l.startswith(("pose ", "sigma ", "error "))]
if rest(la) != rest(lb) or max(abs(x - y) for x, y in zip(pose(la), pose(lb))) > 1e-9:
    sys.exit(f"FAIL: {label}: output differs from the in-tree program's:\n" + open(a).read() + "---\n" + open(b).read())
PY
    note "$1: same as the in-tree program to 1e-9 (not byte for byte)"
  else
    note "$1: the in-tree program's output, byte for byte"
  fi
}

mode_embed() {
  command -v python3 >/dev/null 2>&1 || skip "python3 not found"
  [ -x "$INTREE" ] || fail "$INTREE not built (cmake --build)"
  local P="$TMP/prefix" t0 t1 libdir incdir
  libdir="$(cache CMAKE_INSTALL_LIBDIR)"; incdir="$(cache CMAKE_INSTALL_INCLUDEDIR)"
  "$CMAKE" --install "$BUILD" --prefix "$P" --component dev > "$TMP/install.log" 2>&1 \
    || { cat "$TMP/install.log"; fail "cmake --install --component dev"; }
  # ---- exactly what a consumer needs ----------------------------------------------
  {
    dev_files "$P"
    # Every package's licence and changelog (packaging/debian/copyright).
    echo "$P/share/doc/elaslam-dev/copyright"; echo "$P/share/doc/elaslam-dev/changelog.Debian.gz"
  } | sort > "$TMP/expected"
  find "$P" \( -type f -o -type l \) | sort > "$TMP/actual"
  diff "$TMP/expected" "$TMP/actual" > "$TMP/list.diff" \
    || { cat "$TMP/list.diff"; fail "the dev component: expected (<) and installed (>) files differ"; }
  note "dev component: $(wc -l < "$TMP/actual") files, $(du -sk "$P" | cut -f1) KiB ($(du -ck "$P/$libdir"/*.a | tail -1 | cut -f1) KiB of libraries)"
  for l in common transport robot main; do
    cmp -s "$P/$libdir/libelaslam_$l.a" "$BUILD/lib/libelaslam_$l.a" || fail "libelaslam_$l.a is not the built one"
  done

  "$INTREE" "$SRC/config/paper.yaml" > "$TMP/intree.txt" 2>&1 || { cat "$TMP/intree.txt"; fail "$INTREE"; }
  check_output "in-tree" "$TMP/intree.txt"
  # ---- find_package(elaslam CONFIG) -------------------------------------------------
  t0=$(date +%s)
  "$CMAKE" -S "$EXAMPLE" -B "$TMP/example" "${GENERATOR[@]}" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_FLAGS="-Wall -Wextra -Wpedantic -Werror" -DCMAKE_PREFIX_PATH="$P" > "$TMP/configure.log" 2>&1 || { cat "$TMP/configure.log"; fail "configure the example"; }
  "$CMAKE" --build "$TMP/example" > "$TMP/build.log" 2>&1 || { cat "$TMP/build.log"; fail "build the example"; }
  t1=$(date +%s)
  note "find_package: configured and built in $((t1 - t0)) s"
  "$TMP/example/embed_robot" "$SRC/config/paper.yaml" > "$TMP/find_package.txt" 2>&1 \
    || { cat "$TMP/find_package.txt"; fail "the example (find_package) failed"; }
  check_output "find_package" "$TMP/find_package.txt"
  same_as_intree "find_package" "$TMP/find_package.txt"
  # ---- pkg-config ---------------------------------------------------------------------
  if command -v pkg-config >/dev/null 2>&1; then
    local flags
    flags="$(PKG_CONFIG_PATH="$P/$libdir/pkgconfig" pkg-config --cflags --libs elaslam)" \
      || fail "pkg-config --cflags --libs elaslam"
    case " $flags " in *" -isystem $P/$incdir "*) ;; *) fail "pkg-config: no -isystem $P/$incdir in '$flags'" ;; esac
    t0=$(date +%s)
    # shellcheck disable=SC2086 # flags are words
    ${CXX:-c++} -std=c++17 -O2 -Wall -Wextra -Wpedantic -Werror "$EXAMPLE/embed_robot.cpp" -o "$TMP/embed_pc" $flags > "$TMP/pc.log" 2>&1 \
      || { cat "$TMP/pc.log"; echo "flags: $flags"; fail "compile with pkg-config's flags"; }
    t1=$(date +%s)
    "$TMP/embed_pc" "$SRC/config/paper.yaml" > "$TMP/pc.txt" 2>&1 || { cat "$TMP/pc.txt"; fail "the example (pkg-config)"; }
    check_output "pkg-config" "$TMP/pc.txt"
    same_as_intree "pkg-config" "$TMP/pc.txt"
    note "pkg-config: compiled in $((t1 - t0)) s with: $flags"
  else
    note "pkg-config: not found, that part skipped"
  fi
  grep '^pose \|^error ' "$TMP/find_package.txt" | sed 's/^/-- /'
  echo "embed: ok"
}

# elaslam inside examples/embed_robot: LABEL, elaslam's build folder under the
# superproject's, then the superproject's configure options.
mode_superproject() {
  local label="$1" sub="$2" B="$TMP/super" before after t0 t1
  shift 2
  before="$(cd "$SRC" && git status --porcelain 2>/dev/null || true)"
  t0=$(date +%s)
  "$CMAKE" -S "$EXAMPLE" -B "$B" "${GENERATOR[@]}" "$@" > "$TMP/configure.log" 2>&1 \
    || { cat "$TMP/configure.log"; fail "$label: configure with $*"; }
  # The message types and the version, built inside the superproject's tree.
  "$CMAKE" --build "$B" --target elaslam_lcmtypes_gen elaslam_version_gen > "$TMP/build.log" 2>&1 \
    || { cat "$TMP/build.log"; fail "$label: build elaslam_lcmtypes_gen in the superproject"; }
  t1=$(date +%s)
  [ -f "$B/$sub/lcmgen/cpp/elaslam/pose_estimate_t.hpp" ] || fail "$label: no generated headers in $B/$sub/lcmgen"
  [ -f "$B/$sub/share/elaslam/VERSION" ] || fail "$label: no VERSION in $B/$sub/share/elaslam"
  [ ! -e "$B/lcmgen" ] && [ ! -e "$B/bin" ] || fail "elaslam wrote into the superproject's top build folder"
  # Only the libraries: no tests, programs or install rules by default.
  # Every target of the build (not only the primary ones `--target help` shows).
  if [ ${#GENERATOR[@]} -gt 0 ]; then
    ninja -C "$B" -t targets all | sed -n 's/^\([^:]*\): .*/\1/p' > "$TMP/targets.txt"
  else
    "$CMAKE" --build "$B" --target help | sed -n 's/^\.\.\. \([^ ]*\).*/\1/p' > "$TMP/targets.txt"
  fi
  has_target() { grep -qx "$1" "$TMP/targets.txt"; }
  for t in elaslam_robot elaslam_main elaslam_transport elaslam_common embed_robot; do
    has_target "$t" || fail "$label: no target $t in the superproject"
  done
  for t in test_robot robot_node main_robot simulator run_scenario viewer; do
    ! has_target "$t" || fail "$label: target $t in the superproject (tests and programs are off there by default)"
  done
  [ ! -e "$B/$sub/packaging" ] || fail "$label: install rules (packaging/) in the superproject"
  after="$(cd "$SRC" && git status --porcelain 2>/dev/null || true)"
  [ "$before" = "$after" ] || fail "$label: the source tree changed: $after"
  note "$label: configured and built the message types in $((t1 - t0)) s"
}

# FetchContent from this clone's repository at HEAD (what is committed: a user's
# GIT_REPOSITORY URL and tag); the fetched tree must be that commit.
mode_fetchcontent() {
  command -v git >/dev/null 2>&1 || skip "git not found"
  local head
  head="$(git -C "$SRC" rev-parse --verify HEAD 2>/dev/null)" || skip "$SRC is not a git clone with a commit"
  mode_superproject fetchcontent _deps/elaslam-build -DELASLAM_GIT_REPOSITORY="$SRC" -DELASLAM_GIT_TAG="$head"
  [ "$(git -C "$TMP/super/_deps/elaslam-src" rev-parse HEAD)" = "$head" ] || fail "fetchcontent: the fetched tree is not $head"
  note "fetchcontent: elaslam $head fetched into _deps/elaslam-src"
}

case "$MODE" in
  embed) mode_embed ;;
  superproject) mode_superproject superproject elaslam -DELASLAM_SOURCE_DIR="$SRC"; echo "superproject: ok" ;;
  fetchcontent) mode_fetchcontent; echo "fetchcontent: ok" ;;
  *) echo "embed_check.sh: unknown mode '$MODE'" >&2; exit 2 ;;
esac
