#!/usr/bin/env python3
"""The seed-001 comparison figures (Luo and Sundararaghavan, Figs. 7, 9, 10, 12, 13) in one
command, run from the repository root:

    /usr/bin/python3 tools/seed001_figures.py [--build build] [--out docs/figures] [--adr]

Runs the driver on
  xml/bar1d_variable_modulus.xml  with None, Springs, Average Displacement, Stress Points
                                  (C1, C2 from seed Table 1 for n = 500);
  xml/plate_square_opening.xml    with None and Stress Points (the seed compares only these two
                                  in 2D and 3D), and Springs (C1 = 3) and ADS (C2 = 1);
  xml/plate_square_opening_half.xml  the same plate modelled across y = 0 (axis 1 an interior
                                  row), None and Stress Points;
  xml/brick3d.xml                 with None and Stress Points;
and with --adr also the bar and the plate with stress points under the explicit ADR solver.
Writes into --out:
  seed001_fig7_bar.png       u and strain along the bar, local amplitudes a_u, a_e (eq. 21)
  seed001_fig9_plate.png     u_x over the plate, no control against stress points
  seed001_fig10_plate.png    u_x and sigma_xx along axis 1 (y = 0) against the FEM reference
                             (validation/reference/plate_square_opening_fem.csv), a_u, a_sigma
  seed001_fig9_plate_half.png, seed001_fig10_plate_half.png   the same for the half plate
  seed001_fig12_brick.png    u_z on the bottom face, no control against stress points
  seed001_fig13_brick.png    u_z along x = 40, z = 0 against FEM (brick3d_fem.csv), a_w
  seed001_bar.csv, seed001_plate_axis1.csv, seed001_plate_half_axis1.csv,
  seed001_brick_line.csv     the plotted data
  seed001_measures.csv       per scene and control: the error against the reference and the
                             oscillation measure (tools/seed001_measures.py) on the windows
                             used by the tests
The strain of the bar is taken between neighbouring particles, (u_{i+1} - u_i) / dx at the
midpoints, the measure that shows the zero-energy zigzag (a particle's own F is the central
difference, blind to it).
"""
import argparse
import math
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import seed001_measures as _M  # noqa: E402

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

class M:
    """seed001_measures with numpy arrays in and out."""
    read_csv = staticmethod(lambda path: {k: np.array(v) for k, v in _M.read_csv(path).items()})
    profile = staticmethod(lambda *a: {k: np.array(v) for k, v in _M.profile(*a).items()})
    at = staticmethod(lambda rs, rv, s: np.array(_M.at(list(rs), list(rv), list(s))))
    amplitude = staticmethod(lambda n, r: np.array(_M.amplitude(list(n), list(r))))
    zigzag = staticmethod(lambda s, n, r, lo, hi: _M.zigzag(list(s), list(n), list(r), lo, hi))
    max_rel = staticmethod(lambda s, n, r, lo, hi: _M.max_rel(list(s), list(n), list(r), lo, hi))


ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STYLE = {"None": ("tab:red", "s", "No control"), "Springs": ("tab:orange", "^", "Springs"),
         "Average Displacement": ("tab:green", "v", "ADS"),
         "Stress Points": ("tab:blue", "o", "Stress-point"),
         "Stress Points ADR": ("tab:cyan", "x", "Stress-point, ADR")}

# windows of the measures (the tests use the same ones): away from the opening's corner
# (seed: x > 20 mm) and from the pulled edge; on the brick's line away from the held faces
PLATE_WIN = (20.0, 44.0)
BRICK_WIN = (10.0, 70.0)
# Springs and ADS constants for the plate (seed Table 1 is for the 1D bar only). A scan at
# h = 2 mm (C1 = 0.3, 3, 30; C2 = 0.01, 0.1, 1; docs/validation.md) showed the trade-off: the
# zigzag falls only as the constant stiffens the plate. These are the smallest constants of the
# scan that bring the displacement zigzag to the stress points' level (within a factor 2).
PLATE_C = {"Springs": 3.0, "Average Displacement": 1.0}


