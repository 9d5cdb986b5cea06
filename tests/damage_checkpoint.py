#!/usr/bin/env python3
"""Copies a checkpoint folder and removes one key from its state.json (for the bad-input test of
a damaged checkpoint).

    damage_checkpoint.py SOURCE_DIR DEST_DIR KEY
"""
import json
import shutil
import sys

src, dst, key = sys.argv[1:4]
shutil.rmtree(dst, ignore_errors=True)
shutil.copytree(src, dst)
path = dst + "/state.json"
with open(path) as f:
    state = json.load(f)
if key not in state:
    sys.exit(f"FAILED: {path} has no key {key!r} to remove")
del state[key]
with open(path, "w") as f:
    json.dump(state, f)
print(f"removed {key!r} from {path}")
