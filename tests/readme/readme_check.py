#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Every command of README.md and of the docs pages it leads to works: the README
tests (tests/readme/README.md). The pages, read in this order as one README:
README.md, docs/usage.md, docs/results.md (PAGES in this file); "README commands"
are theirs.

  readme_check.py extract [--source DIR] [--build DIR] [--where]
      print the commands found in the pages, one a line, in the pages' order
      (--where: each after the first page that has it and a tab)
  readme_check.py check [--source DIR] [--build DIR]
      the table (tests/readme/commands.txt) against the pages: every command
      has an entry, every entry matches a command of a page (exit 1 if not)
  readme_check.py run --build DIR [--source DIR] [--scratch DIR] [--only REGEX] [--fresh]
      check, then run every entry in a scratch copy of the repository root (with
      --fresh: a git clone of its HEAD, nothing built, in README order) and
      print a table of command / seconds / result; exit 0 when everything that
      ran passed, 1 on a failure, 77 when nothing could run (ctest: skipped)
  readme_check.py help --build DIR [--source DIR] [--scratch DIR]
      --help and -h of every tools/*.sh and tools/*.py and --help of every
      program in BUILD/bin, --version of every C++ program and installed script: exit 0 and output
      that names the program; tools/* --no-such-option: exit 2 and a message
      naming it; else the test fails

Standard library only, so any python3 runs it.
"""
import argparse
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))

# The pages whose commands the README test runs, in the order a new user follows
# them: README.md (the quick start), then docs/usage.md (the team's options, the
# viewer, real data, recordings, deployment, every program, the tests), then
# docs/results.md (the experiments behind every figure). Their commands are read
# as one README: one list without duplicates, one table (commands.txt), one order
# (a command that uses build/bin/X comes after the command that builds it, on any
# page before it or earlier on its own). Other docs pages' commands are examples
# for their readers, not run here.
PAGES = ("README.md", "docs/usage.md", "docs/results.md")

# ---- what a README command is ----------------------------------------------------
# First words of an inline code span that make it a command (see tests/readme/README.md).
PATH_PREFIXES = ("build/bin/", "tools/", "tests/", ".venv/bin/", "./")
COMMAND_NAMES = {"cmake", "cpack", "ctest", "sudo", "systemctl", "journalctl", "python3", "python", "java", "ip",
                 "apt-get", "apt", "dpkg", "git", "make", "ninja", "bash", "sh", "env", "xvfb-run"}
COMMAND_NAME_PATTERNS = (re.compile(r"lcm-[\w-]+"), re.compile(r"elaslam-[\w-]+"))
# A synopsis, not a command: placeholders outside quotes.
PLACEHOLDER = re.compile(r"(?<![\w$-])[A-Z][A-Z0-9_]*(?![\w=])")
SYNOPSIS_MARKS = re.compile(r"\[|\]|\.\.\.|…|<|>|\{|\}|(?<! )\|(?! )")
QUOTED = re.compile(r"'[^']*'|\"[^\"]*\"")


def normalize(cmd):
    return " ".join(cmd.split())


def strip_comment(line):
    """A line without its trailing `# comment` (a # after whitespace, outside quotes)."""
    quote = None
    for i, c in enumerate(line):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c == "#" and (i == 0 or line[i - 1].isspace()):
            return line[:i]
    return line


def is_synopsis(span):
    unquoted = QUOTED.sub("''", span)
    return bool(PLACEHOLDER.search(unquoted) or SYNOPSIS_MARKS.search(unquoted))


def span_is_command(span, source, programs):
    """Whether an inline code span is a command (the rule of tests/readme/README.md)."""
    if not span or span.startswith("-") or is_synopsis(span):
        return False
    try:
        words = shlex.split(span)
    except ValueError:
        return False
    if not words:
        return False
    first = words[0]
    if first.startswith(PATH_PREFIXES):
        if first.endswith("/"):
            return False  # a directory
        if len(words) > 1 or first.startswith("build/bin/"):
            return True
        # One word: a command only when it names an executable file of the source tree.
        path = os.path.join(source, first)
        return os.path.isfile(path) and os.access(path, os.X_OK)
    if len(words) == 1:
        return False  # a program's name in prose (`lcm-logger`, `evaluate`)
    return (first in COMMAND_NAMES or any(p.fullmatch(first) for p in COMMAND_NAME_PATTERNS)
            or first in programs)


def read_page(source, page):
    path = os.path.join(source, page)
    try:
        with open(path, encoding="utf-8") as f:
            return f.read()
    except OSError as e:
        raise SystemExit(f"readme_check: cannot read {page}, one of the README test's pages: {e}")


def readme_commands(source, programs, pages=PAGES):
    """The pages' commands, page by page in PAGES order, each page's in order of
    appearance (its fenced commands, then its inline ones), without duplicates."""
    found = []
    for page in pages:
        found += page_commands(read_page(source, page), source, programs)
    return list(dict.fromkeys(normalize(c) for c in found))


def command_pages(source, programs, pages=PAGES):
    """{command: the first page that has it}."""
    where = {}
    for page in pages:
        for c in page_commands(read_page(source, page), source, programs):
            where.setdefault(normalize(c), page)
    return where


def page_commands(page_text, source, programs):
    """One page's commands in order of appearance: the fenced ones, then the inline ones."""
    lines = page_text.split("\n")
    found, prose = [], []
    fence, shell_block, pending = None, False, ""
    for line in lines:
        m = re.match(r"^\s*(```+|~~~+)\s*([\w+-]*)", line)
        if fence is None and m:
            fence, shell_block = m.group(1), m.group(2) in ("sh", "bash", "shell")
            prose.append("")
            continue
        if fence is not None:
            if line.strip().startswith(fence):
                fence = None
                if pending.strip():
                    found.append(pending)
                pending = ""
            elif shell_block:
                text = strip_comment(line).rstrip()
                if text.endswith("\\"):
                    pending += text[:-1] + " "
                    continue
                text = pending + text
                pending = ""
                if text.strip():
                    found.append(text)
            continue
        prose.append(line)
    # Inline code spans of the prose (a span may cross a line break; `` spans are not used).
    text = "\n".join(prose)
    for m in re.finditer(r"(?<!`)`([^`]+)`(?!`)", text):
        span = normalize(m.group(1))
        if span_is_command(span, source, programs):
            found.append(span)
    return found


# ---- the table -------------------------------------------------------------------
class Entry:
    def __init__(self, kind, text, line):
        self.kind = kind          # "readme" or "extra"
        self.text = normalize(text)
        self.line = line          # line number in commands.txt
        self.run = None           # the command to run, or None with skip
        self.skip = None          # SKIP reason
        self.expect = []          # regexes the output must contain
        self.root = False         # needs root and network namespaces
        self.needs = []           # paths (relative to the scratch dir) that must exist
        self.timeout = 300


def read_table(path):
    entries, cur = [], None
    with open(path, encoding="utf-8") as f:
        for n, raw in enumerate(f, 1):
            line = raw.rstrip("\n")
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            m = re.match(r"^(readme|extra|run|expect|root|needs|timeout):\s?(.*)$", line)
            if not m:
                raise SystemExit(f"{path}:{n}: not a table line (key: value): {line}")
            key, value = m.group(1), m.group(2).strip()
            if key in ("readme", "extra"):
                cur = Entry(key, value, n)
                entries.append(cur)
                continue
            if cur is None:
                raise SystemExit(f"{path}:{n}: '{key}:' before the first 'readme:' or 'extra:'")
            if key == "run":
                if value.startswith("SKIP"):
                    cur.skip = value[4:].strip() or "no reason given"
                    if not value[4:].strip():
                        raise SystemExit(f"{path}:{n}: SKIP needs a reason")
                elif value == "=":
                    cur.run = cur.text
                else:
                    cur.run = value
            elif key == "expect":
                try:
                    re.compile(value)
                except re.error as e:
                    raise SystemExit(f"{path}:{n}: bad regex {value!r}: {e}")
                cur.expect.append(value)
            elif key == "root":
                if value not in ("yes", "no"):
                    raise SystemExit(f"{path}:{n}: root: yes or no")
                cur.root = value == "yes"
            elif key == "needs":
                cur.needs.append(value)
            elif key == "timeout":
                cur.timeout = float(value)
    for e in entries:
        if e.run is None and e.skip is None:
            raise SystemExit(f"{path}:{e.line}: '{e.text}' has no 'run:' line")
    return entries


def project_programs(source):
    """Names of the project's programs: add_executable() targets outside tests/."""
    names = set()
    for d, dirs, files in os.walk(source):
        rel = os.path.relpath(d, source)
        dirs[:] = [x for x in dirs if not x.startswith((".", "build")) and not (rel == "." and x in ("tests", "runs"))]
        if "CMakeLists.txt" in files:
            with open(os.path.join(d, "CMakeLists.txt"), encoding="utf-8") as f:
                names.update(re.findall(r"add_executable\(\s*([\w-]+)", f.read()))
    return names


def programs_in(build):
    b = os.path.join(build, "bin") if build else None
    if not b or not os.path.isdir(b):
        return set()
    return {f for f in os.listdir(b) if os.access(os.path.join(b, f), os.X_OK) and os.path.isfile(os.path.join(b, f))}


def shown(path, source):
    rel = os.path.relpath(os.path.abspath(path), source)
    return path if rel.startswith("..") else rel


# What a README command builds, for the order check: tools/run_team.sh its TARGETS
# (read from the script), the test command and a `cmake --build build` without
# --target (or the package target, which depends on all) everything.
def run_team_targets(source):
    with open(os.path.join(source, "tools", "run_team.sh"), encoding="utf-8") as f:
        m = re.search(r"^TARGETS=\(([^)]*)\)", f.read(), re.M)
    return set(m.group(1).split()) if m else set()


# Non-program outputs of the build that a README command needs: the generated
# Python message types (not among run_team.sh's targets).
NEEDS_FULL_BUILD = ("tools/decode_log.py",)


def order_problems(source, cmds, pages=PAGES):
    """The pages read in order (PAGES) by a new user on a fresh clone: every
    build/bin/<name> a command uses must be built by an earlier command. Returns
    the problems."""
    text = normalize("\n".join(read_page(source, page) for page in pages))
    pos = {c: (text.find(c) if text.find(c) >= 0 else len(text)) for c in cmds}
    team_targets = run_team_targets(source)
    built, everything, problems = set(), False, []
    for c in sorted(cmds, key=lambda c: pos[c]):
        if not everything:
            for prog in re.findall(r"(?<![\w/.])build/bin/([\w-]+)", c):
                if prog not in built:
                    problems.append(f"`{c}` uses build/bin/{prog}, which no earlier command builds")
            if c.startswith(NEEDS_FULL_BUILD):
                problems.append(f"`{c}` needs the whole build, which no earlier command makes")
        if re.match(r"tools/run_team\.sh(\s|$)", c):
            built |= team_targets
        if (re.match(r"(tools/run_tests\.sh|cmake --build build)(\s|$)", c) and
                ("--target" not in c or re.search(r"--target (package|all)\b", c))):
            everything = True
    return problems


def check(source, build, table):
    programs = project_programs(source)
    cmds = readme_commands(source, programs)
    where = command_pages(source, programs)
    entries = read_table(table)
    mapped = {e.text for e in entries if e.kind == "readme"}
    missing = [c for c in cmds if c not in mapped]
    stale = [e for e in entries if e.kind == "readme" and e.text not in cmds]
    dup = sorted({e.text for e in entries if e.kind == "readme" and
                  sum(1 for x in entries if x.kind == "readme" and x.text == e.text) > 1})
    ok = True
    if missing:
        ok = False
        print(f"README commands without an entry in {shown(table, source)} (add them):")
        for c in missing:
            print(f"\n# {where[c]}\nreadme: {c}\nrun: =")
        print()
    if stale:
        ok = False
        print(f"stale entries in {shown(table, source)} (no such command in {', '.join(PAGES)}; "
              "update or remove):")
        for e in stale:
            print(f"  line {e.line}: readme: {e.text}")
    if dup:
        ok = False
        print("README commands with more than one entry: " + "; ".join(dup))
    order = order_problems(source, cmds)
    if order:
        ok = False
        print(f"README commands out of order (a new user running them top to bottom, {' then '.join(PAGES)}, "
              "on a fresh clone fails):")
        for p in order:
            print("  " + p)
    per_page = ", ".join(f"{p} {sum(1 for c in cmds if where[c] == p)}" for p in PAGES)
    print(f"README commands: {len(cmds)} ({per_page}); table entries: {len(entries)} "
          f"({sum(1 for e in entries if e.kind == 'extra')} extra)" + ("" if ok else ": MISMATCH"))
    return ok, entries


# ---- running ---------------------------------------------------------------------
def namespaces_usable():
    if os.geteuid() != 0 or not shutil.which("ip"):
        return False
    return subprocess.run(["ip", "netns", "list"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode == 0


def make_scratch(source, build, scratch, fresh=False):
    """<scratch>/repo mirrors the repository root: links to the source folders and
    build -> the test's build dir; outputs (results/, runs/, ...) are real folders
    there. fresh: a git clone of the source's HEAD instead, with nothing built, no
    .venv and no data, as a new user has it."""
    marker = os.path.join(scratch, ".readme_scratch")
    if os.path.isdir(scratch) and os.listdir(scratch):
        if not os.path.isfile(marker):
            raise SystemExit(f"readme_check: {scratch} is not empty and not a scratch dir of ours "
                             "(no .readme_scratch): not emptying it")
        shutil.rmtree(scratch)
    repo = os.path.join(scratch, "repo")
    os.makedirs(os.path.join(scratch, "logs"))
    os.makedirs(repo)
    open(marker, "w").close()
    if fresh:
        os.rmdir(repo)
        subprocess.run(["git", "clone", "--quiet", "--no-hardlinks", source, repo], check=True)
        return repo
    for name in sorted(os.listdir(source)):
        if name in (".git", "runs", "results", "Testing") or name.startswith("build"):
            continue
        os.symlink(os.path.join(source, name), os.path.join(repo, name))
    os.symlink(os.path.abspath(build), os.path.join(repo, "build"))
    return repo


def run_one(cmd, cwd, env, log_path, timeout):
    t0 = time.monotonic()
    with open(log_path, "wb") as log:
        log.write(f"$ {cmd}\n".encode())
        log.flush()
        p = subprocess.Popen(["bash", "-c", cmd], cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=log,
                             stderr=subprocess.STDOUT, start_new_session=True)
        timed_out = False
        try:
            rc = p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            timed_out = True
            os.killpg(p.pid, signal.SIGTERM)  # the command's own process group (its session)
            try:
                rc = p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                rc = p.wait()
    with open(log_path, "rb") as f:
        out = f.read().decode("utf-8", "replace")
    return rc, time.monotonic() - t0, timed_out, out


def short(text, width):
    return text if len(text) <= width else text[:width - 3] + "..."


NESTED = "ELASLAM_README_TEST"  # set for the commands: a README test started by one of them skips


def command_env(build):
    env = dict(os.environ)
    env[NESTED] = "1"
    env["ELASLAM_BUILD_DIR"] = os.path.abspath(build)
    # LCM traffic stays in the process unless a project script (netns_run.sh,
    # run_team.sh) sets a URL inside its own network namespace.
    env["LCM_DEFAULT_URL"] = "memq://"
    env.pop("ELASLAM_VENV_REEXEC", None)
    env.pop("ELASLAM_CONFIG", None)
    env.pop("VIRTUAL_ENV", None)
    return env


def cmd_run(args):
    source, build = os.path.abspath(args.source), os.path.abspath(args.build)
    ok, entries = check(source, build, args.table)
    if not ok:
        return 1
    scratch = os.path.abspath(args.scratch or os.path.join(build, "tests", "readme", "scratch"))
    root_ok = namespaces_usable()
    if args.fresh and not root_ok:
        # The first command (tools/run_team.sh) needs root; without it nothing after it is built.
        print("readme_check: --fresh needs root and network namespaces (the first command): skipped")
        return 77
    repo = make_scratch(source, build, scratch, args.fresh)
    env = command_env(os.path.join(repo, "build") if args.fresh else build)
    where = "a fresh clone, nothing built" if args.fresh else f"build -> {build}"
    print(f"scratch: {repo} ({where}); root with network namespaces: {'yes' if root_ok else 'no'}\n")
    rows, done, failed, ran = [], {}, [], 0
    for i, e in enumerate(entries, 1):
        label = e.text if e.kind == "readme" else f"(extra) {e.text}"
        if args.only and not re.search(args.only, e.text):
            continue
        if e.skip:
            rows.append((i, label, None, f"SKIP: {e.skip}"))
            continue
        if e.root and not root_ok:
            rows.append((i, label, None, "SKIP: needs root and network namespaces"))
            continue
        absent = [p for p in e.needs if not os.path.exists(os.path.join(repo, p))]
        if absent:
            rows.append((i, label, None, f"SKIP: no {', '.join(absent)}"))
            continue
        if e.run in done:
            j, res = done[e.run]
            rows.append((i, label, None, f"{res} (same command as #{j})"))
            continue
        log_path = os.path.join(scratch, "logs", f"{i:02d}.log")
        print(f"[{i}] $ {e.run}", flush=True)
        rc, secs, timed_out, out = run_one(e.run, repo, env, log_path, e.timeout)
        ran += 1
        problems = []
        if timed_out:
            problems.append(f"timed out after {e.timeout:g} s")
        elif rc != 0:
            problems.append(f"exit status {rc}")
        for rx in e.expect:
            if not re.search(rx, out, re.MULTILINE):
                problems.append(f"output lacks /{rx}/")
        res = "ok" if not problems else "FAIL: " + "; ".join(problems)
        if problems:
            failed.append(i)
            tail = "\n".join(out.rstrip().split("\n")[-25:])
            print(f"    {res}; last lines of {log_path}:\n" + "\n".join("    | " + t for t in tail.split("\n")), flush=True)
        else:
            print(f"    ok, {secs:.1f} s", flush=True)
        done[e.run] = (i, "ok" if not problems else "FAIL")
        rows.append((i, label, secs, res))
    width = max([len("README command")] + [len(short(r[1], 80)) for r in rows])
    print(f"\n{'#':>3}  {'README command':<{width}}  {'seconds':>7}  result")
    for i, label, secs, res in rows:
        print(f"{i:>3}  {short(label, 80):<{width}}  {'' if secs is None else f'{secs:.1f}':>7}  {res}")
    print(f"\n{ran} run, {len(failed)} failed, {sum(1 for r in rows if r[3].startswith('SKIP'))} skipped; "
          f"logs in {os.path.join(scratch, 'logs')}")
    if failed:
        return 1
    return 0 if ran else 77


# ---- --help and --version --------------------------------------------------------
BAD_OPTION = "--no-such-option"


def cmd_help(args):
    source, build = os.path.abspath(args.source), os.path.abspath(args.build)
    scratch = os.path.abspath(args.scratch or os.path.join(build, "tests", "readme", "scratch_help"))
    repo = make_scratch(source, build, scratch)
    env = command_env(build)
    checks = []
    # Every script (a file with a #! line; it must be executable: its --help then fails
    # with 126 when it is not); a module the scripts import (tools/elaslam_tool.py) is none.
    def is_script(f):
        with open(os.path.join(source, "tools", f), "rb") as fh:
            return fh.read(2) == b"#!"
    tools = sorted(f for f in os.listdir(os.path.join(source, "tools")) if f.endswith((".sh", ".py")) and is_script(f))
    for f in tools:
        for flag in ("--help", "-h"):
            checks.append((f"tools/{f} {flag}", f, "script"))
        checks.append((f"tools/{f} {BAD_OPTION}", f, "bad"))
        if f.endswith(".py") or f == "spy.sh":  # installed as elaslam-* programs: --version too
            checks.append((f"tools/{f} --version", f, "version"))
    bindir = os.path.join(build, "bin")
    progs = sorted(programs_in(build))
    for p in progs:
        checks.append((f"build/bin/{p} --help", p, "program"))
        if not p.startswith("bench_"):  # Google Benchmark programs have no --version
            checks.append((f"build/bin/{p} --version", p, "version"))
    if not progs:
        print(f"no programs in {bindir}: build first")
        return 1
    failed, help_failed = 0, set()
    print(f"{'command':<44} {'exit':>4} {'lines':>5}  result")
    for i, (cmd, name, kind) in enumerate(checks):
        if kind == "bad" and name in help_failed:
            # A script that ignores --help may well do real work with an unknown option.
            print(f"{cmd:<44} {'':>4} {'':>5}  FAIL: not run (its --help failed)")
            failed += 1
            continue
        log_path = os.path.join(scratch, "logs", f"help{i:02d}.log")
        rc, secs, timed_out, out = run_one(cmd, repo, env, log_path, args.timeout)
        body = out.split("\n", 1)[1] if "\n" in out else ""
        stem = os.path.splitext(name)[0]
        want_rc, want_text = (2, BAD_OPTION) if kind == "bad" else (0, stem)
        if kind == "version":
            want_text = f"{stem} (elaslam "  # "<program> (elaslam <version>, git <commit>)"
        if name.startswith("bench_"):
            want_text = ""  # Google Benchmark's help says "benchmark", not the program's name
        problems = []
        if timed_out:
            problems.append(f"timed out after {args.timeout:g} s")
        elif rc != want_rc:
            problems.append(f"exit status {rc}, not {want_rc}")
        if not body.strip():
            problems.append("no output")
        elif want_text not in body:
            problems.append(f"output does not name {want_text}")
        res = "ok" if not problems else "FAIL: " + "; ".join(problems)
        n_lines = len(body.strip().split("\n")) if body.strip() else 0
        print(f"{cmd:<44} {rc:>4} {n_lines:>5}  {res}")
        if problems:
            failed += 1
            help_failed.add(name)
            print("\n".join("    | " + t for t in body.rstrip().split("\n")[-8:]))
    print(f"\n{len(checks)} checks, {failed} failed")
    return 1 if failed else 0


def main():
    default_source = os.path.dirname(os.path.dirname(HERE))
    ap = argparse.ArgumentParser(prog="readme_check.py", description=__doc__.split("\n\n")[0],
                                 epilog=__doc__.split("\n\n", 1)[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    for name in ("extract", "check", "run", "help"):
        s = sub.add_parser(name)
        s.add_argument("--source", default=default_source, help="the source tree (default: this file's ../..)")
        s.add_argument("--build", required=name in ("run", "help"), default=None,
                       help="the build directory (its bin/ has the programs)")
        s.add_argument("--table", default=os.path.join(HERE, "commands.txt"))
        if name in ("run", "help"):
            s.add_argument("--scratch", help="scratch directory (default: BUILD/tests/readme/scratch[_help]); "
                                             "emptied first")
        if name == "run":
            s.add_argument("--only", help="run only the entries whose command matches this regex")
            s.add_argument("--fresh", action="store_true",
                           help="run the commands in a git clone of the source's HEAD with nothing built "
                                "(a new user's order: the first command builds what the team needs, "
                                "`cmake --build build` the rest); needs root")
        if name == "extract":
            s.add_argument("--where", action="store_true", help="each command after its page and a tab")
        if name == "help":
            s.add_argument("--timeout", type=float, default=30.0, help="per command [s]")
    args = ap.parse_args()
    if args.cmd in ("run", "help") and os.environ.get(NESTED):
        print(f"readme_check: skipped: started by a command of a README test ({NESTED} is set; "
              "e.g. tools/run_tests.sh running ctest)")
        return 77
    if args.cmd == "extract":
        source = os.path.abspath(args.source)
        programs = project_programs(source)
        where = command_pages(source, programs)
        for c in readme_commands(source, programs):
            print(f"{where[c]}\t{c}" if args.where else c)
        return 0
    if args.cmd == "check":
        return 0 if check(os.path.abspath(args.source), args.build, args.table)[0] else 1
    if args.cmd == "run":
        return cmd_run(args)
    return cmd_help(args)


if __name__ == "__main__":
    sys.exit(main())
