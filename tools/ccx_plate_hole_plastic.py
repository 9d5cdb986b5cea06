#!/usr/bin/env python3
"""Elastic-plastic finite-element reference for the plate with a hole (xml/plate_hole_plastic.xml),
computed with CalculiX (`ccx`): the force on the ends against their displacement through loading
and unloading, and the plastic zone.

    ccx_plate_hole_plastic.py [--refine R] [--path 1 0] [--increments N] [--out CSV] [--zone CSV] [--keep DIR]

Model: the plate of tools/ccx_plate_hole.py (150 x 50 mm, hole radius 10 mm, quarter meshed with
symmetry, plane strain, thickness 1, u_y = 0 on the ends) with 8-node plane-strain quadrilaterals
of reduced integration (CPE8R: full integration locks under isochoric plastic flow), E = 210 GPa,
nu = 0.33, von Mises plasticity with linear isotropic hardening (sigma_y0 = 250 MPa, H = 2 GPa:
*PLASTIC (250, 0), (2250, 1)), small strain. The ends move u_x = +-0.3 mm times the load factor,
which follows the path's knots (default 0 -> 1 -> 0), results at N equal fractions of each segment
(automatic incrementation, at most one fraction an increment).

Output: per increment the load factor, the end displacement and the reaction on the end
x = 75 over the whole width (N per unit thickness), printed and, with --out, as CSV
(load_factor,u_end,reaction); with --zone, the integration points of the last increment with
their equivalent plastic strain where it is positive (x,y,peeq,area: a quarter of its element's area), over the
quarter x, y >= 0 (the plate's zone is 4 times it).
"""
import argparse
import math
import os
import re
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ccx_plate_hole import quarter_input  # noqa: E402  (the quarter plate's mesh and node sets)
from ccx_seed001 import run_ccx  # noqa: E402

E, NU, SY, H, UEND = 210000.0, 0.33, 250.0, 2000.0, 0.3


def totals(dat_path):
    """[(time, fx)] of the '*NODE PRINT ... TOTALS=ONLY' blocks of the .dat file."""
    out, time = [], None
    with open(dat_path) as f:
        lines = f.readlines()
    for k, line in enumerate(lines):
        m = re.search(r"total force \(fx,fy,fz\) for set NEND and time\s+([0-9.Ee+-]+)", line)
        if m:
            time = float(m.group(1))
            for nxt in lines[k + 1:k + 4]:
                vals = nxt.split()
                if len(vals) >= 2:
                    out.append((time, float(vals[0])))
                    break
    return out


