#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Packaging tests (ctest label `package`; packaging/, docs/deployment.md).
#   package_check.sh install BUILD_DIR VERSION   cmake --install into a scratch prefix:
#       the exact layout, the config lookup without --config (the installed default),
#       the same metrics as the build tree, --version of every program
#   package_check.sh deb BUILD_DIR VERSION       cpack -G DEB into a scratch folder: the
#       seven packages and their contents, Depends (computed) and conffiles, dpkg -x
#       into a scratch root and run from there (as root with ip netns: a live team),
#       dpkg --root install, upgrade (conffile edits kept) and purge; lintian on every
#       package: no E: line (W: and I: are listed)
#   package_check.sh units BUILD_DIR VERSION     systemd-analyze verify and security of
#       the installed units and the real-time drop-in
# Everything happens in a temporary folder (removed at exit); the build tree gains
# only packaging/install-time/ and install_manifest*.txt, as any install does.
# Exit 77 (ctest: skipped) when a tool it needs is missing (tools/setup.sh
# --with-test-tools installs them).
set -euo pipefail
MODE="${1:?usage: package_check.sh install|deb|units BUILD_DIR VERSION}"
BUILD="$(cd "${2:?BUILD_DIR}" && pwd)"
VERSION="${3:?VERSION}"
# shellcheck source=tests/packaging/lib.sh
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
CPACK="${CPACK_COMMAND:-cpack}"
scratch pkg

need() { command -v "$1" >/dev/null 2>&1 || skip "$1 not found ($2; tools/setup.sh --with-test-tools installs it)"; }

