#!/usr/bin/env python3
"""Runs a command that must fail with exit code 2 and one stderr line containing TEXT.

    expect_refusal.py TEXT -- COMMAND...
"""
import subprocess
import sys

i = sys.argv.index("--")
text, cmd = sys.argv[1], sys.argv[i + 1:]
r = subprocess.run(cmd, capture_output=True, text=True)
lines = [l for l in r.stderr.splitlines() if l.strip()]
if r.returncode != 2 or len(lines) != 1 or text not in lines[0]:
    print(f"CHECK FAILED: exit {r.returncode}, stderr {r.stderr!r}")
    sys.exit(1)
print("refused: " + lines[0])
