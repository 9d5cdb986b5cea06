#!/usr/bin/env python3
"""Damage figures of the plate with a hole (seed 000, section 4.5, Figs. 31-34) from perinox runs.

    python3 tools/damage_figures.py --out docs/figures --tag 30x10_G0.01 DAMAGE_RUN [NODAMAGE_RUN ...]

From DAMAGE_RUN (a run of xml/plate_hole_damage.xml): <tag>_damage.png (damage index phi on the
deformed real particles, Figs. 31 / 34), <tag>_ux.png (u_x on the deformed particles, Fig. 33),
<tag>_history.png (broken bonds and reaction against the step / load factor).
With NODAMAGE_RUN folders (the same plate, 'Damage/Enabled=false', e.g. G = 0, 0.001, 0.01): the
u_x profiles along the horizontal and vertical axes (Fig. 32) as <tag>_profiles.csv and .png.
Deformations are magnified by --scale (default 50: the end displacement is 0.1 mm on 150 mm).
With --stretch DIR [DIR ...] (runs without damage, e.g. G = 0.01 and 0.5) and optionally --fe CSV
(tools/ccx_plate_hole.py --out): <tag>_stretch.png, the largest bond stretch of each real particle
(its bonds as perinox builds the families) at the last step, one panel per run and the FEM's on
the same colour scale: where a spurious mode, rather than the hole, stretches the bonds.
"""
import argparse
import csv
import json
import os
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def fields(d):
    with open(os.path.join(d, "fields.csv")) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def summary(d):
    with open(os.path.join(d, "summary.json")) as f:
        return json.load(f)


def fit_squares(fig, panels):
    """Sizes each panel's square markers to 0.9 of its lattice spacing in the drawn axes' scale
    (marker sizes are in points squared), so a fine lattice reads as a field and a coarse one as
    particles. panels: (axes, scatter collection, the particles' reference x)."""
    fig.canvas.draw()
    for ax, sc, x in panels:
        xs = sorted({round(v, 9) for v in x})
        dx = min((b - a for a, b in zip(xs, xs[1:]) if b - a > 1e-9), default=1.0)
        width_pt = ax.get_window_extent().width * 72.0 / fig.dpi
        per_mm = width_pt / (ax.get_xlim()[1] - ax.get_xlim()[0])
        sc.set_sizes([(0.9 * dx * per_mm) ** 2])


def scatter(rows, key, title, path, scale, cmap, vmin=None, vmax=None):
    real = [r for r in rows if r["fictitious"] == 0]
    x = [r["x"] + scale * r["ux"] for r in real]
    y = [r["y"] + scale * r["uy"] for r in real]
    c = [r[key] for r in real]
    fig, ax = plt.subplots(figsize=(9, 3.6))
    sc = ax.scatter(x, y, c=c, s=1.0, cmap=cmap, vmin=vmin, vmax=vmax, marker="s")
    ax.set_aspect("equal")
    ax.set_xlabel("x + %g u_x (mm)" % scale)
    ax.set_ylabel("y + %g u_y (mm)" % scale)
    ax.set_title("\n".join(textwrap.fill(t, 110) for t in title.split("\n")), fontsize=8)
    fig.colorbar(sc, ax=ax, shrink=0.8, label=key)
    fig.tight_layout()
    fit_squares(fig, [(ax, sc, [r["x"] for r in real])])
    fig.savefig(path, dpi=130)
    plt.close(fig)


