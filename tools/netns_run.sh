#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Run a command in a private, throw-away network namespace with LCM multicast on
# its loopback, so that LCM traffic never touches the host's real interfaces and
# parallel tests cannot hear each other.
#
#   tools/netns_run.sh [--port P] -- CMD ARGS...
#   tools/netns_run.sh --help
#
# - needs root (ip netns); otherwise prints why and exits 77 (ctest: SKIP_RETURN_CODE 77)
# - creates namespace elaslam_<pid>_<random>, brings lo up with multicast and a
#   224.0.0.0/4 route on it (LCM.md, netns recipe)
# - exports LCM_DEFAULT_URL="udpm://239.255.76.67:<P>?ttl=0&recv_buf_size=8388608"
#   (P default 7667) and runs CMD inside; every process CMD starts shares the namespace
# - deletes the namespace on exit, also on SIGINT/SIGTERM/SIGHUP (CMD gets SIGTERM
#   first), and returns CMD's exit code (128 + signal if we were signalled)
set -u

PORT=7667
# --help: the comment block above; a usage error: one line naming the problem, exit 2.
help() { sed -n '3,/^set -u/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0; }
usage_error() {
  echo "netns_run: $1" >&2
  echo "usage: tools/netns_run.sh [--port P] -- CMD [ARGS...]   (--help: details)" >&2
  exit 2
}
while [ $# -gt 0 ]; do
  case "$1" in
    --port)
      [ $# -ge 2 ] || usage_error "--port needs a value"
      PORT="$2"
      shift 2
      ;;
    --port=*) PORT="${1#--port=}"; shift ;;
    --) shift; break ;;
    -h|--help) help ;;
    -*) usage_error "unknown argument '$1'" ;;
    *) usage_error "unexpected argument '$1': the command goes after --" ;;
  esac
done
[ $# -ge 1 ] || usage_error "no command after --"
case "$PORT" in
  ''|*[!0-9]*) echo "netns_run: --port must be a number, got '$PORT'" >&2; exit 2 ;;
esac
if [ "$PORT" -lt 1 ] || [ "$PORT" -gt 65535 ]; then
  echo "netns_run: --port must be in 1..65535, got $PORT" >&2
  exit 2
fi

if [ "$(id -u)" -ne 0 ]; then
  echo "netns_run: skipped: creating a network namespace needs root (run as root or under sudo)" >&2
  exit 77
fi
if ! command -v ip >/dev/null 2>&1 || ! ip netns list >/dev/null 2>&1; then
  echo "netns_run: skipped: 'ip netns' is not available (install iproute2; a container may forbid namespaces)" >&2
  exit 77
fi

NS="elaslam_$$_${RANDOM}${RANDOM}"
CHILD=""
cleanup() {
  if [ -n "$CHILD" ] && kill -0 "$CHILD" 2>/dev/null; then
    kill -TERM "$CHILD" 2>/dev/null
    wait "$CHILD" 2>/dev/null
  fi
  ip netns del "$NS" 2>/dev/null
}
on_signal() {
  local sig=$1
  trap - EXIT INT TERM HUP
  cleanup
  exit $((128 + sig))
}
trap cleanup EXIT
trap 'on_signal 2' INT
trap 'on_signal 15' TERM
trap 'on_signal 1' HUP

if ! ip netns add "$NS"; then
  echo "netns_run: skipped: 'ip netns add $NS' failed (no permission for namespaces here?)" >&2
  exit 77
fi
if ! { ip netns exec "$NS" ip link set lo up &&
       ip netns exec "$NS" ip link set lo multicast on &&
       ip netns exec "$NS" ip route add 224.0.0.0/4 dev lo; }; then
  echo "netns_run: could not set up loopback multicast in $NS" >&2
  exit 1
fi

export LCM_DEFAULT_URL="udpm://239.255.76.67:${PORT}?ttl=0&recv_buf_size=8388608"
# In the background so that the traps run while CMD is going; `ip netns exec`
# execs CMD in place, so $CHILD is CMD itself.
ip netns exec "$NS" "$@" <&0 &
CHILD=$!
wait "$CHILD"
RC=$?
CHILD=""
exit "$RC"
