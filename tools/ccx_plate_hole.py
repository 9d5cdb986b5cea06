#!/usr/bin/env python3
"""Linear-elastic finite-element reference for the plate with a hole of seed 000 section 4.5
(xml/plate_hole_damage.xml without damage), computed with CalculiX (`ccx`).

    ccx_plate_hole.py [--refine R] [--particles NX NY] [--out CSV] [--keep DIR]

Model: 150 x 50 mm, hole radius 10 mm at the centre, E = 210 GPa, nu = 0.33, plane strain,
thickness 1; u_x = +-0.1 mm and u_y = 0 on the ends x = +-75 (the scene's fictitious layers move
rigidly, so the continuum boundary is clamped in y too). The quarter x, y >= 0 is meshed (symmetry
u_x = 0 on x = 0, u_y = 0 on y = 0) with 8-node plane-strain quadrilaterals (CPE8, full
integration): two mapped blocks around the hole (split at 45 degrees) and one block from x = 25
to 75; R scales the element counts (R = 1: 16 elements along each eighth of the hole's edge).

Output (printed): the strain at the top of the hole (0, 10), the net-section nominal strain and
the stress concentration; then, on the particle lattice of the scene (NX x NY particles, default
30 x 10, horizon 3.015 dx, fictitious layers at x = +-(75 + dx/2 ...) moving with the ends), the
bond stretch that the FE displacement field gives to every bond of the scene's families: its
maximum and where, the maximum over the bonds crossing the vertical axis beside the hole
(|y_mid| > 10 mm) and over the bonds away from it (|x_mid| > 10 mm + dx/2) and their ratio (the
measure of tests/check_damage.py --stretch-far-ratio), and, with
--out, per real particle the largest stretch of its bonds (id order of the lattice, columns
x, y, max_stretch). This is the continuum's answer to "how far are the bonds stretched" that the
peridynamic run without damage is compared with (docs/validation.md, damage section).
"""
import argparse
import math
import os
import shutil
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ccx_seed001 import read_frd, run_ccx  # noqa: E402  (CalculiX job runner and .frd reader)

E, NU, R_HOLE, HX, HY, UEND = 210000.0, 0.33, 10.0, 75.0, 25.0, 0.1


def mesh(R):
    """Nodes {key: (x, y)} and CPE8 elements (lists of 8 keys) of the quarter plate."""
    nt, nr, nc = 16 * R, 24 * R, 24 * R
    nodes, elems = {}, []

    def key(p):
        return (round(p[0], 7), round(p[1], 7))

    def block(point, ni, nj):
        grid = {}
        for i in range(2 * ni + 1):
            for j in range(2 * nj + 1):
                p = point(i / (2 * ni), j / (2 * nj))
                k = key(p)
                nodes.setdefault(k, p)
                grid[(i, j)] = k
        for i in range(0, 2 * ni, 2):
            for j in range(0, 2 * nj, 2):
                c = [grid[(i, j)], grid[(i + 2, j)], grid[(i + 2, j + 2)], grid[(i, j + 2)],
                     grid[(i + 1, j)], grid[(i + 2, j + 1)], grid[(i + 1, j + 2)], grid[(i, j + 1)]]
                P = [nodes[k] for k in c[:4]]
                area = sum(P[a][0] * P[(a + 1) % 4][1] - P[(a + 1) % 4][0] * P[a][1] for a in range(4))
                if area < 0:
                    c = [c[0], c[3], c[2], c[1], c[7], c[6], c[5], c[4]]
                elems.append(c)

    grade = lambda t: t ** 1.6  # radial grading: small elements at the hole

    def around(th0, th1, outer):
        def point(s, t):
            th = th0 + (th1 - th0) * s
            a = (R_HOLE * math.cos(th), R_HOLE * math.sin(th))
            b = outer(th)
            g = grade(t)
            return ((1 - g) * a[0] + g * b[0], (1 - g) * a[1] + g * b[1])
        return point

    block(around(0.0, math.pi / 4, lambda th: (HY, HY * math.tan(th))), nt, nr)
    block(around(math.pi / 4, math.pi / 2, lambda th: (HY / math.tan(th), HY)), nt, nr)
    # x from 25 to 75, the y values of the first block's outer edge (conforming)
    block(lambda s, t: (HY + (HX - HY) * t, HY * math.tan(math.pi / 4 * s)), nt, nc)
    return nodes, elems


