#!/usr/bin/env python3
"""Checks the damage pattern of a plate-with-a-hole run (fields.csv of one or more runs).

    check_damage.py --hole-radius R [--near D] [--symmetric] [--min-broken N]
                    [--to-the-end] [--symmetric-within H] [--crack-to-edges W] [--crack-band W]
                    DIR [DIR2 ...]

- at least N bonds broken (summary.json);
- every damaged real particle (phi > 0) lies within D of the hole's edge, centred at the origin
  (damage starts at the hole);
- --symmetric: the damage field is symmetric about both axes: the mirror images of a damaged
  particle carry the same phi to 1e-9 (the lattice and loading are symmetric);
- --to-the-end: the run reached load factor 1 and every recorded step converged;
- --symmetric-within H: every particle with phi >= 0.5 has, at each of its three mirror images
  about the axes, a particle with phi >= 0.25 within H (one particle spacing: the event-by-event
  stall breaks may pick one of two mirror-image bond groups first);
- --crack-to-edges W: the crack runs from the hole to both free edges, perpendicular to the load,
  and is open: every row of real particles between the hole (|y| > R) and the free edges holds,
  within |x| <= W of the vertical axis, two neighbouring particles of the row, both damaged
  (phi >= 0.25), across which u_x jumps by at least half the separation of the ends (u_x of the
  right fictitious layer minus the left one). Why not "a particle with phi >= 0.5": a straight
  crack between two particle columns cuts only the bonds that cross it, which is less than half
  of each neighbour's family (delta = 3.015 dx: 11 of 28 bonds inside, 7 of 17 on the free
  edge; measured beside the crack: phi 0.45-0.53 at G = 0.5, below 0.5 in 4 of the 6 rows, and
  0.40-0.47 at G = 1), so that test fails on a clean crack and passes on scattered damage with no
  separation; the opening is what tells a crack from diffuse damage;
- --crack-band W: the weaker form for a crack band several particles wide (the 150 x 50 plate,
  where damaged particles hang between the two halves next to the hole): every such row holds,
  within |x| <= W, a damaged particle (phi >= 0.25), and u_x of its rightmost particle within W
  minus that of its leftmost is at least half the separation of the ends;
- --stretch-far-ratio F (for a run without damage): the bond stretches at the last step, every
  bond of the scene's families (horizon factor and spacing from scene.resolved.xml, fictitious
  particles included). The largest stretch of a bond whose midpoint lies more than R + dx/2 from
  the vertical axis is at most F times the largest stretch of a bond crossing the vertical axis
  above or below the hole: the hole's stress concentration, not a spurious (zero-energy) mode,
  decides where bonds break first. Linear-elastic FEM on the 30 x 10 lattice gives 0.68
  (tools/ccx_plate_hole.py); the paper's G = 0.01 gives 1.00;
- --max-stretch S: the largest bond stretch at the last step is at most S;
- with several folders (e.g. 1 and 2 MPI ranks): identical damage fields, particle by particle.
"""
import argparse
import csv
import json
import math
import os
import re
import sys
import xml.etree.ElementTree as ET


def load(d):
    rows, ux = {}, {}
    with open(os.path.join(d, "fields.csv")) as f:
        for r in csv.DictReader(f):
            rows[int(r["id"])] = (float(r["x"]), float(r["y"]), float(r["damage"]), int(r["fictitious"]))
            ux[int(r["id"])] = float(r["ux"])
    with open(os.path.join(d, "summary.json")) as f:
        s = json.load(f)
    return rows, s, ux


def discretization(d):
    """Spacing and horizon of the lattice scene the run used (scene.resolved.xml)."""
    root = ET.parse(os.path.join(d, "scene.resolved.xml")).getroot()
    disc = next(e for e in root if e.tag == "ParameterList" and e.get("name") == "Discretization")
    par = {e.get("name"): e.get("value") for e in disc if e.tag == "Parameter"}
    nums = lambda v: [float(t) for t in re.findall(r"[-+0-9.eE]+", v)]
    lo, hi, n = nums(par["Lower Corner"]), nums(par["Upper Corner"]), nums(par["Particles"])
    dx = (hi[0] - lo[0]) / n[0]
    return dx, float(par["Horizon Factor"]) * dx


