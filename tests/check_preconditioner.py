#!/usr/bin/env python3
"""The Two-Stage preconditioner keeps its multigrid hierarchy while the auxiliary operator does
not change (summary.json "preconditioner").

    check_preconditioner.py --hierarchies N RUN_DIR    exactly N hierarchies built (lattice FEM: 1 a run)
    check_preconditioner.py --damage RUN_DIR           short horizon: at most one more hierarchy per
                                                       damage event (a break round, a step whose
                                                       bonds broke, a stall break) than the first

Both also require one set-up per linear solve. Counts only.
"""
import argparse
import json
import os
import sys

ap = argparse.ArgumentParser()
ap.add_argument("--hierarchies", type=int)
ap.add_argument("--damage", action="store_true")
ap.add_argument("run")
a = ap.parse_args()
with open(os.path.join(a.run, "summary.json")) as f:
    s = json.load(f)
p = s.get("preconditioner")
if not p:
    print("FAILED: no Two-Stage preconditioner statistics in summary.json")
    sys.exit(1)
print(f"set-ups {p['setups']}, hierarchies built {p['hierarchies_built']}, levels {p['levels']}, "
      f"linear solves {s['linear_solves_total']}")
if p["setups"] != s["linear_solves_total"]:
    print("FAILED: set-ups differ from linear solves")
    sys.exit(1)
if a.hierarchies is not None and p["hierarchies_built"] != a.hierarchies:
    print(f"FAILED: expected {a.hierarchies} hierarchies")
    sys.exit(1)
if a.damage:
    events = sum(st["break_rounds"] for st in s["steps"]) + sum(
        1 for st in s["steps"] if st["broken_bonds"] > 0 or st["stall_broken_bonds"] > 0) + s.get("stall_breaks", 0)
    if s.get("broken_bonds_total", 0) == 0:
        print("FAILED: no bond broke, so the damage path was not exercised")
        sys.exit(1)
    if p["hierarchies_built"] > 1 + events:
        print(f"FAILED: {p['hierarchies_built']} hierarchies for {events} damage events")
        sys.exit(1)
print("PASSED")