def quarter_input(R, element, title):
    """The quarter plate as CalculiX input lines: its nodes, `element` elements (CPE8, CPE8R) in
    ELSET EALL and the node sets NX0 (x = 0), NY0 (y = 0) and NEND (x = 75); with the mesh's
    nodes, elements, the used node keys in id order and their ids."""
    nodes, elems = mesh(R)
    used = {k for c in elems for k in c}  # the element centres of the grids are not nodes
    keys = sorted(used, key=lambda k: (k[1], k[0]))
    ids = {k: n + 1 for n, k in enumerate(keys)}
    L = ["** %s, quarter plate, %s" % (title, element), "*NODE, NSET=NALL"]
    for k in keys:
        L.append("%d, %.12g, %.12g" % (ids[k], nodes[k][0], nodes[k][1]))
    L.append("*ELEMENT, TYPE=%s, ELSET=EALL" % element)
    for e, c in enumerate(elems, 1):
        L.append("%d, " % e + ", ".join(str(ids[k]) for k in c))

    def nset(name, sel):
        L.append("*NSET, NSET=%s" % name)
        s = sorted(ids[k] for k in keys if sel(nodes[k]))
        L.extend(", ".join(str(v) for v in s[a:a + 12]) for a in range(0, len(s), 12))

    nset("NX0", lambda p: abs(p[0]) < 1e-9)
    nset("NY0", lambda p: abs(p[1]) < 1e-9)
    nset("NEND", lambda p: abs(p[0] - HX) < 1e-9)
    return L, nodes, elems, keys, ids


def fe_solution(R, work, threads):
    L, nodes, elems, keys, ids = quarter_input(R, "CPE8", "tools/ccx_plate_hole.py")
    L += ["*MATERIAL, NAME=MAT", "*ELASTIC", "%g, %g" % (E, NU),
          "*SOLID SECTION, ELSET=EALL, MATERIAL=MAT", "1.0",
          "*STEP", "*STATIC", "*BOUNDARY", "NX0, 1, 1, 0.0", "NY0, 2, 2, 0.0",
          "NEND, 1, 1, %g" % UEND, "NEND, 2, 2, 0.0",
          "*NODE FILE", "U, RF", "*EL FILE", "S, E", "*END STEP"]
    run_ccx(work, "plate", L, threads)
    frd = read_frd(os.path.join(work, "plate.frd"))
    xy = np.array([nodes[k] for k in keys])
    u = np.array([frd["DISP"][ids[k]][:2] for k in keys])
    rx = 2 * sum(frd["FORC"][ids[k]][0] for k in keys if abs(nodes[k][0] - HX) < 1e-9)
    top = ids[min(keys, key=lambda k: math.hypot(nodes[k][0], nodes[k][1] - R_HOLE))]
    return xy, u, frd["TOSTRAIN"][top] if "TOSTRAIN" in frd else None, frd["STRESS"][top], len(elems), rx


def interpolator(xy, u):
    import matplotlib.tri as mtri
    tri = mtri.Triangulation(xy[:, 0], xy[:, 1])
    r = np.hypot(xy[:, 0], xy[:, 1])
    on_arc = r < R_HOLE + 1e-6
    tri.set_mask(on_arc[tri.triangles].all(axis=1))
    fx = mtri.LinearTriInterpolator(tri, u[:, 0])
    fy = mtri.LinearTriInterpolator(tri, u[:, 1])

    def at(x, y):  # the full plate by symmetry: u_x odd in x, u_y odd in y
        ax, ay = abs(x), abs(y)
        vx, vy = float(fx(ax, ay)), float(fy(ax, ay))
        if math.isnan(vx) or math.isnan(vy):
            raise ValueError("point (%g, %g) outside the mesh" % (x, y))
        return math.copysign(1, x) * vx, math.copysign(1, y) * vy
    return at


