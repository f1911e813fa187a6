#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The docs' links resolve: every relative markdown link and every docs/*.md path
named in the text of README.md and docs/**/*.md points to a file or folder that
exists; docs/adr/README.md lists every decision record (docs/adr/NNNN-*.md) and no
other; every Mermaid diagram rendered to a checked-in SVG (docs/images/*.svg, by
tools/render_diagrams.sh) was rendered from the diagram's current source.

  tests/docs/docs_links_check.py [ROOT]

Exit 0 when all hold; 1 listing what does not. Standard library only.
"""
import glob
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..", "tools"))
from mermaid_diagrams import SVG_STAMP, diagrams, source_sha  # noqa: E402

LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
# A docs path named in prose or a code span: docs/x.md, docs/adr/0001-x.md, docs/experiments/
DOC_PATH = re.compile(r"(?<![\w/.-])(docs/[\w./-]*[\w/])")
FENCE = re.compile(r"^\s*(```+|~~~+)")
ADR_NAME = re.compile(r"^\d{4}-[a-z0-9][a-z0-9.-]*\.md$")
# The SVG of a diagram carries the sha256 of the Mermaid source it was rendered from.


def pages(root):
    out = [os.path.join(root, "README.md")]
    out += sorted(glob.glob(os.path.join(root, "docs", "**", "*.md"), recursive=True))
    return [p for p in out if os.path.isfile(p)]


def prose(text):
    """Lines outside fenced blocks, with their numbers."""
    fence = None
    for n, line in enumerate(text.split("\n"), 1):
        m = FENCE.match(line)
        if fence is None and m:
            fence = m.group(1)
            continue
        if fence is not None:
            if line.strip().startswith(fence):
                fence = None
            continue
        yield n, line


def check(root):
    errors = []
    for page in pages(root):
        rel = os.path.relpath(page, root)
        text = open(page, encoding="utf-8").read()
        for n, line in prose(text):
            for m in LINK.finditer(line):
                target = m.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
                    continue  # http:, mailto:, an anchor of the page itself
                path = target.split("#", 1)[0]
                full = os.path.normpath(os.path.join(os.path.dirname(page), path))
                if not os.path.exists(full):
                    errors.append(f"{rel}:{n}: link to {target}: no such file")
            for m in DOC_PATH.finditer(line):
                path = m.group(1).rstrip(".")
                if "*" in path or not (path.endswith(".md") or path.endswith("/")):
                    continue
                if not os.path.exists(os.path.join(root, path)):
                    errors.append(f"{rel}:{n}: names {path}: no such file")
        for source, name, after in diagrams(text):
            # The SVG linked right after the block must be of this source.
            if not name:
                continue
            svg = os.path.join(root, "docs", "images", name)
            if not os.path.isfile(svg):
                continue  # reported above as a broken link
            stamp = SVG_STAMP.search(open(svg, encoding="utf-8").read())
            if not stamp:
                errors.append(f"{rel}:{after}: docs/images/{name} has no mermaid-source-sha256 stamp")
            elif stamp.group(1) != source_sha(source):
                errors.append(f"{rel}:{after}: docs/images/{name} is stale: the Mermaid source changed; "
                              "run tools/render_diagrams.sh")
    adr_dir = os.path.join(root, "docs", "adr")
    if os.path.isdir(adr_dir):
        records = {f for f in os.listdir(adr_dir) if f != "README.md"}
        for f in sorted(records):
            if not ADR_NAME.match(f):
                errors.append(f"docs/adr/{f}: not a record name (NNNN-short-title.md)")
        index = open(os.path.join(adr_dir, "README.md"), encoding="utf-8").read()
        listed = set(re.findall(r"\]\((\d{4}-[\w.-]+\.md)\)", index))
        for f in sorted(records - listed):
            errors.append(f"docs/adr/README.md: does not list {f}")
        numbers = sorted(f[:4] for f in records if ADR_NAME.match(f))
        if len(set(numbers)) != len(numbers):
            errors.append("docs/adr/: two records share a number")
    return errors


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", ".."))
    errors = check(root)
    for e in errors:
        print(e)
    if errors:
        print(f"docs_links_check: {len(errors)} problem(s)")
        return 1
    print(f"docs_links_check: {len(pages(root))} pages, every link resolves")
    return 0


if __name__ == "__main__":
    sys.exit(main())
