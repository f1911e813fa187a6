#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Set-up for elaslam on Debian (bookworm): installs what is missing, makes the
# Python virtual environment, configures the build in build/.
# Idempotent and fast when everything is there.
#   tools/setup.sh [--build-dir DIR] [--sanitize] [--no-python] [--with-test-tools] [--with-spy] [--with-fuzz]
# --with-test-tools: also what the tests need beyond building and running the team
#   (Debian packaging, systemd-analyze, Xvfb, a Java runtime for lcm-spy, nftables);
#   tools/run_tests.sh passes it. --with-spy: what tools/spy.sh needs (Java, Xlibs).
#   --with-fuzz: clang and its libFuzzer runtime (tools/fuzz.sh).
set -euo pipefail
# The real source tree, also when started through a symbolic link (a scratch copy).
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
BUILD_DIR="$ROOT/build"
SANITIZE=OFF
PYTHON=1
TEST_TOOLS=0
SPY=0
FUZZ=0
while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) BUILD_DIR="$2"; shift 2 ;;
    --sanitize) SANITIZE=ON; shift ;;
    --no-python) PYTHON=0; shift ;;
    --with-test-tools) TEST_TOOLS=1; SPY=1; shift ;;
    --with-spy) SPY=1; shift ;;
    --with-fuzz) FUZZ=1; shift ;;
    -h|--help) sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "setup.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

# ---- Debian packages ----------------------------------------------------------
PKGS=(g++ cmake ninja-build pkg-config git
      liblcm-dev liblcm-bin liblcm-java libglib2.0-dev
      libeigen3-dev libyaml-cpp-dev libgtest-dev googletest libbenchmark-dev
      libcli11-dev nlohmann-json3-dev libsodium-dev libcpp-httplib-dev libsystemd-dev
      python3 python3-venv iproute2 procps)
# lcm-spy (tools/spy.sh): a JDK to build the message jar, a JRE with AWT, jchart2d.
SPY_PKGS=(openjdk-17-jdk-headless openjdk-17-jre libjchart2d-java)
# Tests beyond the build: Debian packages (cpack's dpkg-shlibdeps needs dpkg-dev and
# file), systemd-analyze for the units, Xvfb and X tools for the lcm-spy test,
# nftables for loss in a namespace, chromium and curl for the viewer test, curl and
# unzip for tools/get_mrclam.sh, lintian for the packages, the arm64 cross toolchain
# and qemu-user for package_cross_arm64 (tools/cross_arm64.sh adds the arm64
# architecture and its :arm64 libraries itself).
TEST_PKGS=(dpkg-dev file systemd xvfb x11-utils imagemagick nftables chromium curl unzip lintian
           crossbuild-essential-arm64 qemu-user-static)
[ "$SPY" -eq 1 ] && PKGS+=("${SPY_PKGS[@]}")
[ "$TEST_TOOLS" -eq 1 ] && PKGS+=("${TEST_PKGS[@]}")
# libFuzzer (tools/fuzz.sh): clang 14 and its runtime (-fsanitize=fuzzer).
FUZZ_PKGS=(clang libclang-rt-14-dev)
[ "$FUZZ" -eq 1 ] && PKGS+=("${FUZZ_PKGS[@]}")
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  if [ "$(id -u)" -eq 0 ]; then SUDO=""
  elif command -v sudo >/dev/null 2>&1; then SUDO="sudo"
  else
    echo "setup: missing packages and no root or sudo. Run as root:" >&2
    echo "  apt-get update && apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  NEW_PACKAGES=1  # e.g. a JDK: an existing build must look again (CMake finds Java at configure time)
fi

# ---- Python virtual environment (tools) -----------------------------------------
if [ "$PYTHON" -eq 1 ]; then
  VENV="$ROOT/.venv"
  REQ="$ROOT/tools/requirements.txt"
  STAMP="$VENV/.requirements.sha256"
  want="$(sha256sum "$REQ" | cut -d' ' -f1)"
  if [ ! -x "$VENV/bin/python" ] || [ "$(cat "$STAMP" 2>/dev/null)" != "$want" ]; then
    echo "setup: making the Python environment in .venv"
    PY=/usr/bin/python3; [ -x "$PY" ] || PY="$(command -v python3)"
    "$PY" -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check -r "$REQ"
    echo "$want" > "$STAMP"
  fi
fi

# ---- Configure ------------------------------------------------------------------
WERROR=OFF
[ "${CI:-}" = "true" ] && WERROR=ON
# Configure when there is no build yet or its options differ from these (a build
# configured by hand keeps its own; CI turns warnings into errors).
cache="$BUILD_DIR/CMakeCache.txt"
if [ ! -f "$BUILD_DIR/build.ninja" ] || [ -n "${NEW_PACKAGES:-}" ] || ! grep -qx "ELASLAM_SANITIZE:BOOL=$SANITIZE" "$cache" ||
   { [ "$WERROR" = ON ] && ! grep -qx "ELASLAM_WERROR:BOOL=ON" "$cache"; }; then
  cmake -S "$ROOT" -B "$BUILD_DIR" -G Ninja -DELASLAM_WERROR="$WERROR" -DELASLAM_SANITIZE="$SANITIZE" \
    $([ "$SANITIZE" = ON ] && echo -DCMAKE_BUILD_TYPE=RelWithDebInfo) >/dev/null
fi
echo "setup: ready (build dir: ${BUILD_DIR#$ROOT/})"
