#!/usr/bin/env python3
"""Markdown table of the hard-case runs that `ctest -L hard` leaves in build/test-output.

    python3 tools/hard_table.py [build/test-output]
"""
import json
import os
import sys

root = sys.argv[1] if len(sys.argv) > 1 else "build/test-output"
print("| run | outcome | load steps | cut-backs | Newton iterations | all attempts | Krylov iterations | wall time |")
print("|---|---|---|---|---|---|---|---|")
for name in sorted(os.listdir(root)):
    if not name.startswith("hard_"):
        continue
    path = os.path.join(root, name, "summary.json")
    if not os.path.exists(path):
        continue
    with open(path) as f:
        s = json.load(f)
    outcome = "converged" if s["converged"] else "stopped: " + s.get("failure", "")[:90]
    steps = s["steps"]
    print(f"| {name[5:]} | {outcome} | {len(steps)} | {sum(st['cutbacks'] for st in steps)} | "
          f"{sum(st['newton_iterations'] for st in steps)} | {s.get('newton_iterations_total', '')} | "
          f"{s.get('krylov_iterations_total', '')} | {s['wall_time_s']:.1f} s |")
