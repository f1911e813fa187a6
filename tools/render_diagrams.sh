#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Renders the docs' Mermaid diagrams to checked-in SVGs.
#
#   tools/render_diagrams.sh [--chromium PATH] [--mermaid-cli VERSION]
#
# - Every ```mermaid block of docs/*.md followed (within four lines) by a link to
#   images/NAME.svg is rendered to docs/images/NAME.svg with the Mermaid CLI
#   (npx @mermaid-js/mermaid-cli, default version 11.17.0, fetched from the npm
#   registry on first use) and a headless Chromium (default /usr/bin/chromium, run
#   with --no-sandbox; Debian's `chromium` package).
# - The SVG starts with the comment <!-- mermaid-source-sha256: HEX -->, the sha256 of
#   the block's lines (each ending in a newline); the docs test (tests/docs,
#   docs_links) fails when the block no longer has that hash: run this again after
#   changing a diagram and commit the SVG.
set -euo pipefail
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
CHROMIUM=/usr/bin/chromium
MMDC_VERSION=11.17.0
usage() { sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit "${1:-0}"; }
usage_error() { echo "render_diagrams: $1 (see --help)" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --chromium|--mermaid-cli) [ $# -ge 2 ] || usage_error "$1 needs a value" ;;&
    --chromium) CHROMIUM="$2"; shift 2 ;;
    --mermaid-cli) MMDC_VERSION="$2"; shift 2 ;;
    -h|--help) usage 0 ;;
    *) usage_error "unknown argument '$1'" ;;
  esac
done
[ -x "$CHROMIUM" ] || usage_error "no Chromium at $CHROMIUM (apt-get install chromium, or --chromium PATH)"
command -v npx >/dev/null || usage_error "npx not found (apt-get install npm)"

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
printf '{"executablePath": "%s", "args": ["--no-sandbox", "--disable-gpu"]}\n' "$CHROMIUM" >"$WORK/puppeteer.json"

# One line per diagram: SOURCE_FILE SVG_NAME SHA256, the block's source in WORK/SVG_NAME.mmd.
python3 - "$ROOT" "$WORK" >"$WORK/diagrams" <<'PY'
import glob, os, sys
root, work = sys.argv[1], sys.argv[2]
sys.path.insert(0, os.path.join(root, "tools"))
from mermaid_diagrams import diagrams, source_sha
for page in sorted(glob.glob(os.path.join(root, "docs", "*.md"))):
    for source, svg, _ in diagrams(open(page, encoding="utf-8").read()):
        if svg:
            open(os.path.join(work, svg + ".mmd"), "w", encoding="utf-8").write(source)
            print(os.path.relpath(page, root), svg, source_sha(source))
PY
[ -s "$WORK/diagrams" ] || { echo "render_diagrams: no diagram links to docs/images/*.svg" >&2; exit 1; }
mkdir -p "$ROOT/docs/images"
while read -r page svg sha; do
  PUPPETEER_SKIP_DOWNLOAD=1 npx -y "@mermaid-js/mermaid-cli@$MMDC_VERSION" -q -p "$WORK/puppeteer.json" \
    -i "$WORK/$svg.mmd" -o "$WORK/$svg" -b white
  { printf '<!-- mermaid-source-sha256: %s -->\n' "$sha"; cat "$WORK/$svg"; echo; } >"$ROOT/docs/images/$svg"
  echo "render_diagrams: $page -> docs/images/$svg"
done <"$WORK/diagrams"
