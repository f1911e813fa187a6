#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""No include runs from a lower layer to a higher one: every `#include
"elaslam/<folder>/..."` in a library folder's C++ sources names a folder that the
table of docs/architecture.md "Layers" allows for it; every library folder is in
the table, and every folder the table names exists.

  tests/docs/include_layers.py [ROOT]

Exit 0 when every include is allowed; 1 listing each one that is not (file, line,
the folder it includes), or a table that does not match the tree.
"""
import os
import re
import sys

SECTION = "## Layers"
ROW = re.compile(r"^\|\s*`([\w]+)/`\s*\|([^|]*)\|\s*$")
FOLDER = re.compile(r"`([\w]+)/`")
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]elaslam/([\w]+)/')
SOURCES = (".cpp", ".hpp", ".h")


def layer_table(doc_text):
    """{folder: set of folders it may include}, from the section's table."""
    start = doc_text.find("\n" + SECTION + "\n")
    if start < 0:
        return None
    table = {}
    for line in doc_text[start + len(SECTION) + 2:].splitlines():
        if line.startswith("## "):
            break
        m = ROW.match(line)
        if m:
            table[m.group(1)] = set(FOLDER.findall(m.group(2)))
    return table


def library_folders(root):
    """Top-level folders whose sources include their own headers (elaslam/<folder>/)."""
    out = set()
    for name in sorted(os.listdir(root)):
        if os.path.isdir(os.path.join(root, name, "include", "elaslam", name)):
            out.add(name)
    return out


def problems(root):
    doc = os.path.join(root, "docs", "architecture.md")
    with open(doc, encoding="utf-8") as f:
        table = layer_table(f.read())
    if not table:
        return ["docs/architecture.md: no table under '%s'" % SECTION]
    found = []
    libraries = library_folders(root)
    for name in sorted(libraries - set(table)):
        found.append("docs/architecture.md: library folder %s/ is not in the layer table" % name)
    for name in sorted(set(table) | {d for v in table.values() for d in v}):
        if not os.path.isdir(os.path.join(root, name)):
            found.append("docs/architecture.md: the layer table names %s/, which does not exist" % name)
    for folder in sorted(table):
        allowed = table[folder] | {folder}
        for base, _, files in os.walk(os.path.join(root, folder)):
            for file in sorted(files):
                if not file.endswith(SOURCES):
                    continue
                path = os.path.join(base, file)
                with open(path, encoding="utf-8", errors="replace") as f:
                    for number, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        if m and m.group(1) not in allowed:
                            found.append("%s:%d: %s/ includes %s/ (allowed: %s)" % (
                                os.path.relpath(path, root), number, folder, m.group(1),
                                ", ".join(sorted(table[folder])) or "nothing"))
    return found


def main(argv):
    root = argv[1] if len(argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    found = problems(os.path.abspath(root))
    for p in found:
        print("include_layers: " + p)
    if found:
        return 1
    print("include_layers: every include runs down the layers")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
