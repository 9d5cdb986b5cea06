#!/usr/bin/env python3
"""Krylov iterations per linear solve must not grow by more than a factor as the particles grow.

    check_krylov_growth.py --max-ratio R SMALL_DIR LARGE_DIR

Both runs must have converged; the mean Krylov iterations per linear solve of the large run
(krylov_iterations_total / linear_solves_total in summary.json) may be at most R times the small
run's. Counts, not times: the result does not depend on the machine's load.
"""
import argparse
import json
import os
import sys


def per_solve(d):
    with open(os.path.join(d, "summary.json")) as f:
        s = json.load(f)
    if not s.get("converged"):
        print(f"FAILED: the run in {d} did not converge")
        sys.exit(1)
    solves = s["linear_solves_total"]
    if solves <= 0:
        print(f"FAILED: the run in {d} made no linear solve")
        sys.exit(1)
    return s["krylov_iterations_total"] / solves, s["particles"] if "particles" in s else None


ap = argparse.ArgumentParser()
ap.add_argument("--max-ratio", type=float, required=True)
ap.add_argument("small")
ap.add_argument("large")
a = ap.parse_args()
ks, ns = per_solve(a.small)
kl, nl = per_solve(a.large)
ratio = kl / ks
print(f"Krylov iterations per solve: {ks:.1f} ({ns} particles) -> {kl:.1f} ({nl} particles), ratio {ratio:.2f}")
if ratio > a.max_ratio:
    print(f"FAILED: the ratio exceeds {a.max_ratio}")
    sys.exit(1)
print("PASSED")
