#!/usr/bin/env python3
"""Draws the pictures of one perinox run from its output folder.

    python3 drivers/plot_result.py OUTDIR

Writes OUTDIR/deformed.png (real particles on the deformed configuration, coloured by
sigma_xx and by |u|, and by the damage index and the equivalent plastic strain where the run has
them) and OUTDIR/probes.png (probe values against the load factor: displacements on the left
axis, reactions on the right, each labelled with its quantity and the scene's unit of it; where the
scene has an analytic reference, a star marks what it gives each displacement probe at load factor 1).
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_fields(path):
    rows = []
    with open(path) as f:
        for r in csv.DictReader(f):
            rows.append({k: float(v) for k, v in r.items()})
    return rows


def main(out):
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    rows = read_fields(os.path.join(out, "fields.csv"))
    real = [r for r in rows if r["fictitious"] == 0]
    fict = [r for r in rows if r["fictitious"] != 0]
    xs_all = [r["x"] + r["ux"] for r in real]
    ys_all = [r["y"] + r["uy"] for r in real]
    width = (max(xs_all) - min(xs_all)) or 1.0
    height = (max(ys_all) - min(ys_all)) or 1.0
    slender = width / height > 4  # beams: stack the panels (the axes stay equal: no squeezed body)
    panels = [("sxx", "Cauchy stress sigma_xx"), ("umag", "|u|")]
    if any(r.get("damage", 0) > 0 for r in real):
        panels.append(("damage", "damage index phi"))
    if any(r.get("eqps", 0) > 0 for r in real):  # a plastic material that has yielded
        panels.append(("eqps", "equivalent plastic strain"))
    n = len(panels)
    if slender:
        # A panel as tall as the body at 12 inches wide, plus room for the title and colour bar.
        fig, axes = plt.subplots(n, 1, figsize=(12, n * (min(3.3, 10.0 * height / width) + 1.2)), squeeze=False)
        axes = axes[:, 0]
    else:
        fig, axes = plt.subplots(1, n, figsize=(6 * n, 4.5))
    for ax, (key, label) in zip(axes, panels):
        xs = [r["x"] + r["ux"] for r in real]
        ys = [r["y"] + r["uy"] for r in real]
        if key == "umag":
            cs = [(r["ux"] ** 2 + r["uy"] ** 2 + r["uz"] ** 2) ** 0.5 for r in real]
        else:
            cs = [r[key] for r in real]
        kw = {"vmin": 0.0, "vmax": max(cs) or 1.0} if key in ("damage", "eqps") else {}
        sc = ax.scatter(xs, ys, c=cs, s=12, cmap="jet", **kw)
        if fict:
            ax.scatter([r["x"] + r["ux"] for r in fict], [r["y"] + r["uy"] for r in fict], c="0.6", s=8, marker="s")
        ax.set_aspect("equal")
        ax.set_title(label)
        ax.set_xlabel("x + u_x (scene length unit)")
        ax.set_ylabel("y + u_y")
        fig.colorbar(sc, ax=ax, shrink=0.8)
    status = "converged" if summary["converged"] else "NOT converged"
    fig.suptitle(f"{summary.get('title', '')} ({status}, final load factor {summary['steps'][-1]['load_factor']:.3g})")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "deformed.png"), dpi=110)
    plt.close(fig)

    probes = summary.get("probes", {})
    if probes:
        # Displacements (scene length unit) on the left axis, reactions (scene force unit) on a
        # right one, plastic strains (no unit) on the left when there is nothing else: each curve
        # against the axis of its quantity, never a force and a length on one scale.
        units = {"displacement": "displacement (scene length unit)", "reaction": "reaction (scene force unit)",
                 "plastic_strain": "equivalent plastic strain (-)"}
        kinds = []
        for hist in probes.values():
            key = next((k for k in hist[0] if k != "load_factor"), "displacement") if hist else "displacement"
            if key not in kinds:
                kinds.append(key)
        fig, ax = plt.subplots(figsize=(7, 4.5))
        axis_of = {kinds[0]: ax}
        if len(kinds) > 1:
            axis_of[kinds[1]] = ax.twinx()
        for k in kinds[2:]:
            axis_of[k] = ax  # a third kind shares the left axis; its unit is in the legend
        styles = ["-", "--", ":"]
        lines = []
        for name, hist in probes.items():
            key = next((k for k in hist[0] if k != "load_factor"), "displacement") if hist else "displacement"
            lf = [h["load_factor"] for h in hist]
            ncomp = len(hist[0][key]) if hist else 0
            target = axis_of[key]
            for c in range(ncomp):
                comp = ("max", "mean")[c] if key == "plastic_strain" else "xyz"[c]
                lines += target.plot(lf, [h[key][c] for h in hist], marker="o", linestyle=styles[kinds.index(key) % 3],
                                     label=f"{name} {key}[{comp}]")
                ref = summary.get("probe_references", {}).get(name)
                if ref and key == "displacement":
                    lines += target.plot([ref["load_factor"]], [ref["displacement"][c]], marker="*", markersize=13,
                                         linestyle="none", color=lines[-1].get_color(), markeredgecolor="k",
                                         label=f"{name} {key}[{comp}]: {ref['reference']} reference")
        for key, a in axis_of.items():
            if a is not ax or key == kinds[0]:
                a.set_ylabel(units.get(key, key) if a is not ax or len(kinds) < 3 else " / ".join(units.get(k, k) for k in kinds if axis_of[k] is ax))
        ax.set_xlabel("load factor")
        ax.grid(True)
        ax.legend(lines, [l.get_label() for l in lines], fontsize=8)
        ax.set_title(summary.get("title", ""), fontsize=10)
        fig.tight_layout()
        fig.savefig(os.path.join(out, "probes.png"), dpi=110)
        plt.close(fig)


if __name__ == "__main__":
    main(sys.argv[1])