def bond_stretches(d):
    """[(x_i, y_i, x_j, y_j, stretch)] of every bond (i < j) of the families of run folder d at its
    last step: all particles within the horizon (as perinox builds them, fictitious included)."""
    dx, delta = discretization(d)
    pts = []
    with open(os.path.join(d, "fields.csv")) as f:
        for r in csv.DictReader(f):
            pts.append((float(r["x"]), float(r["y"]), float(r["ux"]), float(r["uy"])))
    r2 = (delta * (1 + 1e-12)) ** 2
    cells = {}
    for k, p in enumerate(pts):
        cells.setdefault((math.floor(p[0] / delta), math.floor(p[1] / delta)), []).append(k)
    out = []
    for i, (xi, yi, uxi, uyi) in enumerate(pts):
        cx, cy = math.floor(xi / delta), math.floor(yi / delta)
        for ox in (-1, 0, 1):
            for oy in (-1, 0, 1):
                for j in cells.get((cx + ox, cy + oy), ()):
                    if j <= i:
                        continue
                    xj, yj, uxj, uyj = pts[j]
                    ex, ey = xj - xi, yj - yi
                    if ex * ex + ey * ey > r2:
                        continue
                    ln = math.hypot(ex, ey)
                    out.append((xi, yi, xj, yj, math.hypot(ex + uxj - uxi, ey + uyj - uyi) / ln - 1.0))
    return dx, out


def fail(msg):
    print("FAILED: " + msg)
    sys.exit(1)


