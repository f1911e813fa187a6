#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Cross-build elaslam for arm64 (a robot's Raspberry Pi 4/5, Jetson, ...) on an amd64
# Debian bookworm machine, with Debian's multiarch toolchain, and check or package it.
#
#   tools/cross_arm64.sh [--build-dir DIR] [--targets "T..."] [--packages] [--smoke] [--setup-only]
#
#   --build-dir DIR  the cross build (default: build-arm64); its sysroot/ holds the
#                    unpacked arm64 LCM and yaml-cpp (see below)
#   --targets "T..." build only these targets (default: every program)
#   --packages       then the Debian packages, arm64, into DIR/packages (cpack -G DEB)
#   --smoke          then run the arm64 robot_node --version and a short in-process
#                    team (run_scenario, 20 frames) under qemu-user
#   --setup-only     install and unpack what the cross build needs, then stop
#
# Set-up (as root; idempotent): dpkg --add-architecture arm64; crossbuild-essential-arm64
# and qemu-user-static; the Multi-Arch: same libraries as :arm64 packages
# (libsodium-dev, libsystemd-dev, libcpp-httplib-dev, libglib2.0-0, libstdc++6). LCM
# and yaml-cpp (liblcm1, liblcm-dev, libyaml-cpp0.7, libyaml-cpp-dev) are not Multi-Arch:
# same in bookworm, so installing their :arm64 packages would remove the machine's own:
# their .debs are downloaded (apt-get download) and unpacked into DIR/sysroot, which
# cmake/toolchain-aarch64.cmake searches too.
#
# Depends: of the arm64 packages: dpkg-shlibdeps on the arm64 programs, as for the
# native packages, with the unpacked packages' own shlibs files as debian/shlibs.local
# (dpkg's database does not know them); passed to CPack (ELASLAM_CROSS_DEPENDS_<C>).
#
# Exit 77 when the toolchain cannot be set up (not root and something is missing, or
# apt cannot reach Debian's archive): the test (tests/packaging) skips.
set -euo pipefail
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
PROG="$(basename "$0")"
BUILD="$ROOT/build-arm64"
TARGETS=""
PACKAGES=0
SMOKE=0
SETUP_ONLY=0
while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) BUILD="$2"; shift 2 ;;
    --targets) TARGETS="$2"; shift 2 ;;
    --packages) PACKAGES=1; shift ;;
    --smoke) SMOKE=1; shift ;;
    --setup-only) SETUP_ONLY=1; shift ;;
    -h|--help) sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "$PROG: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
mkdir -p "$BUILD"
BUILD="$(cd "$BUILD" && pwd)"
SYSROOT="$BUILD/sysroot"
TRIPLET=aarch64-linux-gnu
cannot() { echo "$PROG: cannot set up the arm64 toolchain: $*" >&2; exit 77; }
say() { echo "$PROG: $*" >&2; }

