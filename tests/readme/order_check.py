#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The README's order check (readme_check.order_problems) on made-up READMEs: a
program used before any command builds it, and the Python tools before the whole
build, are found; after the test command or `cmake --build build` nothing is. The
pages are read in order as one: a docs page may use what README.md built, not the
other way round. Then the project's own pages (readme_check.PAGES).
  tests/readme/order_check.py
"""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import readme_check as r  # noqa: E402


def problems(lines, targets="simulator robot_node", docs=None):
    """lines: README.md's commands; docs: a second page's (docs/usage.md), read after it."""
    with tempfile.TemporaryDirectory() as d:
        os.makedirs(os.path.join(d, "tools"))
        os.makedirs(os.path.join(d, "docs"))
        with open(os.path.join(d, "tools", "run_team.sh"), "w") as f:
            f.write(f"TARGETS=({targets})\n")
        pages = {"README.md": lines}
        if docs is not None:
            pages["docs/usage.md"] = docs
        for page, cmds in pages.items():
            with open(os.path.join(d, page), "w") as f:
                f.write("```sh\n" + "\n".join(cmds) + "\n```\n")
        cmds = r.readme_commands(d, set(), tuple(pages))
        return r.order_problems(d, cmds, tuple(pages))


def main():
    p = problems(["tools/run_team.sh", "build/bin/simulator --help", "build/bin/log_info x.lcmlog",
                  "tools/decode_log.py x", "cmake --build build", "build/bin/log_info y"])
    assert len(p) == 2, p
    assert "build/bin/log_info x.lcmlog" in p[0] and "log_info, which no earlier" in p[0], p
    assert "tools/decode_log.py x" in p[1], p
    assert problems(["tools/run_team.sh", "tools/run_tests.sh", "build/bin/log_info x", "tools/decode_log.py x"]) == []
    # A --target build builds only that target; the package target builds all.
    assert len(problems(["cmake --build build --target simulator", "build/bin/evaluate x"])) == 1
    assert problems(["cmake --build build --target package", "build/bin/evaluate x"]) == []
    # Two pages read as one, README.md first: the docs page uses what the README built ...
    assert problems(["tools/run_team.sh", "cmake --build build"], docs=["build/bin/log_info x"]) == []
    # ... but a README command cannot use what only the docs page builds,
    p = problems(["tools/run_team.sh", "build/bin/log_info x"], docs=["cmake --build build", "build/bin/log_info y"])
    assert len(p) == 1 and "build/bin/log_info x" in p[0], p
    # and a command the README has already counts where the README has it.
    assert len(problems(["build/bin/log_info x"], docs=["cmake --build build", "build/bin/log_info x"])) == 1
    # The project's own README.
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    own = r.order_problems(root, r.readme_commands(root, r.project_programs(root)))
    assert own == [], own
    print("order_check: 9 checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
