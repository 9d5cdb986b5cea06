#!/usr/bin/env python3
"""Finite-element references for the 2D and 3D examples of seed 001 (sections 5.2 and 5.3),
computed with CalculiX (`ccx`, Debian package calculix-ccx), linear elasticity (the seed's
examples are small-strain).

    ccx_seed001.py plate [--refine R] [--out CSV] [--keep DIR]
    ccx_seed001.py brick [--refine R] [--out CSV] [--keep DIR]

plate  The quarter plate of xml/plate_square_opening.xml: 0 <= x, y <= 50 mm minus the opening
       0 <= x, y < 10 mm, E = 1000 MPa, nu = 0.3, plane stress, thickness 1. u_x = 0 on x = 0,
       u_y = 0 on y = 0, u_x = 0.5 mm on x = 50; the rest traction free. Mesh: 8-node quads
       (CPS8, full integration) of size 2 mm / R, so every particle of the scene (2 mm grid) is
       a corner node. Output: u_x and sigma_xx (nodal, extrapolated from the integration points
       and averaged by ccx) at the nodes y = 0, x = 10, 12, ..., 50 (axis 1 of seed Fig. 10), every
       corner node of that line (step 2 mm / R).
brick  The brick of xml/brick3d.xml: 0 <= x, y <= 80, 0 <= z <= 40 mm, E = 1000 MPa,
       nu = 0.3; side faces x = 0, 80 and y = 0, 80 carry u = (0.01 (x - 40), 0.01 (y - 40), 0);
       top and bottom free. The problem is symmetric about x = 40, y = 40 and z = 20, so the
       model is the eighth 40 <= x, y <= 80, 0 <= z <= 20 with u_x = 0 on x = 40, u_y = 0 on
       y = 40 and u_z = 0 on z = 20. Mesh: 20-node bricks (C3D20, full integration) of size
       2.5 mm / R. Output: u_z at every corner node of the line x = 40, z = 0, 0 <= y <= 80 (seed
       Fig. 13; step 2.5 mm / R), the half y < 40 mirrored from y > 40.

The CSV has one '#' header line naming the model and mesh, then the column names.
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile

E, NU = 1000.0, 0.3


def run_ccx(work, job, inp_lines, threads):
    with open(os.path.join(work, job + ".inp"), "w") as f:
        f.write("\n".join(inp_lines) + "\n")
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), CCX_NPROC_STIFFNESS=str(threads),
               CCX_NPROC_EQUATION_SOLVER=str(threads))
    r = subprocess.run(["ccx", "-i", job], cwd=work, env=env, stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, universal_newlines=True)
    with open(os.path.join(work, "ccx.log"), "w") as f:
        f.write(r.stdout)
    if r.returncode != 0 or "*ERROR" in r.stdout:
        sys.stderr.write(r.stdout[-3000:])
        sys.exit("ccx failed (job files in %s)" % work)


def read_frd(path):
    """Returns {block name: {node: [values]}} for the nodal result blocks of a .frd file
    (DISP, STRESS). Fixed-width records: ' -1', node id in 10 columns, values in 12."""
    out, name = {}, None
    with open(path) as f:
        for line in f:
            if line.startswith(" -4"):
                name = line.split()[1]
                out[name] = {}
            elif line.startswith(" -3"):
                name = None
            elif name and line.startswith(" -1"):
                node = int(line[3:13])
                vals = [float(line[13 + 12 * k:25 + 12 * k]) for k in range((len(line.rstrip("\n")) - 13) // 12)]
                out[name][node] = vals
    return out


def nsets(L, name, ids):
    L.append("*NSET, NSET=%s" % name)
    ids = sorted(ids)
    L += [", ".join(str(v) for v in ids[k:k + 12]) for k in range(0, len(ids), 12)]


def plate(R, work, threads):
    h = 2.0 / R
    n = 25 * R  # elements per side (50 mm)
    a = 5 * R   # opening (10 mm) in elements
    # nodes of the quadratic lattice (2n+1)^2, skipping element centres and the opening
    def inside_opening(i, j):  # lattice point strictly inside the opening
        return i < 2 * a and j < 2 * a
    elems, used = [], set()
    for ey in range(n):
        for ex in range(n):
            if ex < a and ey < a:
                continue
            i, j = 2 * ex, 2 * ey
            c = [(i, j), (i + 2, j), (i + 2, j + 2), (i, j + 2), (i + 1, j), (i + 2, j + 1), (i + 1, j + 2), (i, j + 1)]
            elems.append(c)
            used.update(c)
    ids = {p: k + 1 for k, p in enumerate(sorted(used, key=lambda p: (p[1], p[0])))}
    X = lambda p: (p[0] * h / 2, p[1] * h / 2)
    L = ["** tools/ccx_seed001.py plate, CPS8, element size %g mm" % h, "*NODE, NSET=NALL"]
    for p, k in sorted(ids.items(), key=lambda t: t[1]):
        L.append("%d, %.12g, %.12g" % ((k,) + X(p)))
    L.append("*ELEMENT, TYPE=CPS8, ELSET=EALL")
    for e, c in enumerate(elems, 1):
        L.append("%d, " % e + ", ".join(str(ids[p]) for p in c))
    nsets(L, "NX0", [k for p, k in ids.items() if p[0] == 0])
    nsets(L, "NY0", [k for p, k in ids.items() if p[1] == 0])
    nsets(L, "NX1", [k for p, k in ids.items() if p[0] == 2 * n])
    L += ["*MATERIAL, NAME=MAT", "*ELASTIC", "%g, %g" % (E, NU),
          "*SOLID SECTION, ELSET=EALL, MATERIAL=MAT", "1.0",
          "*STEP", "*STATIC", "*BOUNDARY", "NX0, 1, 1, 0.0", "NY0, 2, 2, 0.0", "NX1, 1, 1, 0.5",
          "*NODE FILE", "U", "*EL FILE", "S", "*END STEP"]
    run_ccx(work, "plate", L, threads)
    frd = read_frd(os.path.join(work, "plate.frd"))
    rows = []
    for i in range(2 * a, 2 * n + 1, 2):  # every corner node on y = 0, x = 10 ... 50
        k = ids[(i, 0)]
        rows.append((X((i, 0))[0], frd["DISP"][k][0], frd["DISP"][k][1], frd["STRESS"][k][0]))
    head = ("# ccx_seed001.py plate --refine %d: CalculiX linear static, %d CPS8 (plane stress, full "
            "integration, thickness 1), element size %g mm, %d nodes; E=%g nu=%g; units mm, N, MPa; "
            "u_x=0.5 on x=50, symmetry on x=0 and y=0; nodes y=0 (axis 1); sxx nodal (extrapolated, averaged)"
            % (R, len(elems), h, len(ids), E, NU))
    return head + "\nx,ux,uy,sxx\n" + "".join("%g,%.7e,%.7e,%.7e\n" % r for r in rows)


def brick(R, work, threads):
    h = 2.5 / R
    nx, nz = 16 * R, 8 * R  # eighth: 40 x 40 x 20 mm
    used, elems = set(), []
    for ez in range(nz):
        for ey in range(nx):
            for ex in range(nx):
                i, j, k = 2 * ex, 2 * ey, 2 * ez
                c = [(i, j, k), (i + 2, j, k), (i + 2, j + 2, k), (i, j + 2, k),
                     (i, j, k + 2), (i + 2, j, k + 2), (i + 2, j + 2, k + 2), (i, j + 2, k + 2),
                     (i + 1, j, k), (i + 2, j + 1, k), (i + 1, j + 2, k), (i, j + 1, k),
                     (i + 1, j, k + 2), (i + 2, j + 1, k + 2), (i + 1, j + 2, k + 2), (i, j + 1, k + 2),
                     (i, j, k + 1), (i + 2, j, k + 1), (i + 2, j + 2, k + 1), (i, j + 2, k + 1)]
                elems.append(c)
                used.update(c)
    ids = {p: q + 1 for q, p in enumerate(sorted(used, key=lambda p: (p[2], p[1], p[0])))}
    X = lambda p: (40.0 + p[0] * h / 2, 40.0 + p[1] * h / 2, p[2] * h / 2)
    L = ["** tools/ccx_seed001.py brick (eighth model), C3D20, element size %g mm" % h, "*NODE, NSET=NALL"]
    for p, q in sorted(ids.items(), key=lambda t: t[1]):
        L.append("%d, %.12g, %.12g, %.12g" % ((q,) + X(p)))
    L.append("*ELEMENT, TYPE=C3D20, ELSET=EALL")
    for e, c in enumerate(elems, 1):
        ln = [str(ids[p]) for p in c]
        L.append("%d, " % e + ", ".join(ln[:15]) + ",")
        L.append(", ".join(ln[15:]))
    top = 2 * nx
    nsets(L, "NSX", [q for p, q in ids.items() if p[0] == 0])
    nsets(L, "NSY", [q for p, q in ids.items() if p[1] == 0])
    nsets(L, "NSZ", [q for p, q in ids.items() if p[2] == 2 * nz])
    # side faces: u = (0.01 (x - 40), 0.01 (y - 40), 0) node by node
    bnd = []
    for p, q in ids.items():
        if p[0] == top or p[1] == top:
            x, y, _ = X(p)
            bnd.append("%d, 1, 1, %.12g" % (q, 0.01 * (x - 40.0)))
            bnd.append("%d, 2, 2, %.12g" % (q, 0.01 * (y - 40.0)))
            bnd.append("%d, 3, 3, 0.0" % q)
    L += ["*MATERIAL, NAME=MAT", "*ELASTIC", "%g, %g" % (E, NU),
          "*SOLID SECTION, ELSET=EALL, MATERIAL=MAT",
          "*STEP", "*STATIC", "*BOUNDARY", "NSX, 1, 1, 0.0", "NSY, 2, 2, 0.0", "NSZ, 3, 3, 0.0"] + bnd + [
          "*NODE FILE", "U", "*END STEP"]
    run_ccx(work, "brick", L, threads)
    frd = read_frd(os.path.join(work, "brick.frd"))
    # lattice index of y = 40 + 2.5 s is 2 R s (quadratic lattice: step h/2 = 1.25 / R)
    # every corner node of the line (step h), the half y < 40 mirrored
    half = {s: frd["DISP"][ids[(0, 2 * s, 0)]][2] for s in range(nx + 1)}
    rows = [(40.0 + h * s, half[abs(s)]) for s in range(-nx, nx + 1)]
    head = ("# ccx_seed001.py brick --refine %d: CalculiX linear static, eighth model (symmetry x=40, y=40, z=20), "
            "%d C3D20 (full integration), element size %g mm, %d nodes; E=%g nu=%g; units mm, N, MPa; "
            "sides u=(0.01(x-40), 0.01(y-40), 0); line x=40, z=0 (y<40 mirrored)"
            % (R, len(elems), h, len(ids), E, NU))
    return head + "\ny,uz\n" + "".join("%g,%.7e\n" % r for r in rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", choices=("plate", "brick"))
    ap.add_argument("--refine", type=int, default=0, help="elements per particle spacing (default: plate 8, brick 2)")
    ap.add_argument("--out", help="CSV output path (default: stdout)")
    ap.add_argument("--keep", help="directory to keep the ccx job files in")
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    R = a.refine or (8 if a.case == "plate" else 2)
    if a.keep:
        os.makedirs(a.keep, exist_ok=True)
        work = a.keep
    else:
        os.makedirs("/tmp/ccx", exist_ok=True)
        work = tempfile.mkdtemp(prefix="seed001_%s_" % a.case, dir="/tmp/ccx")
    text = (plate if a.case == "plate" else brick)(R, work, a.threads)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)
    if not a.keep:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