def profile(d, name):
    p = os.path.join(d, "profile_%s.csv" % name)
    with open(p) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def stretch_figure(runs, fe_csv, path):
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
    from check_damage import bond_stretches  # the checks' own bond set and stretch
    panels = []
    for d in runs:
        _, bonds = bond_stretches(d)
        best = {}
        for xi, yi, xj, yj, st in bonds:
            for k in ((xi, yi), (xj, yj)):
                best[k] = max(best.get(k, -1.0), st)
        real = {(r["x"], r["y"]) for r in fields(d) if r["fictitious"] == 0}
        G = "?"
        with open(os.path.join(d, "scene.resolved.xml")) as f:
            for line in f:
                if 'name="G"' in line:
                    G = "%g" % float(line.split('value="')[1].split('"')[0])
        pts = [(x, y, best[(x, y)]) for (x, y) in real]
        panels.append(("perinox, no damage, G = %s: largest %.4f" % (G, max(p[2] for p in pts)), pts))
    if fe_csv:
        with open(fe_csv) as f:
            pts = [(float(r["x"]), float(r["y"]), float(r["max_stretch"]))
                   for r in csv.DictReader(line for line in f if not line.startswith("#"))]
        panels.append(("linear-elastic FEM (CalculiX) on the same bonds: largest %.4f" % max(p[2] for p in pts), pts))
    vmax = 2.0 * max(p[2] for p in panels[-1][1]) if fe_csv else max(max(p[2] for p in q[1]) for q in panels)
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.6 * len(panels)), squeeze=False)
    drawn = []
    for ax, (title, pts) in zip(axes[:, 0], panels):
        sc = ax.scatter([p[0] for p in pts], [p[1] for p in pts], c=[p[2] for p in pts], s=1.0, marker="s",
                        cmap="viridis", vmin=0.0, vmax=vmax)
        ax.set_aspect("equal")
        ax.set_title(title, fontsize=9)
        fig.colorbar(sc, ax=ax, shrink=0.9, extend="max", label="largest bond stretch")
        drawn.append((ax, sc, [p[0] for p in pts]))
    axes[-1, 0].set_xlabel("x (mm)")
    fig.tight_layout()
    fit_squares(fig, drawn)
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--tag", required=True)
    ap.add_argument("--scale", type=float, default=50.0)
    ap.add_argument("--stretch", nargs="+", default=[], help="runs without damage for <tag>_stretch.png")
    ap.add_argument("--fe", help="FEM largest bond stretch per particle (tools/ccx_plate_hole.py --out)")
    ap.add_argument("damage_run")
    ap.add_argument("nodamage_runs", nargs="*")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    if a.stretch:
        stretch_figure(a.stretch, a.fe, os.path.join(a.out, a.tag + "_stretch.png"))
    s = summary(a.damage_run)
    rows = fields(a.damage_run)
    G = s["scene"].get("G", "?") if isinstance(s.get("scene"), dict) else "?"
    nreal = sum(1 for r in rows if r["fictitious"] == 0)
    why = s.get("failure", "")
    if s["converged"]:
        state = "converged to the end"
    elif why.startswith("reached 'Solver/Max Total Steps'"):  # a snapshot: a run resumed for a step
        state = "stopped at its step limit at load factor %.4g" % s["steps"][-1]["load_factor"]
    else:
        state = "stopped: " + why[:80]
    head = "%d particles, %d bonds broken, %d steps, %s" % (nreal, s.get("broken_bonds_total", 0), len(s["steps"]), state)
    if "broken_bonds_total" in s:  # a run with damage
      scatter(rows, "damage", "damage index phi on the deformed particles (x%g)\n%s" % (a.scale, head),
              os.path.join(a.out, a.tag + "_damage.png"), a.scale, "jet", 0.0, 1.0)
    scatter(rows, "ux", "u_x (mm) on the deformed particles (x%g)\n%s" % (a.scale, head),
            os.path.join(a.out, a.tag + "_ux.png"), a.scale, "jet")
    # History: load factor and cumulative broken bonds per step, reaction against load factor.
    steps = s["steps"]
    lf = [st["load_factor"] for st in steps]
    cum, t = [], 0
    for st in steps:
        t += st.get("broken_bonds", 0)
        cum.append(t)
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.6))
    ax[0].plot(range(1, len(steps) + 1), lf, "b-", lw=1, label="load factor")
    ax[0].set_xlabel("step")
    ax[0].set_ylabel("load factor", color="b")
    ax2 = ax[0].twinx()
    ax2.plot(range(1, len(steps) + 1), cum, "r-", lw=1)
    ax2.set_ylabel("broken bonds (cumulative)", color="r")
    reac = s.get("probes", {}).get("reaction", [])
    if reac:
        ax[1].plot([p["load_factor"] * 0.2 for p in reac], [p["reaction"][0] for p in reac], "k.-", ms=2, lw=0.8)
        ax[1].set_xlabel("end separation 2 u (mm)")
        ax[1].set_ylabel("reaction R_x at the right layer (N)")
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, a.tag + "_history.png"), dpi=130)
    plt.close(fig)
    if a.nodamage_runs:
        out = open(os.path.join(a.out, a.tag + "_profiles.csv"), "w")
        out.write("run,axis,coordinate,ux\n")
        fig, ax = plt.subplots(1, 2, figsize=(10, 3.6))
        for d in a.nodamage_runs:
            sd = summary(d)
            label = os.path.basename(os.path.normpath(d))
            for k, (name, coord) in enumerate((("horizontal_axis", "x"), ("vertical_axis", "y"))):
                pts = profile(d, name)
                # the particles nearest the axis: the row/column with the smallest |y| / |x|
                other = "y" if coord == "x" else "x"
                m = min(abs(p[other]) for p in pts)
                line = sorted((p[coord], p["ux"]) for p in pts if abs(abs(p[other]) - m) < 1e-9 and p[other] > 0)
                for c, u in line:
                    out.write("%s,%s,%.9g,%.9g\n" % (label, name, c, u))
                # break the line across the hole (a gap wider than 1.5 particle spacings)
                xs, us = [], []
                gap = min((b[0] - a_[0] for a_, b in zip(line, line[1:])), default=1.0)
                for q, (c, u) in enumerate(line):
                    if q and c - line[q - 1][0] > 1.5 * gap:
                        xs.append(float("nan"))
                        us.append(float("nan"))
                    xs.append(c)
                    us.append(u)
                ax[k].plot(xs, us, ".-", label=label, lw=1)
                ax[k].set_xlabel("%s (mm), along the %s at %s = %g" % (coord, name.replace("_", " "), other, m))
                ax[k].set_ylabel("u_x (mm)")
        for k in range(2):
            ax[k].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, a.tag + "_profiles.png"), dpi=130)
        plt.close(fig)
        out.close()


if __name__ == "__main__":
    main()