def rows_beside_hole(rows, ux, hole_radius, option):
    """The end separation (u_x of the right fictitious layer minus the left one), the y of the
    rows of real particles between the hole and the free edges, and a function giving a row's
    (x, phi, u_x), sorted by x."""
    fict_ux = [ux[pid] for pid, (x, y, phi, fic) in rows.items() if fic]
    if not fict_ux:
        fail(option + " needs the fictitious end layers (their u_x is the end separation)")
    ys = sorted({round(y, 9) for (x, y, phi, fic) in rows.values() if not fic and abs(y) > hole_radius})
    row_of = lambda yr: sorted((x, phi, ux[pid]) for pid, (x, y, phi, fic) in rows.items()
                               if not fic and abs(round(y, 9) - yr) < 1e-9)
    return max(fict_ux) - min(fict_ux), ys, row_of


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--hole-radius", type=float, required=True)
    ap.add_argument("--near", type=float, default=None)
    ap.add_argument("--to-the-end", action="store_true")
    ap.add_argument("--symmetric-within", type=float, default=None)
    ap.add_argument("--crack-to-edges", type=float, default=None)
    ap.add_argument("--crack-band", type=float, default=None)
    ap.add_argument("--symmetric", action="store_true")
    ap.add_argument("--min-broken", type=int, default=1)
    ap.add_argument("--stretch-far-ratio", type=float, default=None)
    ap.add_argument("--max-stretch", type=float, default=None)
    ap.add_argument("--limit-breaks", type=int, default=None,
                    help="at least this many stall breaks made at a snap-back's limit (Damage/After Snap-Back = "
                         "Break Most Stretched); 0: none at all")
    ap.add_argument("dirs", nargs="+")
    a = ap.parse_args()
    rows, s, ux = load(a.dirs[0])
    if not s["converged"]:
        fail("run did not converge: " + s.get("failure", ""))
    if s.get("broken_bonds_total", 0) < a.min_broken:
        fail(f"only {s.get('broken_bonds_total', 0)} bonds broken")
    if a.limit_breaks is not None:
        at_limit = sum(1 for st in s["steps"] if st.get("stall_at_limit", False))
        print(f"{at_limit} stall break(s) at a snap-back's limit")
        if a.limit_breaks == 0 and at_limit > 0:
            fail(f"{at_limit} stall break(s) at a snap-back's limit, none expected")
        if at_limit < a.limit_breaks:
            fail(f"only {at_limit} stall break(s) at a snap-back's limit, at least {a.limit_breaks} expected")
    damaged = [(x, y, phi) for (x, y, phi, fic) in rows.values() if phi > 0 and not fic]
    print(f"{s.get('broken_bonds_total', 0)} bonds broken, {len(damaged)} damaged particles")
    if a.stretch_far_ratio is not None or a.max_stretch is not None:
        dx, bonds = bond_stretches(a.dirs[0])
        where = lambda b: f"{b[4]:.5g} (bond ({b[0]:g}, {b[1]:g})-({b[2]:g}, {b[3]:g}))"
        top = max(bonds, key=lambda b: b[4])
        print(f"{len(bonds)} bonds, largest stretch {where(top)}")
        if a.max_stretch is not None and top[4] > a.max_stretch:
            fail(f"the largest bond stretch {where(top)} exceeds {a.max_stretch}")
        if a.stretch_far_ratio is not None:
            R = a.hole_radius
            near = [b for b in bonds if b[0] * b[2] < 0 and abs(0.5 * (b[1] + b[3])) > R]
            far = [b for b in bonds if abs(0.5 * (b[0] + b[2])) > R + 0.5 * dx]
            if not near or not far:
                fail("no bonds across the vertical axis beside the hole, or none away from it")
            bn, bf = max(near, key=lambda b: b[4]), max(far, key=lambda b: b[4])
            ratio = bf[4] / bn[4]
            print(f"largest stretch across the vertical axis beside the hole {where(bn)}; "
                  f"more than {R + 0.5 * dx:g} from the axis {where(bf)}; ratio {ratio:.3f}")
            if not ratio <= a.stretch_far_ratio:
                fail(f"bonds away from the hole stretch {ratio:.3f} times as far as those beside it "
                     f"(at most {a.stretch_far_ratio}): a spurious mode, not the hole, would start the damage")
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
        W = a.crack_to_edges
        sep, ys, row_of = rows_beside_hole(rows, ux, a.hole_radius, "--crack-to-edges")
        for yr in ys:
            row = row_of(yr)
            best = None
            for (x1, p1, u1), (x2, p2, u2) in zip(row, row[1:]):
                if abs(x1) > W + 1e-9 or abs(x2) > W + 1e-9:
                    continue
                if best is None or u2 - u1 > best[2]:
                    best = (x1, x2, u2 - u1, min(p1, p2))
                if min(p1, p2) >= 0.25 and u2 - u1 >= 0.5 * sep:
                    break
            else:
                what = ("no two neighbouring particles" if best is None else
                        f"largest jump {best[2]:.4g} between x = {best[0]} and {best[1]} (min phi {best[3]:.3g})")
                fail(f"the crack does not cross the row y = {yr} within |x| <= {W}: no neighbours with phi >= 0.25 "
                     f"and a u_x jump >= half the end separation {sep:.4g}; {what}")
        print(f"the crack crosses all {len(ys)} rows between the hole and the free edges within |x| <= {W}, "
              f"opened by at least half the end separation {sep:.4g}")
    if a.crack_band is not None:
        W = a.crack_band
        sep, ys, row_of = rows_beside_hole(rows, ux, a.hole_radius, "--crack-band")
        for yr in ys:
            band = [p for p in row_of(yr) if abs(p[0]) <= W + 1e-9]
            if not band or max(p for _, p, _ in band) < 0.25:
                fail(f"no damaged particle (phi >= 0.25) in the row y = {yr} within |x| <= {W}")
            opening = band[-1][2] - band[0][2]
            if opening < 0.5 * sep:
                fail(f"the crack band does not open the row y = {yr}: u_x rises by {opening:.4g} from x = "
                     f"{band[0][0]} to {band[-1][0]}, less than half the end separation {sep:.4g}")
        print(f"the crack band crosses all {len(ys)} rows between the hole and the free edges within |x| <= {W}, "
              f"opened by at least half the end separation {sep:.4g}")
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
        r2, s2, _ = load(d)
        if s2["broken_bonds_total"] != s["broken_bonds_total"]:
            fail(f"{d}: {s2['broken_bonds_total']} bonds broken, reference {s['broken_bonds_total']}")
        for pid, v in rows.items():
            if abs(r2[pid][2] - v[2]) > 1e-12:
                fail(f"{d}: damage of particle {pid} differs: {r2[pid][2]} vs {v[2]}")
        print(f"{d} ({s2['ranks']} ranks): identical damage field")
    print("PASSED")


if __name__ == "__main__":
    main()
