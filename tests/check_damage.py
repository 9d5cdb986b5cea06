#!/usr/bin/env python3
"""Checks the damage pattern of a plate-with-a-hole run (fields.csv of one or more runs).

    check_damage.py --hole-radius R --near D [--symmetric] [--min-broken N] DIR [DIR2 ...]

- at least N bonds broken (summary.json);
- every damaged real particle (phi > 0) lies within D of the hole's edge, centred at the origin
  (damage starts at the hole);
- --symmetric: the damage field is symmetric about both axes: the mirror images of a damaged
  particle carry the same phi to 1e-9 (the lattice and loading are symmetric);
- with several folders (e.g. 1 and 2 MPI ranks): identical damage fields, particle by particle.
"""
import argparse
import csv
import json
import math
import os
import sys


def load(d):
    rows = {}
    with open(os.path.join(d, "fields.csv")) as f:
        for r in csv.DictReader(f):
            rows[int(r["id"])] = (float(r["x"]), float(r["y"]), float(r["damage"]), int(r["fictitious"]))
    with open(os.path.join(d, "summary.json")) as f:
        s = json.load(f)
    return rows, s


def fail(msg):
    print("FAILED: " + msg)
    sys.exit(1)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--hole-radius", type=float, required=True)
    ap.add_argument("--near", type=float, required=True)
    ap.add_argument("--symmetric", action="store_true")
    ap.add_argument("--min-broken", type=int, default=1)
    ap.add_argument("dirs", nargs="+")
    a = ap.parse_args()
    rows, s = load(a.dirs[0])
    if not s["converged"]:
        fail("run did not converge: " + s.get("failure", ""))
    if s["broken_bonds_total"] < a.min_broken:
        fail(f"only {s['broken_bonds_total']} bonds broken")
    damaged = [(x, y, phi) for (x, y, phi, fic) in rows.values() if phi > 0 and not fic]
    print(f"{s['broken_bonds_total']} bonds broken, {len(damaged)} damaged particles")
    for x, y, phi in damaged:
        dist = math.hypot(x, y) - a.hole_radius
        if dist > a.near:
            fail(f"damaged particle at ({x}, {y}) is {dist:.3g} from the hole, more than {a.near}")
    if a.symmetric:
        pos = {(round(x, 6), round(y, 6)): phi for (x, y, phi, fic) in rows.values()}
        for x, y, phi in damaged:
            for mx, my in ((-x, y), (x, -y), (-x, -y)):
                other = pos.get((round(mx, 6), round(my, 6)))
                if other is None or abs(other - phi) > 1e-9:
                    fail(f"damage not symmetric: phi({x},{y}) = {phi}, phi({mx},{my}) = {other}")
    # The u_x profile along the horizontal axis (Fig. 32) is odd in x: u_x(-x) = -u_x(x).
    prof = os.path.join(a.dirs[0], "profile_horizontal_axis.csv")
    if os.path.exists(prof):
        with open(prof) as f:
            pts = {(round(float(r["x"]), 6), round(float(r["y"]), 6)): float(r["ux"]) for r in csv.DictReader(f)}
        scale = max(abs(v) for v in pts.values())
        for (x, y), ux in pts.items():
            other = pts.get((round(-x, 6), y))
            if other is None or abs(other + ux) > 1e-8 * scale:
                fail(f"u_x profile not antisymmetric at x = {x}: {ux} vs {other}")
        print(f"u_x profile along the horizontal axis: {len(pts)} particles, antisymmetric")
    elif a.symmetric:
        fail("no profile_horizontal_axis.csv written")
    for d in a.dirs[1:]:
        r2, s2 = load(d)
        if s2["broken_bonds_total"] != s["broken_bonds_total"]:
            fail(f"{d}: {s2['broken_bonds_total']} bonds broken, reference {s['broken_bonds_total']}")
        for pid, v in rows.items():
            if abs(r2[pid][2] - v[2]) > 1e-12:
                fail(f"{d}: damage of particle {pid} differs: {r2[pid][2]} vs {v[2]}")
        print(f"{d} ({s2['ranks']} ranks): identical damage field")
    print("PASSED")


if __name__ == "__main__":
    main()
