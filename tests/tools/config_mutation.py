#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Mutated configurations against every program that reads one (docs/security.md).

  tests/tools/config_mutation.py --bin BUILD/bin [--count N] [--seed S] [--jobs J]
                                 [--timeout SECONDS] [--keep DIR] [--source ROOT]

Makes N mutants of config/paper.yaml and config/mrclam.yaml (text-level mutations,
seeded: the same N and S give the same files), runs every config-reading program on
each with the cheapest command line that loads it (`--check` where the program has
one, found from its --help; else a short run; --no-check: the short runs wherever
the program had no --check before, to compare builds), and counts the outcomes per program:
exit 0, 1, 2, other exits, signals (SIGABRT: an escaped exception), timeouts, and
failures that said nothing on stderr. Exit status 1 when any run died by a signal,
timed out, exited with a code other than 0/1/2, or failed silently; else 0.
"""

import argparse
import collections
import os
import random
import signal
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# Replacement values: non-finite and extreme numbers, wrong types, YAML oddities.
VALUES = [
    "nan", ".nan", "NaN", ".NAN", "inf", ".inf", "-.inf", "+.inf", "infinity", "-Infinity", "1e309", "-1e309",
    "1e-400", "-1", "0", "-0", "-0.0", "1", "2147483647", "2147483648", "-2147483649", "99999999999999999999",
    "0x7fffffff", "0o17", "1_000", "1e6", "-1e6", "1.5", "3", "12abc", "~", "null", "''", '""', "[]", "{}",
    "[1, 2]", "[nan, inf, 1]", "{a: 1}", "true", "false", "no", "yes", "x", '"nan"', "!!float nan", "!!str 3",
    "!custom 1", "!!binary aGVsbG8=", "&anchor 1", "*undefined_alias", "'\\xff'", '"\\0"', '"\\u0000"',
    '"\\xff"', "|\n  literal", ">-\n  folded", "? complex", "- item", "@reserved", "`tick", "%directive",
]

NON_SCALAR_KEYS = ["? [a, b]\n: 1", "[a, b]: 1", "{a: 1}: 2", "? {x: 1}\n: 1", "? - a\n  - b\n: 3", "[]: 1",
                   "? !!null\n: 1", "~: 1", "'': 1", "? [nan]\n: [inf]"]

GARBAGE = [b"\x00", b"\xff", b"\xc3\x28", b"\xe2\x82", b"\xed\xa0\x80", b"\xfe\xff", b"\xef\xbb\xbf", b"\r",
           b"\t", b"\x1b[31m", b"\x7f", b"\x00\x00\x00", b":", b"- ", b"{", b"[", b"'", b'"', b"&", b"*", b"!",
           b"|", b">", b"%", b"#", b"---", b"...", b"\n"]


def key_lines(lines):
    """Indices of lines that hold `key: value` or `key:` (not comments, not blank)."""
    out = []
    for i, l in enumerate(lines):
        s = l.strip()
        if s and not s.startswith("#") and ":" in s:
            out.append(i)
    return out


def indent_of(line):
    return len(line) - len(line.lstrip(" "))


def m_value(rng, lines):
    ks = [i for i in key_lines(lines) if not lines[i].rstrip().endswith(":")]
    if not ks:
        return
    i = rng.choice(ks)
    line = lines[i]
    comment = ""
    if " #" in line:
        line, comment = line.split(" #", 1)
        comment = " #" + comment
    head, _, val = line.partition(": ")
    if not _:
        return
    v = val.strip()
    choice = rng.random()
    if choice < 0.6:
        new = rng.choice(VALUES)
    else:  # a perturbed number: scale, sign, tiny and huge
        try:
            x = float(v)
            new = repr(rng.choice([x * 10 ** rng.randint(1, 12), -x, x + 1e-12, x * 1e-12, x / 3.0, 0.0]))
        except ValueError:
            new = rng.choice(VALUES)
    if "\n" in new:
        new = new.replace("\n", "\n" + " " * (indent_of(line) + 2))
    lines[i] = head + ": " + new + comment


def m_delete(rng, lines):
    if lines:
        del lines[rng.randrange(len(lines))]


def m_duplicate(rng, lines):
    ks = key_lines(lines)
    if ks:
        i = rng.choice(ks)
        lines.insert(i + rng.randint(1, 3), lines[i])


def m_non_scalar_key(rng, lines):
    ks = key_lines(lines)
    if not ks:
        return
    i = rng.choice(ks)
    pad = " " * indent_of(lines[i])
    entry = rng.choice(NON_SCALAR_KEYS)
    lines.insert(i, "\n".join(pad + part for part in entry.split("\n")))


def m_second_document(rng, lines):
    tail = rng.choice(["---\n", "---\nscenario: {}\n", "---\n" + "\n".join(lines), "...\n---\nx: 1", "--- |\n  text"])
    lines.append(tail)


def m_indent(rng, lines):
    ks = key_lines(lines)
    if ks:
        i = rng.choice(ks)
        d = rng.choice([-4, -2, -1, 1, 2, 4])
        lines[i] = " " * max(0, indent_of(lines[i]) + d) + lines[i].lstrip(" ")


def m_swap(rng, lines):
    ks = key_lines(lines)
    if len(ks) > 1:
        i, j = rng.sample(ks, 2)
        lines[i], lines[j] = lines[j], lines[i]


def m_unknown_key(rng, lines):
    ks = key_lines(lines)
    if ks:
        i = rng.choice(ks)
        name = rng.choice(["bogus", "Frames", "rate_hz ", "seed\t", "robots2", "\u00e9t\u00e9", "x" * 300])
        lines.insert(i, " " * indent_of(lines[i]) + name + ": 1")


def m_rename_key(rng, lines):
    ks = [i for i in key_lines(lines) if lines[i].strip()[0].isalpha()]
    if ks:
        i = rng.choice(ks)
        s = lines[i]
        pos = indent_of(s)
        lines[i] = s[:pos] + rng.choice(["_", "X", "", "-"]) + s[pos + 1:]


def m_alias_bomb(rng, lines):
    levels = rng.randint(3, 9)
    bomb = ["lol0: &l0 [x, x, x, x, x, x, x, x, x]"]
    for k in range(1, levels):
        bomb.append("lol%d: &l%d [%s]" % (k, k, ", ".join(["*l%d" % (k - 1)] * 9)))
    lines[0:0] = bomb


def m_alias_value(rng, lines):
    ks = [i for i in key_lines(lines) if not lines[i].rstrip().endswith(":")]
    if len(ks) > 1:
        a, b = rng.sample(ks, 2)
        if ": " in lines[a] and ": " in lines[b]:
            head, _, val = lines[a].partition(": ")
            lines[a] = head + ": &m " + val
            head, _, _ = lines[b].partition(": ")
            lines[b] = head + ": *m"


def m_deep(rng, lines):
    ks = [i for i in key_lines(lines) if ": " in lines[i]]
    if ks:
        i = rng.choice(ks)
        n = rng.choice([50, 500, 5000])
        head, _, _ = lines[i].partition(": ")
        lines[i] = head + ": " + rng.choice(["[" * n + "]" * n, "{a: " * n + "1" + "}" * n])


def m_long_string(rng, lines):
    ks = [i for i in key_lines(lines) if ": " in lines[i]]
    if ks:
        i = rng.choice(ks)
        head, _, _ = lines[i].partition(": ")
        lines[i] = head + ": " + rng.choice(["a", "1", "9"]) * rng.choice([1000, 100000])


def m_merge_key(rng, lines):
    ks = key_lines(lines)
    if ks:
        i = rng.choice(ks)
        lines.insert(i, " " * indent_of(lines[i]) + rng.choice(["<<: {frames: 1}", "<<: *nothing", "<<: [1, 2]"]))


LINE_MUTATIONS = [m_value, m_value, m_value, m_delete, m_duplicate, m_duplicate, m_non_scalar_key, m_second_document,
                  m_indent, m_swap, m_unknown_key, m_rename_key, m_alias_bomb, m_alias_value, m_deep, m_long_string,
                  m_merge_key]


def b_garbage(rng, data):
    pos = rng.randrange(len(data) + 1)
    return data[:pos] + rng.choice(GARBAGE) + data[pos:]


def b_random(rng, data):
    pos = rng.randrange(len(data) + 1)
    return data[:pos] + bytes(rng.randrange(256) for _ in range(rng.randint(1, 64))) + data[pos:]


def b_truncate(rng, data):
    return data[:rng.randrange(len(data) + 1)]


def b_flip(rng, data):
    if not data:
        return data
    pos = rng.randrange(len(data))
    return data[:pos] + bytes([data[pos] ^ (1 << rng.randrange(8))]) + data[pos + 1:]


BYTE_MUTATIONS = [b_garbage, b_random, b_truncate, b_flip]


def mutate(rng, text):
    """1 to 3 mutations of `text` (bytes)."""
    data = text
    for _ in range(rng.choice([1, 1, 1, 2, 3])):
        if rng.random() < 0.75:
            lines = data.decode("utf-8", "surrogateescape").split("\n")
            rng.choice(LINE_MUTATIONS)(rng, lines)
            data = "\n".join(lines).encode("utf-8", "surrogateescape")
        else:
            data = rng.choice(BYTE_MUTATIONS)(rng, data)
    return data


def make_mutants(count, seed, out_dir, sources):
    rng = random.Random(seed)
    texts = [open(s, "rb").read() for s in sources]
    paths = []
    for n in range(count):
        k = n % len(texts)
        path = os.path.join(out_dir, "mutant_%05d_%s" % (n, os.path.basename(sources[k])))
        with open(path, "wb") as f:
            f.write(mutate(rng, texts[k]))
        paths.append(path)
    return paths


def programs(out, dataset, log):
    """name -> (arguments when the program has --check, arguments when it has not). Output paths start with `out`."""
    tiny = ["--dataset", dataset, "--robots", "1,2"]
    return {
        "simulator": (["--check"], ["--check"]),
        "robot_node": (["--robot", "1", "--check"], ["--robot", "1", "--check"]),
        "main_robot": (["--check"], ["--check"]),
        "scenario_dump": (["--check", "--out", os.devnull], ["--out", os.devnull]),
        "run_scenario": (["--check"], ["--frames", "2"]),
        "sweep": (["--check", "--out", out + "sweep"],
                  ["--runs", "1", "--modes", "ekf", "--dynamism", "5", "--speed", "0.1", "--jobs", "1", "--no-plots",
                   "--out", out + "sweep"]),
        "evaluate": (["--log", log, "--quiet"], ["--log", log, "--quiet"]),
        "run_dataset": (tiny + ["--check", "--out", out + "ds"], tiny + ["--no-plots", "--jobs", "1", "--out", out + "ds"]),
        "mrclam_import": (tiny + ["--check", "--out", out + "x.lcmlog"], tiny + ["--out", out + "x.lcmlog"]),
        "mrclam_stats": (tiny + ["--check"], tiny),
    }


def has_check(binary):
    try:
        out = subprocess.run([binary, "--help"], capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.SubprocessError):
        return False
    return "--check" in out


def run_one(binary, args, config, timeout):
    cmd = [binary, "--config", config] + args
    try:
        p = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return cmd, "timeout", b""
    if p.returncode < 0:
        return cmd, "signal " + signal.Signals(-p.returncode).name, p.stderr
    if p.returncode not in (0, 1, 2):
        return cmd, "exit %d" % p.returncode, p.stderr
    if p.returncode != 0 and not p.stderr.strip():
        return cmd, "silent exit %d" % p.returncode, p.stderr
    if b"terminate called" in p.stderr:
        return cmd, "uncaught exception", p.stderr
    return cmd, "exit %d" % p.returncode, p.stderr


def make_log(bin_dir, work, dataset, cfg):
    """A small LCM log with GROUND_TRUTH for evaluate (mrclam_import of the tiny dataset)."""
    log = os.path.join(work, "tiny.lcmlog")
    subprocess.run([os.path.join(bin_dir, "mrclam_import"), "--dataset", dataset, "--config", cfg, "--robots", "1,2",
                    "--out", log], capture_output=True, timeout=120)
    return log


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", required=True, help="the build's bin directory")
    ap.add_argument("--count", type=int, default=1000, help="mutants (default 1000)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=60.0, help="per run [s]; a run that takes longer is counted")
    ap.add_argument("--keep", help="copy the mutants of failed runs here")
    ap.add_argument("--programs", help="comma-separated subset of the programs")
    ap.add_argument("--no-check", action="store_true",
                    help="short runs even where a program has --check (the commands of a build without it)")
    ap.add_argument("--source", default=ROOT, help="repository root (its config/*.yaml are mutated)")
    a = ap.parse_args()
    bin_dir = os.path.abspath(a.bin)
    with tempfile.TemporaryDirectory(prefix="elaslam-mutants-") as work:
        sources = [os.path.join(a.source, "config", n) for n in ("paper.yaml", "mrclam.yaml")]
        dataset = os.path.join(a.source, "tests", "dataset", "data", "tiny")
        mutants = make_mutants(a.count, a.seed, work, sources)
        log = make_log(bin_dir, work, dataset, sources[1])
        out = os.path.join(work, "out") + "/"
        os.makedirs(out)
        progs = programs(out, dataset, log)
        if a.programs:
            progs = {k: v for k, v in progs.items() if k in a.programs.split(",")}
        jobs = []
        modes = {}
        for name, (with_check, without) in progs.items():
            binary = os.path.join(bin_dir, name)
            if not os.path.exists(binary):
                print("config_mutation: no %s: skipped" % binary)
                continue
            check = has_check(binary) and (not a.no_check or name in ("simulator", "robot_node", "main_robot"))
            modes[name] = "--check" if check else "run"
            for i, m in enumerate(mutants):
                # Each run gets its own output paths: parallel runs must not share a file.
                args = [x.replace(out, out + "%d_" % i) for x in (with_check if check else without)]
                jobs.append((name, binary, args, m))
        with ThreadPoolExecutor(max_workers=a.jobs) as ex:
            results = list(ex.map(lambda j: (j[0], j[3]) + run_one(j[1], j[2], j[3], a.timeout), jobs))
        counts = collections.defaultdict(collections.Counter)
        bad = []
        for name, mutant, cmd, outcome, err in results:
            counts[name][outcome] += 1
            if not outcome.startswith("exit"):
                bad.append((name, mutant, cmd, outcome, err))
        outcomes = sorted({o for c in counts.values() for o in c})
        print("config_mutation: %d mutants (seed %d) of %s x %d programs = %d runs" %
              (len(mutants), a.seed, ", ".join(os.path.basename(s) for s in sources), len(counts), len(results)))
        print("| program | how | " + " | ".join(outcomes) + " |")
        print("|---|---|" + "---|" * len(outcomes))
        total = collections.Counter()
        for name in progs:
            if name in counts:
                total.update(counts[name])
                print("| %s | %s | " % (name, modes[name]) + " | ".join(str(counts[name][o]) for o in outcomes) + " |")
        print("| all | | " + " | ".join(str(total[o]) for o in outcomes) + " |")
        aborts = sum(n for o, n in total.items() if o == "signal SIGABRT")
        signals = sum(n for o, n in total.items() if o.startswith("signal"))
        print("config_mutation: %d aborts, %d deaths by a signal, %d bad outcomes in all" % (aborts, signals, len(bad)))
        for name, mutant, cmd, outcome, err in bad[:20]:
            tail = err.decode("utf-8", "replace").strip().splitlines()[-3:]
            print("  %s: %s\n    %s\n    %s" % (name, outcome, " ".join(cmd), "\n    ".join(tail)))
        if a.keep and bad:
            os.makedirs(a.keep, exist_ok=True)
            for name, mutant, cmd, outcome, err in bad:
                dst = os.path.join(a.keep, name + "_" + os.path.basename(mutant))
                with open(mutant, "rb") as src, open(dst, "wb") as f:
                    f.write(src.read())
            print("config_mutation: the mutants of the bad runs are in %s" % a.keep)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
