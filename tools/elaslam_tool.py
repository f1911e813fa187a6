# SPDX-License-Identifier: Apache-2.0
"""Start-up shared by the Python tools (standard library only: it runs before any
third-party import).

In a source tree with a .venv (tools/setup.sh), run_in_venv() re-execs the calling
script with the venv's python and the same arguments, so `tools/plot_sweep.py` and
`python3 tools/plot_sweep.py` work with any python3. An installed copy (this module
in <prefix>/share/elaslam/tools, no .venv beside it) runs with the interpreter that
started it (Debian's python3 and its python3-numpy / python3-matplotlib).

A script finds this module beside itself (source tree, share/elaslam/tools) or, as
bin/elaslam-<tool>, in ../share/elaslam/tools:

    import os, sys
    _here = os.path.dirname(os.path.realpath(__file__))
    sys.path[:0] = [_here, os.path.join(_here, "..", "share", "elaslam", "tools")]
    from elaslam_tool import need, parse_args, run_in_venv, add_version, doc_parser

Tools that read recordings load the generated message types with
load_lcm_types(build_dir, __file__).
"""
import argparse
import importlib
import os
import sys

# <root>/.venv for a source tree: this file is <root>/tools/elaslam_tool.py.
_ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))


def prog():
    """The calling program's name, for messages."""
    return os.path.splitext(os.path.basename(sys.argv[0]))[0]


def version_line():
    """"<prog> (elaslam <version>, git <commit>)", as the C++ programs' --version, from the
    build's share/elaslam/VERSION: installed beside this module's folder, in a source
    tree in $ELASLAM_BUILD_DIR or build/."""
    here = os.path.dirname(os.path.realpath(__file__))
    builds = [os.environ.get("ELASLAM_BUILD_DIR", ""), os.path.join(_ROOT, "build")]
    for path in [os.path.join(here, "..", "VERSION")] + [os.path.join(b, "share", "elaslam", "VERSION") for b in builds if b]:
        try:
            with open(path, encoding="utf-8") as f:
                return f"{prog()} ({f.read().strip()})"
        except OSError:
            continue
    return f"{prog()} (elaslam, version unknown: no build's share/elaslam/VERSION)"


def add_version(ap):
    """--version on an argparse parser."""
    ap.add_argument("--version", action="version", version=version_line(),
                    help="print the version and the source commit, then exit")


def doc_parser(name, doc):
    """The parser of a tool documented by its docstring `doc`: the first paragraph is the
    description, the paragraphs after the second the epilog (kept as written); --version."""
    paragraphs = doc.split("\n\n")
    ap = argparse.ArgumentParser(prog=name, description=paragraphs[0], epilog="\n\n".join(paragraphs[2:]),
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    add_version(ap)
    return ap


def run_in_venv():
    """Re-exec the running script in <root>/.venv when there is one and this is not it."""
    venv = os.path.join(_ROOT, ".venv")
    python = os.path.join(venv, "bin", "python")
    if not os.access(python, os.X_OK) or os.path.realpath(sys.prefix) == os.path.realpath(venv):
        os.environ.pop("ELASLAM_VENV_REEXEC", None)  # in the venv (or none): children start afresh
        return
    if os.environ.get("ELASLAM_VENV_REEXEC") == venv:
        return  # the venv's python did not become the venv: never loop, go on with this one
    os.environ["ELASLAM_VENV_REEXEC"] = venv
    os.execv(python, [python] + sys.argv)


def need(module, debian=None):
    """Import a third-party module, or exit 2 naming it and how to get it."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        top = module.split(".")[0]
        if debian:
            how = f"Debian: apt-get install {debian}"
        elif sys.prefix != sys.base_prefix:  # already a venv: install into it
            how = f"it is on PyPI only (Debian has no package): {sys.executable} -m pip install {top}"
        else:  # never into the system's Python (Debian refuses it: PEP 668); a venv that sees Debian's modules
            how = (f"it is on PyPI only (Debian has no package); install it into a virtual environment "
                   f"and run this program with its python: python3 -m venv --system-site-packages ~/.venvs/elaslam"
                   f" && ~/.venvs/elaslam/bin/pip install {top}; ~/.venvs/elaslam/bin/python {sys.argv[0]} ...")
        sys.stderr.write(f"{prog()}: the Python module '{top}' is missing for {sys.executable} ({e}).\n"
                         f"  {how}; in a source tree, tools/setup.sh makes .venv with every module the tools need.\n")
        sys.exit(2)


def parse_args(ap):
    """ap.parse_args(), naming an unknown option (exit 2) even when a required argument is missing too.
    The options of sub-commands (add_subparsers) count as known."""
    parsers = [ap] + [c for a in ap._actions for c in (getattr(a, "choices", None) or {}).values()
                      if isinstance(c, type(ap))]
    known = [s for p in parsers for a in p._actions for s in a.option_strings]
    for tok in sys.argv[1:]:
        if tok == "--":
            break
        if tok.startswith("-") and tok != "-" and not ap._negative_number_matcher.match(tok):
            if not any(k.startswith(tok.split("=", 1)[0]) for k in known):
                ap.error(f"unrecognized argument: {tok}")
    return ap.parse_args()


def types_dirs(build_dir, script):
    """Where the generated Python package `elaslam` (the LCM message types) may be for
    `script` (the calling tool's __file__), best first: DIR/lcmgen/python with
    --build-dir DIR; else $ELASLAM_BUILD_DIR/lcmgen/python, the installed
    <prefix>/share/elaslam/python, or the source tree's build/lcmgen/python."""
    if build_dir:
        return [os.path.join(build_dir, "lcmgen", "python")]
    dirs = []
    if os.environ.get("ELASLAM_BUILD_DIR"):
        dirs.append(os.path.join(os.environ["ELASLAM_BUILD_DIR"], "lcmgen", "python"))
    for here in dict.fromkeys([os.path.dirname(os.path.abspath(script)), os.path.dirname(os.path.realpath(script))]):
        if here.endswith(os.path.join("share", "elaslam", "tools")):
            dirs += [os.path.join(here, "..", "python"),                    # installed: <prefix>/share/elaslam/python
                     os.path.join(here, "..", "..", "..", "lcmgen", "python")]  # the build tree's mirror of it
        elif os.path.basename(here) == "bin":
            dirs.append(os.path.join(here, "..", "share", "elaslam", "python"))  # installed as <prefix>/bin/...
    dirs.append(os.path.join(os.path.dirname(os.path.dirname(os.path.realpath(script))), "build", "lcmgen", "python"))
    return [os.path.normpath(d) for d in dirs]


def load_lcm_types(build_dir, script):
    """The generated package `elaslam` (see types_dirs), or exit 2 saying where it was looked for."""
    dirs = types_dirs(build_dir, script)
    found = next((d for d in dirs if os.path.isfile(os.path.join(d, "elaslam", "__init__.py"))), None)
    if found is None:
        sys.stderr.write(f"{prog()}: no generated Python message types (elaslam/__init__.py) in "
                         f"{', '.join(dict.fromkeys(dirs))}: build first (cmake --build BUILD) or give --build-dir\n")
        sys.exit(2)
    sys.path.insert(0, found)
    return importlib.import_module("elaslam")
