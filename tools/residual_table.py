#!/usr/bin/env python3
"""Prints the Newton residual table of a run (like seed 000's Tables 2-4) as Markdown.

    residual_table.py OUTDIR [--first 6 --last 10]
"""
import argparse
import json
import os

ap = argparse.ArgumentParser()
ap.add_argument("out")
ap.add_argument("--first", type=int, default=1)
ap.add_argument("--last", type=int, default=10**9)
a = ap.parse_args()
with open(os.path.join(a.out, "summary.json")) as f:
    s = json.load(f)
steps = [st for st in s["steps"] if a.first <= st["step"] <= a.last]
rows = max(len(st["residuals"]) for st in steps)
print("| iteration | " + " | ".join(f"step {st['step']}" for st in steps) + " |")
print("|---|" + "---|" * len(steps))
for i in range(rows):
    cells = [f"{st['residuals'][i]:.3e}" if i < len(st["residuals"]) else "-" for st in steps]
    print(f"| {i} | " + " | ".join(cells) + " |")
