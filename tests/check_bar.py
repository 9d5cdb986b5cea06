#!/usr/bin/env python3
"""Oscillation of the 1D variable-modulus bar (seed 001, 5.1) against its analytic solution.

    check_bar.py DIR --max-zigzag Z | --min-zigzag Z  [--max-ae A]

Strain is measured between neighbouring particles, eps_{i+1/2} = (u_{i+1} - u_i) / dx. On the left
half the exact strain is the constant alpha, so its second difference (the zigzag) measures the
zero-energy-mode oscillation: for the stress-point scheme the interior equations are the
three-point stencil of seed 001 eq. 12, whose solution on a uniform segment is exactly linear,
so the zigzag is round-off (bound 1e-6 alpha); without control the even and odd particles
decouple and the zigzag is of the order of the strain itself. a_e is seed 001 eq. 21 on the left half.
"""
import argparse
import csv
import math
import os
import sys

a, b = 0.001, 0.004 * math.sqrt(2)


def e_exact(x):
    return a + (b / (2 * math.sqrt(x - 0.5)) if x > 0.5 else 0.0)


ap = argparse.ArgumentParser()
ap.add_argument("dir")
ap.add_argument("--max-zigzag", type=float)
ap.add_argument("--min-zigzag", type=float)
ap.add_argument("--max-ae", type=float)
o = ap.parse_args()
rows = sorted((float(r["x"]), float(r["ux"])) for r in csv.DictReader(open(os.path.join(o.dir, "fields.csv"))))
x = [r[0] for r in rows]
u = [r[1] for r in rows]
e = [(u[i + 1] - u[i]) / (x[i + 1] - x[i]) for i in range(len(x) - 1)]
xm = [(x[i + 1] + x[i]) / 2 for i in range(len(x) - 1)]
zig = max(abs(e[i + 1] - 2 * e[i] + e[i - 1]) for i in range(1, len(e) - 1) if xm[i] < 0.45) / a
ae = max(abs(e[i] - e_exact(xm[i])) / e_exact(xm[i]) for i in range(len(e)) if xm[i] < 0.45)
print(f"strain zigzag on the left half: {zig:.3e} alpha; max a_e there: {ae:.3e}")
ok = True
if o.max_zigzag is not None and not zig <= o.max_zigzag:
    print(f"FAILED: zigzag above {o.max_zigzag}")
    ok = False
if o.min_zigzag is not None and not zig >= o.min_zigzag:
    print(f"FAILED: zigzag below {o.min_zigzag} (expected the oscillation)")
    ok = False
if o.max_ae is not None and not ae <= o.max_ae:
    print(f"FAILED: a_e above {o.max_ae}")
    ok = False
sys.exit(0 if ok else 1)