def peeq_points(dat_path):
    """[(element, point, peeq)] of the last '*EL PRINT ... PEEQ' block."""
    blocks, cur = [], None
    with open(dat_path) as f:
        for line in f:
            if "equivalent plastic strain (elem, integ.pnt.,pe)" in line:
                cur = []
                blocks.append(cur)
                continue
            if cur is not None:
                vals = line.split()
                if len(vals) == 3:
                    try:
                        cur.append((int(vals[0]), int(vals[1]), float(vals[2])))
                    except ValueError:
                        cur = None
                elif vals and cur:
                    cur = None
    return blocks[-1] if blocks else []


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--refine", type=int, default=2)
    ap.add_argument("--path", type=float, nargs="+", default=[1.0, 0.0], help="load-factor knots after 0")
    ap.add_argument("--increments", type=int, default=20, help="fixed increments per segment")
    ap.add_argument("--out")
    ap.add_argument("--zone")
    ap.add_argument("--keep")
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args()
    work = a.keep or tempfile.mkdtemp(prefix="plate_hole_plastic_", dir="/tmp")
    os.makedirs(work, exist_ok=True)

    L, nodes, elems, keys, ids = quarter_input(a.refine, "CPE8R", "tools/ccx_plate_hole_plastic.py")
    L += ["*MATERIAL, NAME=MAT", "*ELASTIC", "%g, %g" % (E, NU), "*PLASTIC", "%g, 0.0" % SY, "%g, 1.0" % (SY + H),
          "*SOLID SECTION, ELSET=EALL, MATERIAL=MAT", "1.0",
          "*BOUNDARY", "NX0, 1, 1, 0.0", "NY0, 2, 2, 0.0", "NEND, 2, 2, 0.0"]
    knots = [0.0] + list(a.path)
    # Automatic incrementation (fixed increments diverge at refine 2), at most 1/N of a segment,
    # with the output at the N time points of each segment.
    L += ["*TIME POINTS, NAME=TP, GENERATE", "%.12g, 1.0, %.12g" % (1.0 / a.increments, 1.0 / a.increments)]
    for s in range(1, len(knots)):
        L += ["*STEP, INC=%d" % (100 * a.increments), "*STATIC",
              "%.10g, 1.0, 1e-8, %.10g" % (1.0 / a.increments, 1.0 / a.increments),
              "*BOUNDARY", "NEND, 1, 1, %.12g" % (UEND * knots[s]),
              "*NODE PRINT, NSET=NEND, TOTALS=ONLY, TIME POINTS=TP", "RF",
              "*EL PRINT, ELSET=EALL, TIME POINTS=TP", "PEEQ", "*END STEP"]
    run_ccx(work, "plate", L, a.threads)
    forces = totals(os.path.join(work, "plate.dat"))
    if len(forces) != a.increments * (len(knots) - 1):
        sys.exit("ccx_plate_hole_plastic: expected %d increments, read %d (job in %s)"
                 % (a.increments * (len(knots) - 1), len(forces), work))
    rows = []
    for n, (_, fx) in enumerate(forces):
        seg, inc = divmod(n, a.increments)
        lam = knots[seg] + (knots[seg + 1] - knots[seg]) * (inc + 1) / a.increments
        rows.append((lam, UEND * lam, 2 * fx))  # the quarter's half-width, doubled
    print("FE: %d CPE8R in the quarter, %d nodes (refine %d), %d increments" % (len(elems), len(keys), a.refine, len(rows)))
    for lam, u, rx in rows:
        print("load factor %.4f  u_end %.5f mm  reaction %.2f N" % (lam, u, rx))
    if a.out:
        with open(a.out, "w") as f:
            f.write("# tools/ccx_plate_hole_plastic.py --refine %d --path %s --increments %d\nload_factor,u_end,reaction\n"
                    % (a.refine, " ".join("%g" % k for k in a.path), a.increments))
            for lam, u, rx in rows:
                f.write("%.8g,%.8g,%.8g\n" % (lam, u, rx))
    if a.zone:
        pts = peeq_points(os.path.join(work, "plate.dat"))
        # CPE8R has 2 x 2 integration points (ccx prints them twice); positions from the corner nodes
        g = 1 / math.sqrt(3)
        gauss = [(-g, -g), (g, -g), (-g, g), (g, g)]
        with open(a.zone, "w") as f:
            f.write("# plastic zone at the end of the path (tools/ccx_plate_hole_plastic.py --refine %d): the integration points "
                    "of the quarter x, y >= 0 where peeq > 0; by symmetry the plate's zone is 4 times this\nx,y,peeq,area\n" % a.refine)
            for e, p, pe in pts:
                if p > 4:  # ccx expands a plane element to a brick of two layers: 5-8 repeat 1-4
                    continue
                c = [nodes[k] for k in elems[e - 1]]
                # a quarter of the element's area (straight-sided: the shoelace of its corners)
                area = 0.125 * abs(sum(c[i][0] * c[(i + 1) % 4][1] - c[(i + 1) % 4][0] * c[i][1] for i in range(4)))
                xi, eta = gauss[p - 1]
                N = [(1 - xi) * (1 - eta) / 4, (1 + xi) * (1 - eta) / 4, (1 + xi) * (1 + eta) / 4, (1 - xi) * (1 + eta) / 4]
                x = sum(N[i] * c[i][0] for i in range(4))
                y = sum(N[i] * c[i][1] for i in range(4))
                if pe > 0:
                    f.write("%.6g,%.6g,%.6e,%.6e\n" % (x, y, pe, area))
    if not a.keep:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
