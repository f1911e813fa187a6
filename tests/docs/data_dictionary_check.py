#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Every JSON key and CSV column of the given output files is in docs/data_dictionary.md.

  data_dictionary_check.py DICTIONARY FILE...   (*.json: every key path; *.csv: the header)

Key paths: "a.b" for nested objects, "[]" for list elements ("robots[].id"); a
top-level list (report.json) is read as its elements; the effective `config` object
is one documented key (its keys are config/paper.yaml's). The dictionary's tables
list keys in backticks in their first column; "`a.p50`, `.p99`" continues the
previous key's stem; <R> is a robot id, <CHANNEL> a channel, <Q> range_m or
bearing_rad, <SPAN> run, first_half or second_half, <KEY> and * anything. Exit 1 naming every undocumented key.
"""
import csv
import json
import re
import sys

PLACEHOLDERS = {"<R>": r"\d+", "<CHANNEL>": r"[A-Za-z0-9_]+", "<Q>": r"(range_m|bearing_rad)",
                "<SPAN>": r"(run|first_half|second_half)", "<KEY>": r".+"}


def documented(path):
    patterns = []
    for line in open(path, encoding="utf-8"):
        if not line.startswith("| `"):
            continue
        first = line.split("|")[1]
        stem = ""
        for token in re.findall(r"`([^`]+)`", first):
            if token.startswith(".") and stem:
                token = stem + token
            stem = token.rsplit(".", 1)[0] if "." in token else token
            rx = re.escape(token)
            for k, v in PLACEHOLDERS.items():
                rx = rx.replace(re.escape(k), v)
            rx = rx.replace(r"\*", r".+")
            patterns.append(re.compile(rx + r"$"))
    return patterns


def json_keys(value, prefix, out):
    if isinstance(value, dict):
        for k, v in value.items():
            key = f"{prefix}.{k}" if prefix else k
            if key == "config":
                out.add(key)
                continue
            json_keys(v, key, out)
    elif isinstance(value, list):
        if prefix:
            out.add(prefix)
        for v in value:  # objects in a list; a list of lists ([from, to] ranges) is one key
            if isinstance(v, dict):
                json_keys(v, prefix + "[]" if prefix else "", out)
    else:
        out.add(prefix)


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    patterns = documented(sys.argv[1])
    missing = []
    checked = 0
    for f in sys.argv[2:]:
        keys = set()
        if f.endswith(".json"):
            json_keys(json.load(open(f)), "", keys)
        else:
            keys = set(next(csv.reader(open(f))))
        for k in sorted(keys):
            checked += 1
            if not any(p.match(k) for p in patterns):
                missing.append(f"{f}: {k}")
    if missing:
        print("undocumented in " + sys.argv[1] + ":\n  " + "\n  ".join(missing))
        return 1
    print(f"data dictionary: {checked} keys and columns of {len(sys.argv) - 2} files documented")
    return 0


if __name__ == "__main__":
    sys.exit(main())
