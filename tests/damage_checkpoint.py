#!/usr/bin/env python3
"""Copies a checkpoint folder and damages the copy (for the bad-input tests of damaged checkpoints).

    damage_checkpoint.py SOURCE_DIR DEST_DIR KEY      remove KEY from state.json
    damage_checkpoint.py SOURCE_DIR DEST_DIR :value   replace the first displacement in rank_0.txt by a non-number
    damage_checkpoint.py SOURCE_DIR DEST_DIR KEY=JSON set KEY of state.json to a value no run writes
    damage_checkpoint.py SOURCE_DIR DEST_DIR scene-:Sublist/Key
                                                      remove the parameter Sublist/Key from the scene kept
                                                      in state.json (as a perinox older than the key wrote it)
"""
import re
import json
import shutil
import sys

src, dst, what = sys.argv[1:4]
shutil.rmtree(dst, ignore_errors=True)
shutil.copytree(src, dst)
if what == ":value":
    path = dst + "/rank_0.txt"
    with open(path) as f:
        lines = f.read().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("x "))
    parts = lines[k].split()
    parts[2] = "0x1.zzp+3"
    lines[k] = " ".join(parts)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"damaged line {k + 1} of {path}: {lines[k]}")
    sys.exit(0)
path = dst + "/state.json"
with open(path) as f:
    state = json.load(f)
if what.startswith("scene-:"):
    *subs, name = what[len("scene-:"):].split("/")
    xml = state["scene"]
    attrs = r'(?:[^>"]|"[^"]*")*'  # a tag's attributes, each quoted value taken whole
    # Find the sublists in turn, then the parameter inside the last one.
    at = 0
    for sub in subs:
        m = re.compile(r'<ParameterList\b' + attrs + r'\bname="' + re.escape(sub) + r'"' + attrs + r'>').search(xml, at)
        if not m:
            sys.exit(f"FAILED: no sublist {sub!r} in the scene of {path}")
        at = m.end()
    m = re.compile(r'\s*<Parameter\b' + attrs + r'\bname="' + re.escape(name) + r'"' + attrs + r'/>').search(xml, at)
    if not m:
        sys.exit(f"FAILED: no parameter {name!r} in the scene of {path}")
    state["scene"] = xml[:m.start()] + xml[m.end():]
    with open(path, "w") as f:
        json.dump(state, f)
    print(f"removed {what[len('scene-:'):]!r} from the scene in {path}")
    sys.exit(0)
if "=" in what:
    key, value = what.split("=", 1)
    if key not in state:
        sys.exit(f"FAILED: {path} has no key {key!r} to set")
    state[key] = json.loads(value)
    with open(path, "w") as f:
        json.dump(state, f)
    print(f"set {key!r} to {value} in {path}")
    sys.exit(0)
if what not in state:
    sys.exit(f"FAILED: {path} has no key {what!r} to remove")
del state[what]
with open(path, "w") as f:
    json.dump(state, f)
print(f"removed {what!r} from {path}")