def run(build, scene, out, sets, quiet=True):
    cmd = [os.path.join(build, "drivers", "perinox"), "run", os.path.join(ROOT, "xml", scene),
           "--output", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    env = dict(os.environ, PERINOX_PLOT_SCRIPT="")
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, env=env)
    if r.returncode != 0:
        sys.exit("perinox failed (%s): %s\n%s" % (" ".join(cmd), r.returncode, r.stdout[-2000:]))
    print("  ran %s %s" % (scene, " ".join(sets)))
    return out


def tag(c):
    return c.replace(" ", "_")


def bar(a, work, out, meas):
    a_, b_ = 0.001, 0.004 * math.sqrt(2)
    u_ex = lambda x: a_ * x + np.where(x > 0.5, b_ * np.sqrt(np.maximum(x - 0.5, 0)), 0.0)
    e_ex = lambda x: a_ + np.where(x > 0.5, b_ / (2 * np.sqrt(np.maximum(x - 0.5, 1e-300))), 0.0)
    controls = ["None", "Springs", "Average Displacement", "Stress Points"] + (["Stress Points ADR"] if a.adr else [])
    fig, ax = plt.subplots(2, 2, figsize=(11, 7.5))
    cols = {}
    for c in controls:
        sets = ["Model/Zero-Energy Control=%s" % c.replace(" ADR", "")] + (["Solver/Method=ADR"] if "ADR" in c else [])
        d = run(a.build, "bar1d_variable_modulus.xml", os.path.join(work, "bar_" + tag(c)), sets)
        f = M.read_csv(os.path.join(d, "fields.csv"))
        o = np.argsort(f["x"])
        x, u = f["x"][o], f["ux"][o]
        xm, e = 0.5 * (x[1:] + x[:-1]), np.diff(u) / np.diff(x)
        au, ae = M.amplitude(u, u_ex(x)), M.amplitude(e, e_ex(xm))
        col, mk, lab = STYLE[c]
        ax[0, 0].plot(x, u, mk, ms=2.5, color=col, label=lab)
        ax[0, 1].semilogy(x, np.maximum(au, 1e-12), mk, ms=2.5, color=col, label=lab)
        ax[1, 0].plot(xm, e, mk, ms=2.5, color=col, label=lab)
        ax[1, 1].semilogy(xm, np.maximum(ae, 1e-12), mk, ms=2.5, color=col, label=lab)
        cols["x"], cols["u_exact"] = x, u_ex(x)
        cols["u " + lab] = u
        cols["eps(mid) " + lab] = np.append(e, np.nan)
        left = xm < 0.45
        z = np.max(np.abs(e[2:] - 2 * e[1:-1] + e[:-2])[left[1:-1]]) / a_
        meas.append(("bar", c, "max a_e on x<0.45", np.max(ae[left]), "strain zigzag/alpha on x<0.45", z))
    ax[0, 0].plot(x, u_ex(x), "k-", lw=1, label="analytic")
    xs = np.linspace(0, 1, 2001)
    ax[1, 0].plot(xs, e_ex(xs), "k-", lw=1, label="analytic")
    ax[1, 0].set_ylim(-0.02, 0.03)
    for k, (t, yl) in enumerate([("(a) displacement", "u"), ("(b) a_u", "a_u"), ("(c) strain", "strain"), ("(d) a_e", "a_e")]):
        A = ax[k // 2, k % 2]
        A.set_title(t)
        A.set_xlabel("x")
        A.set_ylabel(yl)
        A.legend(fontsize=7)
    fig.suptitle("Seed 001 Fig. 7: 1D bar with variable modulus, 500 particles")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "seed001_fig7_bar.png"), dpi=120)
    plt.close(fig)
    write_cols(os.path.join(out, "seed001_bar.csv"), cols)


def write_cols(path, cols):
    keys = list(cols)
    n = len(cols[keys[0]])
    with open(path, "w") as f:
        f.write(",".join(keys) + "\n")
        for i in range(n):
            f.write(",".join("%.9g" % cols[k][i] for k in keys) + "\n")


