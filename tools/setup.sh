#!/usr/bin/env bash
# Set-up for elaslam on Debian (bookworm): installs what is missing, makes the
# Python virtual environment, configures the build in build/.
# Idempotent and fast when everything is there.
#   tools/setup.sh [--build-dir DIR] [--sanitize] [--no-python]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="$ROOT/build"
SANITIZE=OFF
PYTHON=1
while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) BUILD_DIR="$2"; shift 2 ;;
    --sanitize) SANITIZE=ON; shift ;;
    --no-python) PYTHON=0; shift ;;
    -h|--help) sed -n '2,6p' "$0"; exit 0 ;;
    *) echo "setup.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

# ---- Debian packages ----------------------------------------------------------
PKGS=(g++ cmake ninja-build pkg-config git
      liblcm-dev liblcm-bin liblcm-java libglib2.0-dev
      libeigen3-dev libyaml-cpp-dev libgtest-dev googletest libbenchmark-dev
      libcli11-dev nlohmann-json3-dev
      python3 python3-venv iproute2 procps)
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
if [ ! -f "$BUILD_DIR/build.ninja" ] || [ "$SANITIZE" = ON ] || [ "$WERROR" = ON ]; then
  cmake -S "$ROOT" -B "$BUILD_DIR" -G Ninja -DELASLAM_WERROR="$WERROR" -DELASLAM_SANITIZE="$SANITIZE" \
    $([ "$SANITIZE" = ON ] && echo -DCMAKE_BUILD_TYPE=RelWithDebInfo) >/dev/null
fi
echo "setup: ready (build dir: ${BUILD_DIR#$ROOT/})"
