#!/usr/bin/env python3
"""Objectivity at system level: the rotated run's final state is R (90 degrees) times the
unrotated one's. Reactions: r_rot = R r; every particle: X + u_rot = R (X + u).

    check_rotation.py UNROTATED_DIR ROTATED_DIR
"""
import csv
import json
import os
import sys


def R(v):
    return (-v[1], v[0])


a, b = sys.argv[1], sys.argv[2]
sa = json.load(open(os.path.join(a, "summary.json")))
sb = json.load(open(os.path.join(b, "summary.json")))
if not (sa["converged"] and sb["converged"]):
    print("FAILED: a run did not converge")
    sys.exit(1)
ra = sa["probes"]["reaction"][-1]["reaction"]
rb = sb["probes"]["reaction"][-1]["reaction"]
scale = max(abs(v) for v in ra)
err_r = max(abs(x - y) for x, y in zip(R(ra), rb)) / scale
fa = {int(r["id"]): r for r in csv.DictReader(open(os.path.join(a, "fields.csv")))}
fb = {int(r["id"]): r for r in csv.DictReader(open(os.path.join(b, "fields.csv")))}
err_x = 0.0
for pid, r in fa.items():
    xa = (float(r["x"]) + float(r["ux"]), float(r["y"]) + float(r["uy"]))
    q = fb[pid]
    xb = (float(q["x"]) + float(q["ux"]), float(q["y"]) + float(q["uy"]))
    rx = R(xa)
    err_x = max(err_x, abs(rx[0] - xb[0]), abs(rx[1] - xb[1]))
print(f"reaction: |R r - r_rot| / |r| = {err_r:.2e}; positions: max |R x - x_rot| = {err_x:.2e} m")
# Both runs converge to |R|/|reaction| < 1e-10; positions and reactions agree to ~1e-9.
if err_r > 1e-7 or err_x > 1e-9:
    print("FAILED")
    sys.exit(1)
print("PASSED")