def plate(a, work, out, meas, half=False):
    ref = M.read_csv(os.path.join(ROOT, "validation", "reference", "plate_square_opening_fem.csv"))
    controls = ["None", "Stress Points"] + ([] if half else ["Springs", "Average Displacement"]) + \
        (["Stress Points ADR"] if a.adr and not half else [])
    scene = "plate_square_opening_half.xml" if half else "plate_square_opening.xml"
    sfx = "_half" if half else ""
    fig, ax = plt.subplots(2, 2, figsize=(11, 7.5))
    fig9, ax9 = plt.subplots(1, 2, figsize=(11, 5))
    cols = {}
    for c in controls:
        sets = ["Model/Zero-Energy Control=%s" % c.replace(" ADR", "")] + (["Solver/Method=ADR"] if "ADR" in c else [])
        if c in PLATE_C:
            sets.append("Model/Control Constant=%g" % PLATE_C[c])
        d = run(a.build, scene, os.path.join(work, "plate" + sfx + "_" + tag(c)), sets)
        p = M.profile(d, "axis_1", "x")
        x = p["x"]
        uf, sf = M.at(ref["x"], ref["ux"], x), M.at(ref["x"], ref["sxx"], x)
        col, mk, lab = STYLE[c]
        ax[0, 0].plot(x, p["ux"], mk + "-", ms=4, lw=0.8, color=col, label=lab)
        ax[0, 1].semilogy(x, np.maximum(M.amplitude(p["ux"], uf), 1e-8), mk + "-", ms=4, lw=0.8, color=col, label=lab)
        ax[1, 0].plot(x, p["sxx"], mk + "-", ms=4, lw=0.8, color=col, label=lab)
        ax[1, 1].semilogy(x, np.maximum(M.amplitude(p["sxx"], sf), 1e-8), mk + "-", ms=4, lw=0.8, color=col, label=lab)
        cols["x"], cols["ux FEM"], cols["sxx FEM"] = x, uf, sf
        cols["ux " + lab], cols["sxx " + lab] = p["ux"], p["sxx"]
        meas.append(("plate%s axis 1 x %g..%g" % ((sfx,) + PLATE_WIN), c,
                     "max |ux-FEM|/max|ux FEM|", M.max_rel(x, p["ux"], uf, *PLATE_WIN),
                     "ux zigzag", M.zigzag(x, p["ux"], uf, *PLATE_WIN)))
        meas.append(("plate%s axis 1 x %g..%g" % ((sfx,) + PLATE_WIN), c,
                     "max |sxx-FEM|/max|sxx FEM|", M.max_rel(x, p["sxx"], sf, *PLATE_WIN),
                     "sxx zigzag", M.zigzag(x, p["sxx"], sf, *PLATE_WIN)))
        if c in ("None", "Stress Points"):
            f = M.read_csv(os.path.join(d, "fields.csv"))
            A = ax9[0 if c == "None" else 1]
            sc = A.scatter(f["x"], f["y"], c=f["ux"], s=28, marker="s", cmap="jet", vmin=0, vmax=0.5)
            A.set_aspect("equal")
            A.set_title("u_x [mm], " + lab)
            fig9.colorbar(sc, ax=A)
    ax[0, 0].plot(ref["x"], ref["ux"], "k-", lw=1, label="FEM")
    ax[1, 0].plot(ref["x"], ref["sxx"], "k-", lw=1, label="FEM")
    for k, (t, yl) in enumerate([("(a) u_x along axis 1", "u_x [mm]"), ("(b) a_u", "a_u"),
                                 ("(c) sigma_xx along axis 1", "sigma_xx [MPa]"), ("(d) a_sigma", "a_sigma")]):
        A = ax[k // 2, k % 2]
        A.set_title(t)
        A.set_xlabel("x [mm] (y = 0)")
        A.set_ylabel(yl)
        A.legend(fontsize=7)
    what = "half plate (axis 1 an interior row)" if half else "quarter plate"
    fig.suptitle("Seed 001 Fig. 10: %s with a square opening, h = 2 mm" % what)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "seed001_fig10_plate%s.png" % sfx), dpi=120)
    fig9.suptitle("Seed 001 Fig. 9: u_x of the %s" % what)
    fig9.tight_layout()
    fig9.savefig(os.path.join(out, "seed001_fig9_plate%s.png" % sfx), dpi=120)
    plt.close(fig)
    plt.close(fig9)
    write_cols(os.path.join(out, "seed001_plate%s_axis1.csv" % sfx), cols)


