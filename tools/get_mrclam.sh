#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Put the UTIAS MRCLAM recording the project's real-data figures use (dataset6) at
# data/mrclam/dataset6 inside the repository, and check every file against the
# checksums in tools/mrclam_dataset6.sha256 (the copy every figure in docs/results.md and
# docs/mrclam.md was measured on).
#
#   tools/get_mrclam.sh [--from DIR] [--zip FILE] [--url URL] [--out DIR] [--check]
#                       [--if-available] [--version] [-h|--help]
#
#   (no option)     download the dataset's zip from --url and unpack it
#   --from DIR      copy from a local copy instead (DIR holds Robot1_Odometry.dat,
#                   ...); default $ELASLAM_MRCLAM_SRC when set
#   --zip FILE      unpack a zip already downloaded (MRCLAM_Dataset6.zip)
#   --url URL       where to download the zip (default below)
#   --out DIR       where to put it (default <repo>/data/mrclam/dataset6)
#   --check         only check an existing copy (exit 0 when every file matches)
#   --if-available  a quiet attempt for test set-up: never fails (exit 0), says why
#                   when it could not get the data
#
# The dataset's home is http://asrl.utias.utoronto.ca/datasets/mrclam/index.html
# (Leung, Halpern, Barfoot, Liu, "The UTIAS multi-robot cooperative localization and
# mapping dataset", IJRR 30(8), 2011). If the download fails (the page has moved,
# no network), get MRCLAM_Dataset6.zip from that page by hand and run
# `tools/get_mrclam.sh --zip MRCLAM_Dataset6.zip`. The checksums are of the
# unpacked .dat files; a copy that differs is refused (the figures would not be
# the documented ones), naming each file that differs.
#
# Exit status: 0 the data is in place and checked; 1 it could not be fetched or a
# checksum differs; 2 a bad argument.
set -euo pipefail

SELF="$(readlink -f "${BASH_SOURCE[0]}")"
HERE="$(dirname "$SELF")"
ROOT="$(cd "$HERE/.." && pwd)"
PROG="$(basename "${BASH_SOURCE[0]}")"
SUMS="$HERE/mrclam_dataset6.sha256"
DEFAULT_URL="http://asrl.utias.utoronto.ca/datasets/mrclam/data/MRCLAM_Dataset6.zip"

usage() { sed -n '3,/^set -e/p' "$SELF" | sed '$d' | sed 's/^# \{0,1\}//'; }
bad_arg() { echo "$PROG: $*" >&2; echo "see $PROG --help" >&2; exit 2; }

FROM="${ELASLAM_MRCLAM_SRC:-}"
ZIP=""
URL="$DEFAULT_URL"
OUT="$ROOT/data/mrclam/dataset6"
CHECK_ONLY=0
IF_AVAILABLE=0
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --version)
      v="$ROOT/build/share/elaslam/VERSION"
      if [ -f "$v" ]; then echo "get_mrclam ($(cat "$v"))"; else echo "get_mrclam (elaslam, version unknown: not built)"; fi
      exit 0 ;;
    --from|--zip|--url|--out)
      [ $# -ge 2 ] && [ -n "$2" ] || bad_arg "option '$1' needs a value"
      case "$1" in --from) FROM="$2" ;; --zip) ZIP="$2" ;; --url) URL="$2" ;; --out) OUT="$2" ;; esac
      shift 2 ;;
    --check) CHECK_ONLY=1; shift ;;
    --if-available) IF_AVAILABLE=1; shift ;;
    *) bad_arg "unknown argument '$1'" ;;
  esac
done

# A failure: with --if-available a note and exit 0 (the tests that need the data
# then say they were skipped), else the message and exit 1.
fail() {
  if [ "$IF_AVAILABLE" = 1 ]; then
    echo "$PROG: MRCLAM dataset6 not available ($*); the tests that need it will say they were skipped"
    exit 0
  fi
  echo "$PROG: $*" >&2
  exit 1
}

# Every file of the checksum list present in DIR with its checksum: prints the
# files that differ or are missing; status 0 when none.
verify() {
  local dir="$1" bad=0 sum name actual
  while read -r sum name; do
    [ -n "$sum" ] || continue
    if [ ! -f "$dir/$name" ]; then echo "  missing: $name"; bad=1; continue; fi
    actual="$(sha256sum "$dir/$name" | cut -d' ' -f1)"
    [ "$actual" = "$sum" ] || { echo "  differs: $name (sha256 $actual, expected $sum)"; bad=1; }
  done < "$SUMS"
  return $bad
}

if [ "$CHECK_ONLY" = 1 ]; then
  [ -d "$OUT" ] || fail "no copy at $OUT (run $PROG to get it)"
  if report="$(verify "$OUT")"; then echo "$PROG: $OUT: every file matches"; exit 0; fi
  fail "$OUT does not match the checksums:"$'\n'"$report"
fi

if [ -d "$OUT" ] && verify "$OUT" > /dev/null; then
  echo "$PROG: $OUT is in place and checked"
  exit 0
fi

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
src=""
if [ -n "$FROM" ]; then
  [ -d "$FROM" ] || fail "--from $FROM: not a directory"
  [ -f "$FROM/Robot1_Odometry.dat" ] || [ ! -d "$FROM/dataset6" ] || FROM="$FROM/dataset6"
  src="$FROM"
else
  if [ -z "$ZIP" ]; then
    command -v curl > /dev/null || fail "curl is not installed (apt-get install curl), or use --zip / --from"
    echo "$PROG: downloading $URL"
    curl -fsSL --retry 2 --connect-timeout 20 -o "$tmp/dataset.zip" "$URL" ||
      fail "could not download $URL; get MRCLAM_Dataset6.zip from http://asrl.utias.utoronto.ca/datasets/mrclam/index.html and run: $PROG --zip MRCLAM_Dataset6.zip"
    ZIP="$tmp/dataset.zip"
  fi
  [ -f "$ZIP" ] || fail "--zip $ZIP: no such file"
  command -v unzip > /dev/null || fail "unzip is not installed (apt-get install unzip)"
  unzip -q -o "$ZIP" -d "$tmp/unpacked" || fail "$ZIP: not a zip file that unzip can read"
  # The folder that holds the .dat files, wherever the zip put it.
  first="$(find "$tmp/unpacked" -name Robot1_Odometry.dat -print -quit)"
  [ -n "$first" ] || fail "$ZIP holds no Robot1_Odometry.dat: not an MRCLAM dataset"
  src="$(dirname "$first")"
fi

if ! report="$(verify "$src")"; then
  fail "$src does not match tools/mrclam_dataset6.sha256 (not dataset6, or a changed copy):"$'\n'"$report"
fi
mkdir -p "$OUT"
while read -r _ name; do cp "$src/$name" "$OUT/$name"; done < "$SUMS"
[ -f "$src/README.md" ] && cp "$src/README.md" "$OUT/README.md"
verify "$OUT" > /dev/null || fail "copying to $OUT failed"
echo "$PROG: dataset6 in $OUT ($(wc -l < "$SUMS") files, every checksum matches)"