# ---- the expected layout (docs/deployment.md), per package --------------------------
# Optional parts follow what this build has: programs whose targets exist
# (log_info, log_merge, monitor, viewer), tools/spy.sh, the lcm-spy jar (needs a JDK).
tool_programs() {
  local t
  for t in run_scenario evaluate sweep run_dataset mrclam_import mrclam_stats log_info log_merge monitor viewer record; do
    [ -x "$BUILD/bin/$t" ] && echo "$t"
  done
  return 0
}
# expected_files PACKAGE PREFIX ETC: the files (not directories) of one package,
# PREFIX the install prefix (usr for the .deb), ETC its /etc/elaslam.
expected_files() {
  local pkg="$1" p="$2" etc="$3" f t
  echo "$p/share/doc/$pkg/copyright"; echo "$p/share/doc/$pkg/changelog.Debian.gz"  # every package
  case "$pkg" in
    elaslam-common)
      echo "$etc/elaslam.yaml"; echo "$etc/elaslam.env"
      echo "$p/share/elaslam/config/paper.yaml"; echo "$p/share/elaslam/config/mrclam.yaml"
      for f in "$SRC"/lcmtypes/*.lcm; do echo "$p/share/elaslam/lcmtypes/$(basename "$f")"; done
      echo "$p/share/elaslam/systemd/realtime.conf"
      echo "$p/share/elaslam/VERSION"
      echo "$p/share/doc/elaslam/deployment.md"; echo "$p/share/doc/elaslam/security.md"
      echo "$p/bin/elaslam-keys" ;;
    elaslam-robot)
      echo "$p/bin/elaslam-robot-node"; echo "$p/lib/systemd/system/elaslam-robot@.service" ;;
    elaslam-main-robot)
      echo "$p/bin/elaslam-main-robot"; echo "$p/lib/systemd/system/elaslam-main-robot.service" ;;
    elaslam-simulator)
      echo "$p/bin/elaslam-simulator"; echo "$p/bin/elaslam-scenario-dump"
      echo "$p/lib/systemd/system/elaslam-simulator.service" ;;
    elaslam-tools)
      for t in $(tool_programs); do echo "$p/bin/elaslam-${t//_/-}"; done
      for t in plot_sweep plot_dataset plot_scenario decode_log export; do
        echo "$p/share/elaslam/tools/$t.py"; echo "$p/bin/elaslam-${t//_/-}"
      done
      echo "$p/share/elaslam/tools/elaslam_tool.py"; echo "$p/share/elaslam/tools/export_markers.py"
      echo "$p/share/elaslam/python/elaslam/__init__.py"
      for f in "$SRC"/lcmtypes/elaslam_*.lcm; do
        f="$(basename "$f" .lcm)"; echo "$p/share/elaslam/python/elaslam/${f#elaslam_}.py"
      done
      return 0 ;;
    elaslam-spy)
      echo "$p/bin/elaslam-spy"; echo "$p/bin/elaslam-logplayer-gui"; echo "$p/share/elaslam/tools/lcm_java_lib.sh"
      [ -f "$BUILD/elaslam_types.jar" ] && echo "$p/share/elaslam/java/elaslam_types.jar"
      return 0 ;;
    elaslam-dev)  # packaging/dev.cmake; tests/packaging/embed_check.sh builds against it
      dev_files "$p" ;;
  esac
}
PACKAGES=(elaslam-common elaslam-robot elaslam-main-robot elaslam-simulator elaslam-tools elaslam-dev elaslam-spy)
# The ELF programs of a tree and the build target each one comes from.
elf_programs() { # ROOT_BIN
  local f
  for f in "$1"/elaslam-*; do
    head -c 4 "$f" | grep -q ELF && echo "$f"
  done
  return 0
}
target_of() { local n; n="$(basename "$1")"; n="${n#elaslam-}"; echo "${n//-/_}"; }

# Same set of files, both sides sorted.
same_list() { # WHAT EXPECTED_FILE ACTUAL_FILE
  if ! diff <(sort -u "$2") <(sort -u "$3") > "$TMP/list.diff"; then
    echo "$1: expected (<) and actual (>) file lists differ:" >&2
    cat "$TMP/list.diff" >&2
    exit 1
  fi
}

# The config lookup and the same result as the build tree's run_scenario:
# run_check LABEL EXPECTED_CONFIG OUT_DIR -- COMMAND...
REF=""
reference_run() {
  [ -n "$REF" ] && return 0
  REF="$TMP/ref"
  "$BUILD/bin/run_scenario" --config "$SRC/config/paper.yaml" --out "$REF" > "$TMP/ref.txt" \
    || { cat "$TMP/ref.txt"; fail "build tree run_scenario"; }
}
run_check() {
  local label="$1" want_config="$2" out="$3"; shift 4
  reference_run
  "$@" --out "$out" > "$out.txt" 2>&1 || { cat "$out.txt"; fail "$label: $* failed"; }
  python3 - "$label" "$want_config" "$out/metrics.json" "$REF/metrics.json" <<'PY' || exit 1
import json, sys
label, want, got_path, ref_path = sys.argv[1:5]
got, ref = json.load(open(got_path)), json.load(open(ref_path))
if got["source"] != want:
    sys.exit(f"FAIL: {label}: read config {got['source']!r}, expected {want!r}")
# Provenance and wall-clock timing differ; every result must not.
diff = [k for k in sorted(set(got) | set(ref))
        if k not in ("command_line", "source", "timing") and got.get(k) != ref.get(k)]
if diff:
    sys.exit(f"FAIL: {label}: metrics differ from the build tree's run in {diff}")
if got["frames"] != 150 or len(got["robots"]) < 1:
    sys.exit(f"FAIL: {label}: implausible metrics (frames {got['frames']})")
print(f"-- {label}: config {want}, landmark error {got['landmark_error']['mean_euclidean']:.4f} m, "
      f"same metrics as the build tree")
PY
  cmp -s "$out/frames.csv" "$REF/frames.csv" || fail "$label: frames.csv differs from the build tree's"
  cmp -s "$out/map.csv" "$REF/map.csv" || fail "$label: map.csv differs from the build tree's"
}

# Every ELF program answers --version with exit 0 and this version.
version_check() { # BIN_DIR: every program and script answers --version with this version
  local f out n=0
  for f in $(elf_programs "$1") "$1"/elaslam-plot-* "$1/elaslam-decode-log" "$1/elaslam-export" "$1/elaslam-spy" "$1/elaslam-logplayer-gui"; do
    out="$("$f" --version 2>&1)" || fail "$f --version: exit $?: $out"
    case "$out" in
      *"(elaslam $VERSION"*) ;;
      *) fail "$f --version: '$out' does not name elaslam $VERSION" ;;
    esac
    n=$((n + 1))
  done
  [ "$n" -ge 14 ] || fail "only $n programs in $1"
  note "--version: $n programs answer 'elaslam $VERSION'"
}

# The units name the programs and /etc files of their install.
units_check() { # ROOT PREFIX ETC
  local root="$1" p="$2" etc="$3" u
  for u in elaslam-robot@.service elaslam-main-robot.service elaslam-simulator.service; do
    local f="$root$p/lib/systemd/system/$u"
    ! grep -n '@[A-Z_]*@' "$f" || fail "$u: unsubstituted @VAR@"
    grep -qx "EnvironmentFile=-$etc/elaslam.env" "$f" || fail "$u: no EnvironmentFile=-$etc/elaslam.env"
    grep -qx "DynamicUser=yes" "$f" || fail "$u: not DynamicUser"
    grep -qx "CapabilityBoundingSet=" "$f" || fail "$u: capabilities not dropped"
    ! grep -q "^CPUScheduling" "$f" || fail "$u: real-time by default"
    if [ "$etc" = /etc/elaslam ]; then
      ! grep -q "^Environment=ELASLAM_CONFIG" "$f" || fail "$u: sets ELASLAM_CONFIG for /etc"
    else
      grep -qx "Environment=ELASLAM_CONFIG=$etc/elaslam.yaml" "$f" || fail "$u: no ELASLAM_CONFIG=$etc/elaslam.yaml"
    fi
  done
  grep -q "^ExecStart=$p/bin/elaslam-robot-node --robot %i --state %S/elaslam/robot-%i/state.json " \
    "$root$p/lib/systemd/system/elaslam-robot@.service" \
    || fail "elaslam-robot@.service: ExecStart"
  grep -q "^ExecStart=$p/bin/elaslam-main-robot --state %S/elaslam/main-robot/global_map.json" \
    "$root$p/lib/systemd/system/elaslam-main-robot.service" || fail "elaslam-main-robot.service: ExecStart"
  grep -q "^StateDirectory=elaslam/robot-%i$" "$root$p/lib/systemd/system/elaslam-robot@.service" \
    || fail "elaslam-robot@.service: StateDirectory"
  note "units: paths of $p, $etc"
}

# The /etc files: the deployment config is the header and then exactly paper.yaml.
etc_check() { # ETC_DIR
  local yaml="$1/elaslam.yaml" env="$1/elaslam.env" n
  grep -q "this machine's elaslam deployment configuration" "$yaml" || fail "$yaml: no header"
  n="$(grep -c '' "$SRC/config/paper.yaml")"
  tail -n "$n" "$yaml" | cmp -s - "$SRC/config/paper.yaml" || fail "$yaml: does not end with config/paper.yaml"
  grep -qx 'LCM_DEFAULT_URL=udpm://239.255.76.67:7667?ttl=1&recv_buf_size=8388608' "$env" || fail "$env: LCM_DEFAULT_URL"
  grep -q "^  key_file: .*/keys/{sender}.key$" "$yaml" || fail "$yaml: no team.key_file (authentication on by default)"
  grep -q "^  roster_file: .*/team.yaml$" "$yaml" || fail "$yaml: no team.roster_file (authentication on by default)"
  grep -qx "  channel_groups: true" "$yaml" || fail "$yaml: no team.channel_groups: true (on in a deployment)"
  ! grep -v '^#' "$env" | grep -v '^$' | grep -v '^[A-Z_][A-Z0-9_]*=' || fail "$env: a line that is not KEY=VALUE"
}

