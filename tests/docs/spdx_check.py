#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Every source file of the project says its licence: an SPDX-License-Identifier
line (Apache-2.0, the LICENSE file) in its first three lines, as a comment of its
language. Sources: C++ (.cpp .hpp .h), Python, shell, CMake (CMakeLists.txt,
.cmake), LCM definitions, the configs (.yaml under config/ and packaging/), Java,
systemd units and fragments, the Debian maintainer scripts. Data (fuzz corpora, test inputs, references) is not source.

  tests/docs/spdx_check.py [--fix] [ROOT]

Exit 0 when every source has the line; 1 listing those that do not. --fix inserts
it (after a shebang line) and exits 0.
"""
import os
import subprocess
import sys

TAG = "SPDX-License-Identifier: Apache-2.0"
COMMENT = {".cpp": "//", ".hpp": "//", ".h": "//", ".java": "//", ".lcm": "//",
           ".py": "#", ".sh": "#", ".cmake": "#", ".yaml": "#", ".service": "#", ".conf": "#", ".in": "#"}
COMMENT[".inc"] = "#"  # packaging/systemd/hardening.inc: a unit file fragment
NOT_SOURCE = ("fuzz/corpus/", "tests/golden/reference/", "tests/common/data/", "tests/dataset/data/",
              "fuzz/ledger/")


def comment_of(path):
    name = os.path.basename(path)
    if name == "CMakeLists.txt":
        return "#"
    ext = os.path.splitext(name)[1]
    if ext == ".in" and not (name.endswith((".cmake.in", ".service.in", ".sh.in")) or path.startswith("packaging/debian/")):
        return None
    if ext == ".yaml" and not path.startswith(("config/", "packaging/")):
        return None
    return COMMENT.get(ext)


def tracked(root):
    """git's list of the project's files; without git (a source archive) the tree
    without build and run outputs."""
    try:
        out = subprocess.run(["git", "-C", root, "ls-files"], capture_output=True, text=True, check=True).stdout
        return out.split("\n")
    except (OSError, subprocess.CalledProcessError):
        paths = []
        for d, dirs, files in os.walk(root):
            rel = os.path.relpath(d, root)
            dirs[:] = [x for x in dirs if not (rel == "." and (x.startswith(("build", ".")) or x in ("runs", "results", "data")))]
            paths += [os.path.normpath(os.path.join(rel, f)) for f in files]
        return paths


def sources(root):
    for path in tracked(root):
        if path and not path.startswith(NOT_SOURCE) and comment_of(path) and os.path.isfile(os.path.join(root, path)):
            yield path


def main():
    args = [a for a in sys.argv[1:] if a != "--fix"]
    fix = "--fix" in sys.argv[1:]
    root = os.path.abspath(args[0]) if args else os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    missing = []
    for path in sources(root):
        full = os.path.join(root, path)
        with open(full, encoding="utf-8", errors="replace") as f:
            lines = f.read().split("\n")
        if any(TAG in line for line in lines[:3]):
            continue
        if not fix:
            missing.append(path)
            continue
        at = 1 if lines and lines[0].startswith("#!") else 0
        lines.insert(at, f"{comment_of(path)} {TAG}")
        mode = os.stat(full).st_mode
        with open(full, "w", encoding="utf-8") as f:
            f.write("\n".join(lines))
        os.chmod(full, mode)
    if missing:
        print(f"spdx_check: {len(missing)} source files without '{TAG}' in their first three lines "
              "(tests/docs/spdx_check.py --fix adds it):")
        for p in missing:
            print("  " + p)
        return 1
    print(f"spdx_check: every source file carries {TAG}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
