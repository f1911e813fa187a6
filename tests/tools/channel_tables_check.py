#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The scripts' copies of the channel table agree with common/include/elaslam/common/channels.hpp
(ctest `channel_tables`; standard library only). The truth is printed by the test's
channel_table program, built from channels.hpp:

- tools/lcm_groups.sh: its LCM_GROUP_* numbers, lcm_group_of for every channel name
  and per-robot channel of robots 1 .. 17, and lcm_team_groups for teams of 1, 3 and
  16 robots (the groups of every channel of that team);
- tools/foxglove_bridge.py: GROUPS are the groups of the channels its handlers read,
  MAX_ROBOTS is contract::kMaxRobots;
- tools/decode_log.py: every channel has a type (one pattern of its table matches).

    channel_tables_check.py CHANNEL_TABLE_PROGRAM SOURCE_DIR
Exit 0 when all agree, 1 naming each disagreement.
"""
import ast
import json
import os
import re
import subprocess
import sys


def assigned(path, name):
    """The literal value of a module-level `name = ...` in a Python file."""
    for node in ast.parse(open(path, encoding="utf-8").read()).body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == name for t in node.targets):
            return ast.literal_eval(node.value)
    raise KeyError(f"{path}: no {name} = ...")


def main():
    prog, root = sys.argv[1], sys.argv[2]
    table = json.loads(subprocess.run([prog], check=True, capture_output=True, text=True).stdout)
    groups = table["groups"]
    fails = []

    def robots_of(channel):
        for p in table["robot_prefixes"]:
            if channel.startswith(p) and channel[len(p):].isdigit():
                return int(channel[len(p):])
        return None

    # ---- tools/lcm_groups.sh
    sh = os.path.join(root, "tools", "lcm_groups.sh")
    names = list(groups)
    script = (f'. "{sh}"; echo "$LCM_GROUP_TEAM $LCM_GROUP_OUTPUTS $LCM_GROUP_MAP $LCM_GROUP_OBSERVERS '
              f'$LCM_GROUP_POSES $LCM_GROUP_ROBOT $LCM_GROUP_LAST"; '
              f'for c in {" ".join(names)}; do lcm_group_of "$c"; done; '
              'for t in "1" "1 2 3" "$(seq -s " " 1 16)"; do echo $(lcm_team_groups $t); done')
    out = subprocess.run(["bash", "-c", script], check=True, capture_output=True, text=True).stdout.splitlines()
    consts = [int(v) for v in out[0].split()]
    want = [table[k] for k in ("group_team", "group_outputs", "group_map", "group_observers", "group_poses",
                               "group_robot")] + [table["channel_groups"] - 1]
    if consts != want:
        fails.append(f"lcm_groups.sh: LCM_GROUP_TEAM..LCM_GROUP_LAST {consts}, channels.hpp {want}")
    for name, got in zip(names, out[1:1 + len(names)]):
        if int(got) != groups[name]:
            fails.append(f"lcm_groups.sh: lcm_group_of {name} = {got}, channels.hpp's channel_group {groups[name]}")
    for team, got in zip(([1], [1, 2, 3], list(range(1, 17))), out[1 + len(names):]):
        used = sorted({g for c, g in groups.items() if robots_of(c) in (None, *team)})
        if sorted(int(g) for g in got.split()) != used:
            fails.append(f"lcm_groups.sh: lcm_team_groups {team} = {got}, channels.hpp's groups {used}")

    # ---- tools/foxglove_bridge.py
    bridge = os.path.join(root, "tools", "foxglove_bridge.py")
    text = open(bridge, encoding="utf-8").read()
    patterns = re.findall(r're\.compile\(r"([^"]+)"\)', text)
    read = sorted({g for c, g in groups.items() if any(re.fullmatch(p, c) for p in patterns)})
    if sorted(assigned(bridge, "GROUPS")) != read:
        fails.append(f"foxglove_bridge.py: GROUPS {assigned(bridge, 'GROUPS')}, the groups of the channels its "
                     f"handlers read {read}")
    if assigned(bridge, "MAX_ROBOTS") != table["max_robots"]:
        fails.append(f"foxglove_bridge.py: MAX_ROBOTS {assigned(bridge, 'MAX_ROBOTS')}, contract::kMaxRobots "
                     f"{table['max_robots']}")

    # ---- tools/decode_log.py
    decode = open(os.path.join(root, "tools", "decode_log.py"), encoding="utf-8").read()
    typed = re.findall(r'\(r"([^"]+)", T\.\w+\)', decode)
    for name in names:
        if not any(re.fullmatch(p, name) for p in typed):
            fails.append(f"decode_log.py: no type for {name}")

    for f in fails:
        print(f"FAIL: {f}")
    if fails:
        return 1
    print(f"channel_tables: {len(names)} channels; lcm_groups.sh, foxglove_bridge.py and decode_log.py agree "
          "with channels.hpp")
    return 0


if __name__ == "__main__":
    sys.exit(main())