def brick(a, work, out, meas):
    ref = M.read_csv(os.path.join(ROOT, "validation", "reference", "brick3d_fem.csv"))
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    fig12, ax12 = plt.subplots(1, 2, figsize=(11, 5))
    cols = {}
    for c in ["None", "Stress Points"]:
        d = run(a.build, "brick3d.xml", os.path.join(work, "brick_" + tag(c)), ["Model/Zero-Energy Control=%s" % c])
        p = M.profile(d, "line", "y")
        y = p["y"]
        wf = M.at(ref["y"], ref["uz"], y)
        col, mk, lab = STYLE[c]
        ax[0].plot(y, p["uz"], mk + "-", ms=4, lw=0.8, color=col, label=lab)
        ax[1].semilogy(y, np.maximum(M.amplitude(p["uz"], wf), 1e-8), mk + "-", ms=4, lw=0.8, color=col, label=lab)
        cols["y"], cols["uz FEM"], cols["uz " + lab] = y, wf, p["uz"]
        meas.append(("brick line x=40 z=0 y %g..%g" % BRICK_WIN, c,
                     "max |uz-FEM|/max|uz FEM|", M.max_rel(y, p["uz"], wf, *BRICK_WIN),
                     "uz zigzag", M.zigzag(y, p["uz"], wf, *BRICK_WIN)))
        f = M.read_csv(os.path.join(d, "fields.csv"))
        m = np.abs(f["z"]) < 1e-9
        A = ax12[0 if c == "None" else 1]
        sc = A.scatter(f["x"][m], f["y"][m], c=f["uz"][m], s=14, marker="s", cmap="jet")
        A.set_aspect("equal")
        A.set_title("u_z [mm] on the bottom face z = 0, " + lab)
        fig12.colorbar(sc, ax=A)
    ax[0].plot(ref["y"], ref["uz"], "k-", lw=1, label="FEM")
    for A, t, yl in ((ax[0], "u_z along x = 40, z = 0", "u_z [mm]"), (ax[1], "a_w", "a_w")):
        A.set_title(t)
        A.set_xlabel("y [mm]")
        A.set_ylabel(yl)
        A.legend(fontsize=7)
    fig.suptitle("Seed 001 Fig. 13: brick 80 x 80 x 40 mm, h = 2.5 mm")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "seed001_fig13_brick.png"), dpi=120)
    fig12.suptitle("Seed 001 Fig. 12 (c, d): u_z on the bottom face")
    fig12.tight_layout()
    fig12.savefig(os.path.join(out, "seed001_fig12_brick.png"), dpi=120)
    plt.close(fig)
    plt.close(fig12)
    write_cols(os.path.join(out, "seed001_brick_line.csv"), cols)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "figures"))
    ap.add_argument("--work", default="/tmp/seed001_runs", help="folder for the driver's output folders")
    ap.add_argument("--adr", action="store_true", help="also the bar and the plate with stress points under ADR")
    ap.add_argument("--only", choices=("bar", "plate", "plate_half", "brick"), action="append")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    os.makedirs(a.work, exist_ok=True)
    meas = []
    plate_half = lambda a_, w_, o_, m_: plate(a_, w_, o_, m_, half=True)
    for name, fn in (("bar", bar), ("plate", plate), ("plate_half", plate_half), ("brick", brick)):
        if not a.only or name in a.only:
            print(name)
            fn(a, a.work, a.out, meas)
    path = os.path.join(a.out, "seed001_measures.csv")
    with open(path, "w") as f:
        f.write("scene,control,measure 1,value 1,measure 2,value 2\n")
        for r in meas:
            f.write("%s,%s,%s,%.4g,%s,%.4g\n" % r)
    print(open(path).read())


if __name__ == "__main__":
    main()