# ---- set-up ---------------------------------------------------------------------------
HOST_PKGS=(crossbuild-essential-arm64 qemu-user-static dpkg-dev)
ARM_PKGS=(libsodium-dev:arm64 libsystemd-dev:arm64 libcpp-httplib-dev:arm64 libglib2.0-0:arm64 libstdc++6:arm64)
UNPACKED=(liblcm1 liblcm-dev libyaml-cpp0.7 libyaml-cpp-dev)
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"
  elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then sudo "$@"
  else cannot "not root (needs: $*)"; fi
}
setup() {
  local missing=() p updated=0
  if ! dpkg --print-foreign-architectures | grep -qx arm64; then
    say "adding the arm64 architecture to dpkg"
    as_root dpkg --add-architecture arm64
    as_root apt-get update -qq || cannot "apt-get update failed"
    updated=1
  fi
  for p in "${HOST_PKGS[@]}" "${ARM_PKGS[@]}"; do installed "$p" || missing+=("$p"); done
  if [ ${#missing[@]} -gt 0 ]; then
    say "installing ${missing[*]}"
    [ "$updated" -eq 1 ] || as_root apt-get update -qq || cannot "apt-get update failed"
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" \
      > "$BUILD/apt.log" 2>&1 || { tail -20 "$BUILD/apt.log" >&2; cannot "apt-get install ${missing[*]} failed"; }
  fi
  # The unpacked ones: the version apt would install, for arm64.
  local stamp="$SYSROOT/.packages" want=""
  for p in "${UNPACKED[@]}"; do want+="$p=$(apt-cache policy "$p:arm64" | awk '/Candidate:/ {print $2}') "; done
  if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
    say "unpacking arm64 ${UNPACKED[*]} into $SYSROOT"
    rm -rf "$SYSROOT" "$BUILD/debs"
    mkdir -p "$SYSROOT" "$BUILD/debs"
    (cd "$BUILD/debs" && apt-get download -q "${UNPACKED[@]/%/:arm64}" > "$BUILD/download.log" 2>&1) ||
      { cat "$BUILD/download.log" >&2; cannot "apt-get download ${UNPACKED[*]} (arm64) failed"; }
    local d
    : > "$SYSROOT/shlibs"
    for d in "$BUILD"/debs/*.deb; do
      dpkg-deb -x "$d" "$SYSROOT"
      dpkg-deb -I "$d" shlibs >> "$SYSROOT/shlibs" 2>/dev/null || true
    done
    echo "$want" > "$stamp"
  fi
}

setup
[ "$SETUP_ONLY" -eq 1 ] && { say "set up: $(aarch64-linux-gnu-g++ --version | head -1), $(qemu-aarch64-static --version | head -1)"; exit 0; }

# ---- configure and build ----------------------------------------------------------------
CMAKE_ARGS=(-S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release
            -DCMAKE_TOOLCHAIN_FILE="$ROOT/cmake/toolchain-aarch64.cmake" -DELASLAM_CROSS_SYSROOT="$SYSROOT"
            -DELASLAM_BUILD_TESTS=OFF -DELASLAM_BUILD_BENCH=OFF)
export ELASLAM_CROSS_SYSROOT="$SYSROOT"
t0=$SECONDS
cmake "${CMAKE_ARGS[@]}" > "$BUILD/configure.log" 2>&1 || { cat "$BUILD/configure.log" >&2; exit 1; }
JOBS="${ELASLAM_JOBS:-2}"
# shellcheck disable=SC2086
nice ninja -C "$BUILD" -j "$JOBS" $TARGETS > "$BUILD/build.log" 2>&1 || { tail -40 "$BUILD/build.log" >&2; exit 1; }
say "built ${TARGETS:-everything} for arm64 in $((SECONDS - t0)) s (-j$JOBS)"

# ---- under qemu-user ----------------------------------------------------------------------
# The arm64 loader and libc come from the :arm64 packages (or libc6-arm64-cross under
# -L); LCM and yaml-cpp from the sysroot.
QEMU=(qemu-aarch64-static -L "/usr/$TRIPLET" -E "LD_LIBRARY_PATH=$SYSROOT/usr/lib/$TRIPLET")
if [ "$SMOKE" -eq 1 ]; then
  file "$BUILD/bin/robot_node" | grep -q "ARM aarch64" || { echo "FAIL: $BUILD/bin/robot_node is not an arm64 program" >&2; exit 1; }
  out="$("${QEMU[@]}" "$BUILD/bin/robot_node" --version)" || { echo "FAIL: robot_node --version under qemu: $out" >&2; exit 1; }
  say "qemu: $out"
  t1=$SECONDS
  rm -rf "$BUILD/smoke"
  "${QEMU[@]}" "$BUILD/bin/run_scenario" --config "$ROOT/config/paper.yaml" --frames 20 --out "$BUILD/smoke" \
    > "$BUILD/smoke.log" 2>&1 || { cat "$BUILD/smoke.log" >&2; echo "FAIL: run_scenario under qemu" >&2; exit 1; }
  [ -s "$BUILD/smoke/metrics.json" ] || { echo "FAIL: no metrics.json from the arm64 run_scenario" >&2; exit 1; }
  say "qemu: run_scenario, 20 frames, in $((SECONDS - t1)) s: $(tail -1 "$BUILD/smoke.log")"
fi

# ---- Debian packages --------------------------------------------------------------------
if [ "$PACKAGES" -eq 1 ]; then
  # Depends per component, from its programs (dpkg-shlibdeps, as CPack does natively).
  deps() { # PROGRAMS...: the shlibs:Depends of these arm64 programs
    local w="$BUILD/shlibdeps"
    rm -rf "$w"; mkdir -p "$w/debian"
    printf 'Source: elaslam\n\nPackage: elaslam\nArchitecture: arm64\n' > "$w/debian/control"
    cp "$SYSROOT/shlibs" "$w/debian/shlibs.local"
    (cd "$w" && DEB_HOST_ARCH=arm64 dpkg-shlibdeps -l"$SYSROOT/usr/lib/$TRIPLET" -O "$@" 2>"$w/err") |
      sed -n 's/^shlibs:Depends=//p' || { cat "$w/err" >&2; exit 1; }
  }
  b="$BUILD/bin"
  DEP_ARGS=(-DELASLAM_CROSS_DEPENDS_COMMON="$(deps "$b/keys")"
            -DELASLAM_CROSS_DEPENDS_ROBOT="$(deps "$b/robot_node")"
            -DELASLAM_CROSS_DEPENDS_MAIN="$(deps "$b/main_robot")"
            -DELASLAM_CROSS_DEPENDS_SIMULATOR="$(deps "$b/simulator" "$b/scenario_dump")")
  tools=()
  for t in run_scenario evaluate sweep run_dataset mrclam_import mrclam_stats log_info log_merge monitor viewer record; do
    [ -x "$b/$t" ] && tools+=("$b/$t")
  done
  DEP_ARGS+=(-DELASLAM_CROSS_DEPENDS_TOOLS="$(deps "${tools[@]}")")
  cmake "${CMAKE_ARGS[@]}" "${DEP_ARGS[@]}" > "$BUILD/configure.log" 2>&1 || { cat "$BUILD/configure.log" >&2; exit 1; }
  (cd "$BUILD" && cpack -G DEB) > "$BUILD/cpack.log" 2>&1 || { tail -30 "$BUILD/cpack.log" >&2; exit 1; }
  errors=0
  for d in "$BUILD"/packages/*.deb; do
    say "$(basename "$d"): $(dpkg-deb -f "$d" Architecture), Depends: $(dpkg-deb -f "$d" Depends)"
    # lintian as for the native packages (tests/packaging/package_check.sh): no E: line,
    # the localhost Maintainer's two tags aside while it is the default.
    if command -v lintian >/dev/null 2>&1; then
      out="$(lintian --no-cfg --allow-root --suppress-tags bogus-mail-host,bogus-mail-host-in-debian-changelog "$d" 2>&1 || true)"
      say "  lintian: $(grep -c '^E: ' <<<"$out") E, $(grep -c '^W: ' <<<"$out") W"
      grep '^E: ' <<<"$out" >&2 && errors=$((errors + 1))
    fi
  done
  [ "$errors" -eq 0 ] || { echo "FAIL: lintian E: lines in $errors arm64 packages (above)" >&2; exit 1; }
fi
