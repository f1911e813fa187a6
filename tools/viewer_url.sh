# SPDX-License-Identifier: Apache-2.0
# Sourced by tools/run_team.sh, tools/replay_team.sh and tests/system/viewer.sh: the
# one wait for a viewer started in the background to say where it serves.
#
#   url=$(wait_viewer_url LOG PID [TRIES])
#
# Prints the URL of the viewer's line "viewer: http://HOST:PORT/" in LOG (where its
# standard output goes) as soon as it is there. Prints nothing when process PID ends
# first, or after TRIES looks 0.1 s apart (default 50). Returns 0 either way, also
# under set -e. LOG may not exist at the first looks: a background job opens its
# output only once it is scheduled, which on a loaded machine can come after them.
wait_viewer_url() {
  local log="$1" pid="$2" tries="${3:-50}" url="" i
  for ((i = 0; i < tries; i++)); do
    [ ! -f "$log" ] || url=$(sed -n 's/^viewer: \(http[^ ]*\)$/\1/p' "$log")
    [ -z "$url" ] || break
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  printf '%s\n' "$url"
}