def lattice(nx, ny, factor=3.015):
    dx = 2 * HX / nx
    nl = int(math.floor(factor + 1e-9))
    pts = []
    for j in range(ny):
        for i in range(-nl, nx + nl):
            x, y = -HX + (i + 0.5) * dx, -HY + (j + 0.5) * dx
            fict = i < 0 or i >= nx
            if not fict and math.hypot(x, y) < R_HOLE:
                continue
            pts.append((x, y, fict))
    return dx, factor * dx, pts


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--refine", type=int, default=2)
    ap.add_argument("--particles", type=int, nargs=2, default=(30, 10))
    ap.add_argument("--out", help="CSV of the largest FE bond stretch per real particle")
    ap.add_argument("--keep")
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args()
    work = a.keep or tempfile.mkdtemp(prefix="plate_hole_", dir="/tmp")
    os.makedirs(work, exist_ok=True)
    xy, u, eps_top, sig_top, ne, rx = fe_solution(a.refine, work, a.threads)
    # nominal: the mean strain 0.2 / 150; net section 30 of 50 mm
    nominal = 2 * UEND / (2 * HX)
    print("FE: %d CPE8 in the quarter, %d nodes (refine %d)" % (ne, len(xy), a.refine))
    if eps_top:
        print("strain at the top of the hole (0, 10): eps_xx = %.5f (nominal 0.2/150 = %.5f, ratio %.2f)"
              % (eps_top[0], nominal, eps_top[0] / nominal))
    print("stress at the top of the hole: sigma_xx = %.1f MPa" % sig_top[0])
    print("reaction on the end x = 75 (whole width, thickness 1): %.1f N (net-section mean stress %.1f MPa,"
          " stress concentration on the net section %.2f)" % (rx, rx / 30.0, sig_top[0] / (rx / 30.0)))
    at = interpolator(xy, u)
    dx, delta, pts = lattice(*a.particles)
    U = []
    for x, y, fict in pts:
        U.append((math.copysign(UEND, x), 0.0) if fict else at(x, y))
    X = np.array([(p[0], p[1]) for p in pts])
    U = np.array(U)
    fict = np.array([p[2] for p in pts])
    n = len(X)
    best = np.full(n, -np.inf)
    top, top_far, top_near = (-1.0, None), (-1.0, None), (-1.0, None)
    for i in range(n):
        d = X - X[i]
        r = np.hypot(d[:, 0], d[:, 1])
        for j in np.nonzero((r <= delta * (1 + 1e-12)) & (np.arange(n) > i))[0]:
            xi = X[j] - X[i]
            s = np.linalg.norm(xi + U[j] - U[i]) / np.linalg.norm(xi) - 1
            best[i] = max(best[i], s)
            best[j] = max(best[j], s)
            mid = 0.5 * (X[i] + X[j])
            if s > top[0]:
                top = (s, (X[i], X[j]))
            if abs(mid[0]) > R_HOLE + 0.5 * dx and s > top_far[0]:
                top_far = (s, (X[i], X[j]))
            if X[i][0] * X[j][0] < 0 and abs(mid[1]) > R_HOLE and s > top_near[0]:
                top_near = (s, (X[i], X[j]))
    fmt = lambda b: "(%g, %g)-(%g, %g)" % (b[0][0], b[0][1], b[1][0], b[1][1])
    print("lattice %d x %d (dx %g, delta %g): largest FE bond stretch %.5f, bond %s"
          % (a.particles[0], a.particles[1], dx, delta, top[0], fmt(top[1])))
    print("largest FE bond stretch across the vertical axis beside the hole (|y_mid| > %g): %.5f, bond %s"
          % (R_HOLE, top_near[0], fmt(top_near[1])))
    print("largest FE bond stretch away from the hole (|x_mid| > %g): %.5f, bond %s; ratio to the one beside "
          "the hole %.3f (check_damage.py --stretch-far-ratio)" % (R_HOLE + 0.5 * dx, top_far[0], fmt(top_far[1]),
                                                                   top_far[0] / top_near[0]))
    if a.out:
        with open(a.out, "w") as f:
            f.write("# ccx_plate_hole.py --refine %d --particles %d %d\nx,y,max_stretch\n"
                    % (a.refine, a.particles[0], a.particles[1]))
            for k in range(n):
                if not fict[k]:
                    f.write("%g,%g,%.7e\n" % (X[k][0], X[k][1], best[k]))
    if not a.keep:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
