#!/usr/bin/env python3
"""Checks the damage pattern of a plate-with-a-hole run (fields.csv of one or more runs).

    check_damage.py --hole-radius R [--near D] [--symmetric] [--min-broken N]
                    [--to-the-end] [--symmetric-within H] [--crack-to-edges W] DIR [DIR2 ...]

- at least N bonds broken (summary.json);
- every damaged real particle (phi > 0) lies within D of the hole's edge, centred at the origin
  (damage starts at the hole);
- --symmetric: the damage field is symmetric about both axes: the mirror images of a damaged
  particle carry the same phi to 1e-9 (the lattice and loading are symmetric);
- --to-the-end: the run reached load factor 1 and every recorded step converged;
- --symmetric-within H: every particle with phi >= 0.5 has, at each of its three mirror images
  about the axes, a particle with phi >= 0.25 within H (one particle spacing: the event-by-event
  stall breaks may pick one of two mirror-image bond groups first);
- --crack-to-edges W: every row of real particles between the hole (|y| > R) and the free edges
  holds a particle with phi >= 0.5 within |x| <= W of the vertical axis (the crack runs from the
  hole to both free edges, perpendicular to the load);
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
    ap.add_argument("--near", type=float, default=None)
    ap.add_argument("--to-the-end", action="store_true")
    ap.add_argument("--symmetric-within", type=float, default=None)
    ap.add_argument("--crack-to-edges", type=float, default=None)
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
    if a.to_the_end:
        lf = s["steps"][-1]["load_factor"] if s["steps"] else 0.0
        if abs(lf - 1.0) > 1e-12:
            fail(f"the run ended at load factor {lf}, not 1")
        print(f"{len(s['steps'])} steps, all converged, load factor 1 reached")
    if a.symmetric_within is not None:
        H = a.symmetric_within
        real = [(x, y, phi) for (x, y, phi, fic) in rows.values() if not fic]
        for x, y, phi in real:
            if phi < 0.5:
                continue
            for mx, my in ((-x, y), (x, -y), (-x, -y)):
                if not any(math.hypot(px - mx, py - my) <= H + 1e-9 and pphi >= 0.25 for px, py, pphi in real):
                    fail(f"damage not symmetric within {H}: phi({x},{y}) = {phi}, nothing damaged near ({mx},{my})")
        print(f"damage symmetric about both axes within {H}")
    if a.crack_to_edges is not None:
        ys = sorted({round(y, 9) for (x, y, phi, fic) in rows.values() if not fic and abs(y) > a.hole_radius})
        for yr in ys:
            cand = [phi for (x, y, phi, fic) in rows.values()
                    if not fic and abs(round(y, 9) - yr) < 1e-9 and abs(x) <= a.crack_to_edges]
            if not cand or max(cand) < 0.5:
                fail(f"the crack does not cross the row y = {yr} within |x| <= {a.crack_to_edges} (max phi {max(cand) if cand else None})")
        print(f"the crack crosses all {len(ys)} rows between the hole and the free edges within |x| <= {a.crack_to_edges}")
    for x, y, phi in damaged:
        if a.near is None:
            break
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
