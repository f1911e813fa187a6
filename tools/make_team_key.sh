#!/bin/sh
# Make a team key for message authentication (docs/security.md): 32 random bytes
# from the kernel's generator, written as 64 hexadecimal characters and a newline to
# PATH, readable by its owner only (mode 0600). Never overwrites: an existing PATH
# (a file, a directory, a symbolic link, even a dangling one) is refused, and the
# key is never written through a link. The key is not printed.
#   tools/make_team_key.sh PATH        (installed: elaslam-make-team-key PATH)
#   tools/make_team_key.sh --version | -h | --help
# Every computer of one team needs the same key: copy it securely (docs/deployment.md).
# Exit status: 0 made, 1 not made (said why), 2 bad arguments.
set -eu
PROG="$(basename "$0")"
HERE="$(dirname "$0")"
case "${1:-}" in
  -h|--help) sed -n '2,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
  --version)  # "<prog> (elaslam <version>, git <commit>)": installed beside bin/, else the build's
    for f in "$HERE/../share/elaslam/VERSION" "${ELASLAM_BUILD_DIR:-$HERE/../build}/share/elaslam/VERSION"; do
      [ -f "$f" ] && { echo "${PROG%.sh} ($(cat "$f"))"; exit 0; }
    done
    echo "${PROG%.sh} (elaslam, version unknown: no build's share/elaslam/VERSION)"; exit 0 ;;
  --) shift ;;
  -*) echo "$PROG: unknown option '$1' (see --help)" >&2; exit 2 ;;
  "") echo "$PROG: give the key file to make: $PROG PATH (see --help)" >&2; exit 2 ;;
esac
[ $# -eq 1 ] || { echo "$PROG: one argument, the key file to make (see --help)" >&2; exit 2; }
key="$1"
if [ -e "$key" ] || [ -L "$key" ]; then
  echo "$PROG: $key exists; a key is never overwritten (remove it first to make a new one)" >&2
  exit 1
fi
dir="$(dirname -- "$key")"
[ -d "$dir" ] || { echo "$PROG: no directory $dir" >&2; exit 1; }
umask 077
# Written to a new file of mktemp's (created exclusively, mode 0600) beside the key,
# then hard-linked to its name: link(2) fails when the name exists in any form (no
# race with a file or link put there meanwhile) and does not follow a link.
tmp="$(mktemp "$dir/.team.key.XXXXXX")"
trap 'rm -f "$tmp"' EXIT
od -An -tx1 -N32 /dev/urandom | tr -d ' \n' > "$tmp"
echo >> "$tmp"
[ "$(wc -c < "$tmp")" -eq 65 ] || { echo "$PROG: could not read 32 random bytes" >&2; exit 1; }
chmod 600 "$tmp"
if ! ln -T -- "$tmp" "$key" 2>/dev/null; then
  echo "$PROG: cannot create $key (it appeared meanwhile, or the directory is not writable)" >&2
  exit 1
fi
echo "$PROG: made $key (mode 0600); copy it to every computer of the team (docs/deployment.md)" >&2
