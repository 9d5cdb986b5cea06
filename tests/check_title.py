#!/usr/bin/env python3
"""Runs a perinox command and checks that summary.json's title is the given text (U+00E9, four hex digits, in TEXT
stands for that character), i.e. the scene's character references were read as the characters.

    check_title.py --title TEXT -- COMMAND... --output DIR ...
"""
import json
import re
import os
import subprocess
import sys

argv = sys.argv[1:]
split = argv.index("--")
title = re.sub(r"U\+([0-9a-fA-F]{4})", lambda m: chr(int(m.group(1), 16)), argv[argv.index("--title") + 1])
cmd = argv[split + 1:]
out = cmd[cmd.index("--output") + 1]
p = subprocess.run(cmd)
if p.returncode != 0:
    sys.exit(f"FAILED: exit {p.returncode}")
with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
    got = json.load(f)["title"]
if got != title:
    sys.exit(f"FAILED: title {got!r}, expected {title!r}")
print(f"title {got!r}: PASSED")
