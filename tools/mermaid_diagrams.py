# SPDX-License-Identifier: Apache-2.0
"""The docs' Mermaid diagrams, as tools/render_diagrams.sh renders them and
tests/docs/docs_links_check.py checks their SVGs (standard library only).

A diagram is a ```mermaid block followed, within four lines, by a link to
images/NAME.svg. Its source is the block's lines, each ending in a newline; the SVG
starts with the stamp <!-- mermaid-source-sha256: HEX -->, the source's sha256.
"""
import hashlib
import re

SVG_LINK = re.compile(r"\]\((?:\.\./)?(?:docs/)?images/([\w.-]+\.svg)\)")
SVG_STAMP = re.compile(r"<!-- mermaid-source-sha256: ([0-9a-f]{64}) -->")


def diagrams(text):
    """(source, NAME.svg linked after it or None, line number of its closing fence) of
    each ```mermaid block of the page `text`."""
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        if re.match(r"^\s*```mermaid\s*$", lines[i]):
            j = i + 1
            while j < len(lines) and not lines[j].strip().startswith("```"):
                j += 1
            m = SVG_LINK.search("\n".join(lines[j + 1:j + 5]))
            yield "\n".join(lines[i + 1:j]) + "\n", m.group(1) if m else None, j + 1
            i = j
        i += 1


def source_sha(source):
    """The stamp's HEX of a diagram's source."""
    return hashlib.sha256(source.encode("utf-8")).hexdigest()