# lintian on every package of DIR: no E: line. W: and I: lines are listed (their
# tags counted). Two errors are let through, and said, while Maintainer is the
# default elaslam@localhost (the project has no public contact yet; a site's build
# sets ELASLAM_PACKAGE_MAINTAINER, and then they count again): bogus-mail-host and
# bogus-mail-host-in-debian-changelog.
lintian_check() { # DIR
  if ! command -v lintian >/dev/null 2>&1; then
    note "lintian: skipped (not installed; tools/setup.sh --with-test-tools installs it)"
    return 0
  fi
  local deb out errors=0 suppress=""
  case "$(dpkg-deb -f "$(ls "$1"/*.deb | head -1)" Maintainer)" in
    *@localhost\>) suppress="--suppress-tags bogus-mail-host,bogus-mail-host-in-debian-changelog" ;;
  esac
  for deb in "$1"/*.deb; do
    # --no-cfg: the machine's ~/.lintianrc and /etc/lintianrc do not change the verdict.
    out="$(lintian --no-cfg --allow-root $suppress "$deb" 2>&1)" || true
    echo "$out" | grep -q '^E: ' && { echo "$out" | grep '^E: ' >&2; errors=$((errors + 1)); }
    note "lintian $(basename "$deb"): $(echo "$out" | grep -c '^E: ') E, $(echo "$out" | grep -c '^W: ') W, $(echo "$out" | grep -c '^I: ') I$(echo "$out" | grep '^[WI]: ' | awk '{print $3}' | sort | uniq -c | awk '{printf " %s%s", $2, ($1 > 1 ? "x" $1 : "")}')"
  done
  [ "$errors" -eq 0 ] || fail "lintian: E: lines in $errors packages (above)"
  [ -z "$suppress" ] || note "lintian: bogus-mail-host(-in-debian-changelog) not counted (Maintainer is the default elaslam@localhost)"
}

# =============================================================================
mode_install() {
  need python3 "metrics comparison"
  local P="$TMP/p"
  "$CMAKE" --install "$BUILD" --prefix "$P" > "$TMP/install.log" 2>&1 || { cat "$TMP/install.log"; fail "cmake --install"; }
  # The layout: exactly the union of the packages' files.
  : > "$TMP/expected"
  for pkg in "${PACKAGES[@]}"; do expected_files "$pkg" "$P" "$P/etc/elaslam" >> "$TMP/expected"; done
  find "$P" \( -type f -o -type l \) > "$TMP/actual"
  same_list "cmake --install --prefix P" "$TMP/expected" "$TMP/actual"
  note "layout: $(wc -l < "$TMP/actual") files as expected"
  # Contents: programs are the built ones, data the source's.
  for f in $(elf_programs "$P/bin"); do
    cmp -s "$f" "$BUILD/bin/$(target_of "$f")" || fail "$f is not $BUILD/bin/$(target_of "$f")"
  done
  for t in plot_sweep plot_dataset plot_scenario decode_log export; do
    for f in "$P/share/elaslam/tools/$t.py" "$P/bin/elaslam-${t//_/-}"; do
      [ -x "$f" ] || fail "$f not executable"
      # The source's text but for the first line: the system's Python 3.
      [ "$(head -1 "$f")" = "#!/usr/bin/python3" ] || fail "$f: first line $(head -1 "$f"), not #!/usr/bin/python3"
      cmp -s <(tail -n +2 "$f") <(tail -n +2 "$SRC/tools/$t.py") || fail "$f differs from tools/$t.py"
      # It starts from there: its start-up module is found in share/elaslam/tools.
      "$f" --help > "$TMP/help.txt" 2>&1 || { cat "$TMP/help.txt"; fail "$f --help"; }
    done
  done
  cmp -s "$P/share/elaslam/config/paper.yaml" "$SRC/config/paper.yaml" || fail "paper.yaml differs"
  cmp -s "$P/share/elaslam/config/mrclam.yaml" "$SRC/config/mrclam.yaml" || fail "mrclam.yaml differs"
  etc_check "$P/etc/elaslam"
  units_check "" "$P" "$P/etc/elaslam"
  version_check "$P/bin"
  # The config lookup: no --config, no $ELASLAM_CONFIG: /etc/elaslam/elaslam.yaml if
  # this machine has one (then this sub-check cannot tell), else the installed default.
  if [ -e /etc/elaslam/elaslam.yaml ]; then
    note "lookup: skipped (this machine has /etc/elaslam/elaslam.yaml, which comes first)"
  else
    run_check "installed default" "$P/share/elaslam/config/paper.yaml" "$TMP/run-default" -- \
      env -u ELASLAM_CONFIG "$P/bin/elaslam-run-scenario"
  fi
  run_check "\$ELASLAM_CONFIG" "$P/etc/elaslam/elaslam.yaml" "$TMP/run-env" -- \
    env ELASLAM_CONFIG="$P/etc/elaslam/elaslam.yaml" "$P/bin/elaslam-run-scenario"
  # A config that was asked for must exist (no silent fall-through).
  if env ELASLAM_CONFIG="$P/etc/elaslam/missing.yaml" "$P/bin/elaslam-run-scenario" > "$TMP/missing.txt" 2>&1; then
    fail "ELASLAM_CONFIG naming a missing file was accepted"
  fi
  echo "install: ok"
}

# =============================================================================
mode_deb() {
  need dpkg-deb "Debian packaging"
  need dpkg-shlibdeps "dpkg-dev: cpack computes Depends with it"
  need file "cpack finds the ELF files with it"
  need python3 "metrics comparison"
  command -v "$CPACK" >/dev/null 2>&1 || skip "cpack not found"
  local D="$TMP/debs" R="$TMP/root" arch
  arch="$(dpkg --print-architecture)"
  (cd "$BUILD" && "$CPACK" -G DEB -B "$D") > "$TMP/cpack.log" 2>&1 || { cat "$TMP/cpack.log"; fail "cpack -G DEB"; }
  local deb pkg a
  declare -A DEB
  for pkg in "${PACKAGES[@]}"; do
    a="$arch"; [ "$pkg" = elaslam-spy ] && a=all
    deb="$D/${pkg}_${VERSION}-1_${a}.deb"
    [ -f "$deb" ] || { ls -l "$D"; fail "no $deb"; }
    DEB[$pkg]="$deb"
    [ "$(dpkg-deb -f "$deb" Package)" = "$pkg" ] || fail "$deb: Package field"
    [ "$(dpkg-deb -f "$deb" Version)" = "$VERSION-1" ] || fail "$deb: Version field"
    # Contents: exactly this package's share of the layout.
    expected_files "$pkg" ./usr ./etc/elaslam > "$TMP/expected"
    dpkg-deb -c "$deb" | awk '$1 !~ /^d/ {print $6}' > "$TMP/actual"
    same_list "$pkg" "$TMP/expected" "$TMP/actual"
    note "$pkg: $(wc -l < "$TMP/actual") files, $(stat -c %s "$deb") bytes"
  done
  [ "$(ls "$D"/*.deb | wc -l)" -eq "${#PACKAGES[@]}" ] || fail "more than ${#PACKAGES[@]} packages: $(ls "$D")"
  # elaslam-dev: the -dev packages of what its static libraries and headers use, typed
  # (nothing for shlibdeps), and no other package of the team.
  local ddep; ddep="$(dpkg-deb -f "${DEB[elaslam-dev]}" Depends)"
  note "elaslam-dev Depends: $ddep"
  for want in libeigen3-dev liblcm-dev libyaml-cpp-dev libsodium-dev libsystemd-dev; do
    case ", $ddep," in *", $want"*) ;; *) fail "elaslam-dev Depends lacks $want: $ddep" ;; esac
  done
  case "$ddep" in *elaslam-*) fail "elaslam-dev depends on another package of the team: $ddep" ;; esac
  # Depends: computed from the binaries, plus elaslam-common of this version.
  for pkg in elaslam-robot elaslam-main-robot elaslam-simulator elaslam-tools; do
    local dep; dep="$(dpkg-deb -f "${DEB[$pkg]}" Depends)"
    note "$pkg Depends: $dep"
    for want in "elaslam-common (= $VERSION-1)" "liblcm1" "libyaml-cpp0" "libstdc++6" "libc6"; do
      case ", $dep," in *", $want"*) ;; *) fail "$pkg Depends lacks $want: $dep" ;; esac
    done
  done
  local tdep; tdep="$(dpkg-deb -f "${DEB[elaslam-tools]}" Depends)"
  for want in python3 python3-numpy python3-matplotlib; do
    case ", $tdep," in *", $want,"*) ;; *) fail "elaslam-tools Depends lacks $want" ;; esac
  done
  # elaslam-spy: what its Java GUIs need (no ELF: typed by hand).
  local sdep; sdep="$(dpkg-deb -f "${DEB[elaslam-spy]}" Depends)"
  note "elaslam-spy Depends: $sdep"
  for want in "elaslam-common (= $VERSION-1)" "default-jre | java-runtime" liblcm-java libjchart2d-java; do
    case ", $sdep," in *", $want"*) ;; *) fail "elaslam-spy Depends lacks $want: $sdep" ;; esac
  done
  # Maintainer: not a placeholder; the copyright file is DEP-5 and Apache-2.0.
  case "$(dpkg-deb -f "${DEB[elaslam-common]}" Maintainer)" in
    *elaslam.example*|"") fail "Maintainer is a placeholder: $(dpkg-deb -f "${DEB[elaslam-common]}" Maintainer)" ;;
  esac
  grep -v "^#" "$SRC/packaging/debian/copyright" | head -1 | grep -qx 'Format: https://www.debian.org/doc/packaging-manuals/copyright-format/1.0/' \
    || fail "packaging/debian/copyright is not DEP-5"
  grep -qx 'License: Apache-2.0' "$SRC/packaging/debian/copyright" || fail "copyright: no License: Apache-2.0"
  lintian_check "$D"
  # elaslam-common's one program, elaslam-keys (its postinst runs it): libsodium and the C++ runtime.
  local cdep; cdep="$(dpkg-deb -f "${DEB[elaslam-common]}" Depends)"
  note "elaslam-common Depends: $cdep"
  for want in libsodium23 "libstdc++6" libc6; do
    case ", $cdep," in *", $want"*) ;; *) fail "elaslam-common Depends lacks $want: $cdep" ;; esac
  done
  case "$cdep" in *elaslam-*|*liblcm*) fail "elaslam-common depends on another package of the team: $cdep" ;; esac
  # Conffiles: both /etc files.
  dpkg-deb -I "${DEB[elaslam-common]}" conffiles > "$TMP/conffiles" || fail "elaslam-common: no conffiles"
  printf '/etc/elaslam/elaslam.env\n/etc/elaslam/elaslam.yaml\n' | diff - <(sort "$TMP/conffiles") \
    || fail "elaslam-common conffiles"
  for pkg in elaslam-robot elaslam-main-robot elaslam-simulator; do
    for s in postinst prerm postrm; do
      dpkg-deb -I "${DEB[$pkg]}" "$s" > "$TMP/$s" || fail "$pkg: no $s"
      sh -n "$TMP/$s" || fail "$pkg: $s does not parse"
    done
  done
  note "conffiles: $(tr '\n' ' ' < "$TMP/conffiles")"

  # ---- run from a dpkg -x root --------------------------------------------------------
  for pkg in "${PACKAGES[@]}"; do dpkg-deb -x "${DEB[$pkg]}" "$R"; done
  etc_check "$R/etc/elaslam"
  units_check "$R" /usr /etc/elaslam
  version_check "$R/usr/bin"
  run_check "dpkg -x root" "$R/etc/elaslam/elaslam.yaml" "$TMP/run-deb" -- \
    env ELASLAM_CONFIG="$R/etc/elaslam/elaslam.yaml" "$R/usr/bin/elaslam-run-scenario"
  # The packaged units verify too, with their /usr paths moved into the root (verify
  # checks that ExecStart exists; the units test covers the drop-in and exposure).
  if command -v systemd-analyze >/dev/null 2>&1; then
    mkdir -p "$TMP/deb-units"
    for u in "$R"/usr/lib/systemd/system/*.service; do
      sed "s#^ExecStart=/usr/bin/#ExecStart=$R/usr/bin/#" "$u" > "$TMP/deb-units/$(basename "$u")"
    done
    local out
    out="$(cd "$TMP/deb-units" && systemd-analyze verify ./*.service ./elaslam-robot@1.service 2>&1)" \
      || { echo "$out"; fail "systemd-analyze verify of the packaged units"; }
    [ -z "$out" ] || { echo "$out"; fail "systemd-analyze verify of the packaged units reported problems"; }
    note "packaged units: systemd-analyze verify clean"
  fi
  # A live team from the root, in a private network namespace (root only).
  if [ "$(id -u)" -eq 0 ] && command -v ip >/dev/null 2>&1 && ip netns list >/dev/null 2>&1; then
    "$SRC/tools/netns_run.sh" --port 7701 -- "$SRC/tests/packaging/team_from_root.sh" "$R" "$TMP/team" \
      || fail "live team from the dpkg -x root"
  else
    note "live team: skipped (needs root and ip netns)"
  fi

  # ---- dpkg itself: install into a scratch root, upgrade, purge ----------------------
  # --force-script-chrootless: the maintainer scripts run here with DPKG_ROOT set
  # (they then leave systemd alone); --force-depends: the scratch root has no libs.
  local I="$TMP/dpkg" DP
  mkdir -p "$I/var/lib/dpkg/info" "$I/var/lib/dpkg/updates" "$I/var/lib/dpkg/triggers"
  touch "$I/var/lib/dpkg/status" "$I/var/lib/dpkg/available"
  DP=(dpkg --root="$I" --force-script-chrootless --force-depends --force-not-root)
  "${DP[@]}" -i "$D"/*.deb > "$TMP/dpkg.log" 2>&1 || { cat "$TMP/dpkg.log"; fail "dpkg -i"; }
  for pkg in "${PACKAGES[@]}"; do
    dpkg-query --admindir="$I/var/lib/dpkg" -W -f='${Status}\n' "$pkg" | grep -qx "install ok installed" \
      || fail "dpkg: $pkg not installed"
  done
  # The keys: a one-computer team made by elaslam-common's postinst: a secret key per
  # role (root's, 0600, in a 0700 directory), the roster listing their public keys (0644).
  local K="$I/etc/elaslam/keys" ROSTER="$I/etc/elaslam/team.yaml"
  [ "$(stat -c '%a %U' "$K")" = "700 root" ] || fail "keys/: $(stat -c '%a %U' "$K" 2>&1)"
  for role in main simulator robot_1 robot_16; do
    [ "$(stat -c '%a %U' "$K/$role.key")" = "600 root" ] || fail "keys/$role.key: $(stat -c '%a %U' "$K/$role.key" 2>&1)"
    grep -qx '[0-9a-f]\{64\}' "$K/$role.key" || fail "keys/$role.key is not 64 hexadecimal digits"
    grep -q "^    $role: \"$("$I/usr/bin/elaslam-keys" public "$K/$role.key")\"$" "$ROSTER" || fail "team.yaml does not list $role's key"
  done
  [ "$(stat -c '%a' "$ROSTER")" = 644 ] || fail "team.yaml: mode $(stat -c '%a' "$ROSTER")"
  grep -q '^  mission: "[0-9a-f]\{16\}"$' "$ROSTER" || fail "team.yaml has no mission"
  local key_before
  key_before="$(cat "$K"/*.key "$ROSTER" | sha256sum)"
  # Upgrade elaslam-common to -2 (the same files) after a site edit: the edit stays.
  echo "# site edit" >> "$I/etc/elaslam/elaslam.yaml"
  dpkg-deb -R "${DEB[elaslam-common]}" "$TMP/common2"
  sed -i "s/^Version: .*/Version: $VERSION-2/" "$TMP/common2/DEBIAN/control"
  dpkg-deb --root-owner-group -b "$TMP/common2" "$TMP/elaslam-common_2.deb" > /dev/null
  "${DP[@]}" -i "$TMP/elaslam-common_2.deb" > "$TMP/dpkg2.log" 2>&1 || { cat "$TMP/dpkg2.log"; fail "dpkg upgrade"; }
  [ "$(tail -1 "$I/etc/elaslam/elaslam.yaml")" = "# site edit" ] || fail "upgrade lost the edit of elaslam.yaml"
  [ "$(cat "$K"/*.key "$ROSTER" | sha256sum)" = "$key_before" ] || fail "upgrade replaced the keys or the roster"
  # Purge elaslam-robot: its state and enablement links go, main-robot's state stays.
  mkdir -p "$I/var/lib/private/elaslam/robot-3" "$I/var/lib/private/elaslam/main-robot" "$I/var/lib/elaslam" \
           "$I/etc/systemd/system/multi-user.target.wants"
  ln -s ../private/elaslam/robot-3 "$I/var/lib/elaslam/robot-3"
  ln -s /usr/lib/systemd/system/elaslam-robot@.service "$I/etc/systemd/system/multi-user.target.wants/elaslam-robot@3.service"
  "${DP[@]}" --purge elaslam-robot > "$TMP/dpkg3.log" 2>&1 || { cat "$TMP/dpkg3.log"; fail "dpkg --purge"; }
  [ ! -e "$I/usr/bin/elaslam-robot-node" ] || fail "purge left the program"
  [ ! -e "$I/var/lib/private/elaslam/robot-3" ] && [ ! -L "$I/var/lib/elaslam/robot-3" ] || fail "purge left robot-3's state"
  [ ! -L "$I/etc/systemd/system/multi-user.target.wants/elaslam-robot@3.service" ] || fail "purge left the enablement link"
  [ -d "$I/var/lib/private/elaslam/main-robot" ] || fail "purging elaslam-robot removed main-robot's state"
  # Purge everything: elaslam-common's purge removes the keys and roster it made.
  "${DP[@]}" --purge elaslam-main-robot elaslam-simulator elaslam-tools elaslam-dev > "$TMP/dpkg4.log" 2>&1 \
    && "${DP[@]}" --purge elaslam-common >> "$TMP/dpkg4.log" 2>&1 || { cat "$TMP/dpkg4.log"; fail "dpkg --purge (all)"; }
  [ ! -e "$K" ] && [ ! -e "$ROSTER" ] || fail "purge left the keys or the roster"
  note "dpkg: installed (a one-computer team's keys made, 0600, and roster), upgraded (site edit and keys kept), purged (keys removed)"
  echo "deb: ok"
}

# =============================================================================
mode_units() {
  need systemd-analyze "systemd"
  local P="$TMP/p" U="$TMP/units" out
  "$CMAKE" --install "$BUILD" --prefix "$P" > "$TMP/install.log" 2>&1 || { cat "$TMP/install.log"; fail "cmake --install"; }
  # Verify copies in one folder with the drop-in as an administrator installs it; the
  # units name $P/bin/... (verify checks that ExecStart exists).
  mkdir -p "$U/elaslam-robot@3.service.d"
  cp "$P"/lib/systemd/system/*.service "$U/"
  cp "$P/share/elaslam/systemd/realtime.conf" "$U/elaslam-robot@3.service.d/"
  out="$(cd "$U" && systemd-analyze verify elaslam-robot@.service ./elaslam-robot@3.service \
           elaslam-main-robot.service elaslam-simulator.service 2>&1)" || { echo "$out"; fail "systemd-analyze verify"; }
  [ -z "$out" ] || { echo "$out"; fail "systemd-analyze verify reported problems"; }
  note "systemd-analyze verify: 3 units, robot 3 with realtime.conf: clean"
  # The drop-in is read (a broken copy is reported), and it is the only place with real-time.
  sed 's/^CPUSchedulingPolicy=fifo/CPUSchedulingPolicy=not-a-policy/' "$P/share/elaslam/systemd/realtime.conf" \
    > "$U/elaslam-robot@3.service.d/realtime.conf"
  out="$(cd "$U" && systemd-analyze verify ./elaslam-robot@3.service 2>&1 || true)"
  echo "$out" | grep -q "realtime.conf.*not-a-policy" || { echo "$out"; fail "verify did not read the drop-in"; }
  grep -qx "CPUSchedulingPolicy=fifo" "$P/share/elaslam/systemd/realtime.conf" || fail "realtime.conf: policy"
  grep -qx "CPUSchedulingPriority=[0-9]*" "$P/share/elaslam/systemd/realtime.conf" || fail "realtime.conf: priority"
  # Exposure (0 = locked down .. 10): the figures in docs/deployment.md; fail above 2.0.
  for u in elaslam-robot@.service elaslam-main-robot.service elaslam-simulator.service; do
    out="$(cd "$P/lib/systemd/system" && systemd-analyze security --offline=true --threshold=20 "./$u" 2>&1)" \
      || { echo "$out"; fail "$u: exposure above 2.0"; }
    note "$(echo "$out" | grep 'Overall exposure level')"
  done
  echo "units: ok"
}

case "$MODE" in
  install) mode_install ;;
  deb) mode_deb ;;
  units) mode_units ;;
  *) echo "package_check.sh: unknown mode '$MODE'" >&2; exit 2 ;;
esac
