#!/usr/bin/env python3
"""Copies a checkpoint folder and damages the copy (for the bad-input tests of damaged checkpoints).

    damage_checkpoint.py SOURCE_DIR DEST_DIR KEY      remove KEY from state.json
    damage_checkpoint.py SOURCE_DIR DEST_DIR :value   replace the first displacement in rank_0.txt by a non-number
    damage_checkpoint.py SOURCE_DIR DEST_DIR KEY=JSON set KEY of state.json to a value no run writes
"""
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
