#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# wait_viewer_url (tools/viewer_url.sh), under set -euo pipefail as its callers run:
#   1. a background job whose output file appears only after the first looks found
#      none (as on a loaded machine) gives its URL, and those looks say nothing;
#   2. only the "viewer: http..." line counts: an error line before it is not a URL;
#   3. a job that ends without a URL gives an empty string at once, not after every look;
#   4. a job that never says one gives an empty string after TRIES looks.
#   tests/tools/viewer_url_check.sh
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=tools/viewer_url.sh
. "$ROOT/tools/viewer_url.sh"
T="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$T"' EXIT
fail() { echo "viewer_url_check: FAIL $*" >&2; exit 1; }  # stderr: also seen from inside $(...)

# The waits between looks, counted: a sleep in this shell is one line in $T/looks
# (the jobs below call `command sleep`).
sleep() { echo look >> "$T/looks"; command sleep "$@"; }
# no_url LOG TRIES: wait_viewer_url on LOG for the job just started ($!); fails on a
# URL, prints how many waits between looks it took.
no_url() {
  local pid=$! url
  : > "$T/looks"
  url=$(wait_viewer_url "$1" "$pid" "$2")
  [ -z "$url" ] || fail "$1: gave '$url', want none"
  wc -l < "$T/looks"
}

# 1 + 2: the job makes its file only after two looks found none, an error line and
# then the URL.
: > "$T/looks"
{ until [ "$(wc -l < "$T/looks")" -ge 2 ]; do command sleep 0.05; done
  printf 'viewer: cannot open something\nviewer: http://127.0.0.1:4242/\n' > "$T/late.log"; command sleep 5; } &
pid=$!
url=$(wait_viewer_url "$T/late.log" "$pid" 2> "$T/late.err")
[ "$url" = "http://127.0.0.1:4242/" ] || fail "late file: got '$url', want http://127.0.0.1:4242/"
[ ! -s "$T/late.err" ] || fail "late file: the looks before it was there said: $(head -n 1 "$T/late.err")"
kill "$pid"
echo "viewer_url_check: a file made after $(wc -l < "$T/looks") looks: $url"

# 3: the job ends with an error line only; the wait stops when it does.
{ command sleep 0.2; echo "viewer: cannot listen on 127.0.0.1:1 (in use? another --port)" > "$T/dead.log"; } &
n=$(no_url "$T/dead.log" 1000)
[ "$n" -lt 1000 ] || fail "a job that ended was waited on for all $n looks"
echo "viewer_url_check: a job that ended without a URL: empty, after $n of 1000 looks"

# 4: a job that runs on and never says where it serves: empty after TRIES looks.
command sleep 30 &
n=$(no_url "$T/never.log" 3)
[ "$n" -eq 3 ] || fail "a job that said nothing: $n looks, want 3"
echo "viewer_url_check: a job that said nothing: empty after $n looks"
