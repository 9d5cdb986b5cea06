#!/usr/bin/env python3
"""Copies a checkpoint folder without its material-state lines ("state GID ...").

    strip_checkpoint_states.py SRC DST

For the bad-input test of a checkpoint that lacks the committed state a plastic scene needs.
"""
import os
import shutil
import sys

src, dst = sys.argv[1], sys.argv[2]
shutil.rmtree(dst, ignore_errors=True)
shutil.copytree(src, dst)
for name in os.listdir(dst):
    if name.startswith("rank_") and name.endswith(".txt"):
        path = os.path.join(dst, name)
        with open(path) as f:
            lines = [line for line in f if not line.startswith("state ")]
        with open(path, "w") as f:
            f.writelines(lines)
