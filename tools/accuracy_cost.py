#!/usr/bin/env python3
"""What accuracy costs in time: error against wall time across discretisation, horizon,
stabilisation and solver, for a scene with a reference value.

    tools/accuracy_cost.py [--quick] --out out/accuracy_cost

Default study: the clamped beam of seed 000 (4.2) against the converged CalculiX mid-span
deflection (-3.127274 mm, validation/reference/clamped_beam_fem.csv), over particles
3x75 ... 9x225, horizons 1.015 / 2.015 dx, G = 0 / 0.01, and solvers: Newton with the direct
solver, Newton with GMRES + ILU, Newton with GMRES + MueLu, matrix-free Newton-Krylov (analytic
J v with MueLu on the direct-neighbour Jacobian, or with ILU of the assembled one), Jacobian-free
Newton-Krylov, and explicit ADR (small cases only: it needs tens of thousands of iterations).
Peak memory (the driver's resident high-water mark), Newton iterations (every attempt, cut-backs
included; for ADR its iterations), linear solves and Krylov iterations (0 for the direct solver)
are recorded beside the time. Each run is the perinox driver; wall time is
the driver's own (summary.json, set-up included), measured one run at a time.
Writes OUT/accuracy_cost.csv and OUT/accuracy_cost.png (log-log error against time; the
lower-left frontier is what a user chooses from).

--study block: the large-problem frontier instead (issue 19): the stabilised tension block
(xml/tension_block.xml, Silling G = 0.5) at delta = 1.015 and 3.015 dx from 3 200 to 204 800
particles (4e5 unknowns), error e_u of the displacement against the scene's affine reference,
with the presets that finish there: scalable at every size, MUMPS and GMRES + ILU(0) up to 51 200.
"""
import argparse
import csv
import json
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REF = -3.127274


def run(perinox, out, sets, scene="clamped_beam.xml"):
    cmd = [perinox, "run", os.path.join(ROOT, "xml", scene), "--output", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", PERINOX_PLOT_SCRIPT="")
    subprocess.run(cmd, capture_output=True, text=True, env=env)
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="out/accuracy_cost")
    ap.add_argument("--quick", action="store_true", help="fewer cases (for a smoke run)")
    ap.add_argument("--solvers", nargs="+", help="run only these solvers (names as in the table)")
    ap.add_argument("--merge", help="a CSV of an earlier run whose rows for other solvers are kept")
    ap.add_argument("--perinox", default=os.path.join(ROOT, "build", "drivers", "perinox"))
    ap.add_argument("--study", choices=["beam", "block"], default="beam")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    if a.study == "block":
        return block_study(a)
    grids = ["{75,3}", "{125,5}"] if a.quick else ["{75,3}", "{125,5}", "{175,7}", "{225,9}"]
    horizons = ["1.015"] if a.quick else ["1.015", "2.015"]
    solvers = [("Newton/direct", ["Solver/Linear Solver Preset=direct"]),
               ("Newton/GMRES+ILU", ["Solver/Linear Solver Preset=gmres-ilu"]),
               ("Newton/scalable", ["Solver/Linear Solver Preset=scalable"]),
               ("Newton/GMRES+MueLu", ["Solver/Linear Solver Preset=gmres-muelu"]),
               ("matrix-free/MueLu", ["Solver/Linear Solver Preset=mf-muelu"]),
               ("matrix-free/ILU(asm)", ["Solver/Linear Solver Preset=mf-assembled-ilu"]),
               ("Jacobian-free/ILU", ["Solver/Linear Solver Preset=jfnk-ilu"]),
               ("ADR", ["Solver/Method=ADR"])]
    rows = []
    if a.solvers:
        solvers = [sv for sv in solvers if sv[0] in a.solvers]
    for grid in grids:
        for h in horizons:
            for G in ["0", "0.01"]:
                for name, extra in solvers:
                    if name == "ADR" and grid not in ("{75,3}",):
                        continue
                    # MueLu without the rigid-body near-null space is slow on slender beams (over
                    # 7 minutes at 7 x 175): only the two smallest grids.
                    if name == "Newton/GMRES+MueLu" and grid not in ("{75,3}", "{125,5}"):
                        continue
                    # The matrix-free presets on the slender beam: all grids for the analytic
                    # product with ILU of the assembled Jacobian; the Jacobian-free product (more
                    # Krylov iterations) and MueLu on the direct-neighbour matrix on
                    # the smallest only (over 5 minutes at 5 x 125: the slender beam is its worst case).
                    if name == "Jacobian-free/ILU" and grid != "{75,3}":
                        continue
                    if name == "matrix-free/MueLu" and grid != "{75,3}":
                        continue
                    tag = f"{grid}_{h}_{G}_{name}".replace("/", "-").replace("{", "").replace("}", "").replace(",", "x").replace("+", "")
                    s = run(a.perinox, os.path.join(a.out, "runs", tag),
                            [f"Discretization/Particles={grid}", f"Discretization/Horizon Factor={h}", f"Model/G={G}"] + extra)
                    v = s["probes"]["midspan"][-1]["displacement"][1] if s["converged"] else float("nan")
                    err = abs(v / REF - 1)
                    # Newton iterations of every attempt (cut-backs included; ADR: its iterations),
                    # the linear systems solved and the Krylov iterations spent (0: direct solver).
                    iters = s["newton_iterations_total"]
                    krylov = s["krylov_iterations_total"]
                    solves = s["linear_solves_total"]
                    rows.append(dict(particles=grid, horizon=h, G=G, solver=name, converged=s["converged"],
                                     deflection=v, error=err, wall_time_s=s["wall_time_s"], iterations=iters,
                                     linear_solves=solves, krylov_iterations=krylov,
                                     dofs=s["dofs"], peak_rss_mib=s.get("peak_rss_mib_max_rank", float("nan")),
                                     matrix_mib=s.get("matrix_bytes", 0) / 2**20))
                    print(f"{grid:>9} delta {h} G {G:>4} {name:>20}: error {err:.3e}  time {s['wall_time_s']:8.2f} s  "
                          f"iterations {iters}  krylov {krylov}"
                          f"  peak {s.get('peak_rss_mib_max_rank', float('nan')):.0f} MiB", flush=True)
    if a.merge:
        ran = {r["solver"] for r in rows}
        with open(a.merge) as f:
            for r in csv.DictReader(f):
                if r["solver"] in ran:
                    continue
                r["converged"] = r["converged"] == "True"
                for k in ("error", "wall_time_s"):
                    r[k] = float(r[k])
                rows.append({k: r.get(k, "") for k in rows[0].keys()} if rows else r)
    with open(os.path.join(a.out, "accuracy_cost.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is missing from this Python: the CSV is written, the plot is not "
              "(run with /usr/bin/python3, which has python3-matplotlib)")
        return
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(14, 6), gridspec_kw={"width_ratios": [1.6, 1]})
    markers = {"Newton/direct": "o", "Newton/GMRES+ILU": "s", "Newton/scalable": "*", "Newton/GMRES+MueLu": "^", "matrix-free/MueLu": "v",
               "matrix-free/ILU(asm)": "D", "Jacobian-free/ILU": "P", "ADR": "x"}
    colours = {"1.015": "C0", "2.015": "C1"}
    for r in rows:
        if not r["converged"]:
            continue
        fill = "none" if r["G"] != "0" else colours[r["horizon"]]
        ax.scatter(r["wall_time_s"], r["error"], marker=markers[r["solver"]], facecolors=fill,
                   edgecolors=colours[r["horizon"]], s=50)
        ax.annotate(r["particles"].strip("{}").replace(",", "x"), (r["wall_time_s"], r["error"]), fontsize=6,
                    xytext=(3, 3), textcoords="offset points")
        # Right: Krylov iterations per linear solve (the preconditioner's quality) against size.
        k, n = float(r.get("krylov_iterations") or 0), float(r.get("linear_solves") or 0)
        if k > 0 and n > 0:
            ax2.scatter(float(r["dofs"]), k / n, marker=markers[r["solver"]], facecolors=fill,
                        edgecolors=colours[r["horizon"]], s=50)
    for name, m in markers.items():
        ax.scatter([], [], marker=m, color="k", label=name)
    for h, c in colours.items():
        ax.scatter([], [], marker="o", color=c, label=f"delta = {h} dx (filled G = 0, open G = 0.01)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time of the run [s] (2-core machine, one run at a time)")
    ax.set_ylabel("relative error of the mid-span deflection vs FEM")
    ax.set_title("Clamped beam (seed 000, 4.2): accuracy against cost")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    ax2.set_xscale("log")
    ax2.set_yscale("log")
    ax2.set_xlabel("unknowns")
    ax2.set_ylabel("Krylov iterations per linear solve")
    ax2.set_title("Iterative solvers: preconditioner quality")
    ax2.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "accuracy_cost.png"), dpi=110)
    print("wrote", os.path.join(a.out, "accuracy_cost.csv"), "and accuracy_cost.png")


def block_study(a):
    """Error e_u against wall time on the stabilised tension block, to 4e5 unknowns."""
    grids = ["80x40", "160x80", "320x160"] if a.quick else ["80x40", "160x80", "320x160", "640x320"]
    solvers = [("Newton/scalable", "scalable", None), ("Newton/MUMPS", "mumps", 51200),
               ("Newton/GMRES+ILU(0)", "gmres-ilu0", 51200)]
    if a.solvers:
        solvers = [sv for sv in solvers if sv[0] in a.solvers]
    rows = []
    for grid in grids:
        nx, ny = (int(v) for v in grid.split("x"))
        for h in ["1.015", "3.015"]:
            for name, preset, largest in solvers:
                if largest is not None and nx * ny > largest:
                    continue
                tag = f"block_{grid}_{h}_{preset}"
                s = run(a.perinox, os.path.join(a.out, "runs", tag),
                        [f"Discretization/Particles={{{nx},{ny}}}", f"Discretization/Horizon Factor={h}",
                         "Model/Stabilization=Silling", "Model/G=0.5", "Solver/Load Steps=1",
                         f"Solver/Linear Solver Preset={preset}", "Output/VTK=false", "Output/Plots=false"],
                        scene="tension_block.xml")
                err = s["errors"]["e_u"] if s["converged"] else float("nan")
                rows.append(dict(particles=nx * ny, horizon=h, solver=name, converged=s["converged"], error=err,
                                 wall_time_s=s["wall_time_s"], dofs=s["dofs"], newton=s["newton_iterations_total"],
                                 krylov=s["krylov_iterations_total"], linear_solves=s["linear_solves_total"],
                                 peak_rss_mib=s.get("peak_rss_mib_max_rank", float("nan"))))
                print(f"{nx * ny:>7} delta {h} {name:>20}: e_u {err:.3e}  time {s['wall_time_s']:8.2f} s  "
                      f"unknowns {s['dofs']}  krylov/solve {s['krylov_iterations_total'] / max(1, s['linear_solves_total']):.1f}"
                      f"  peak {s.get('peak_rss_mib_max_rank', float('nan')):.0f} MiB", flush=True)
    with open(os.path.join(a.out, "accuracy_cost_block.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is missing from this Python: the CSV is written, the plot is not")
        return
    fig, ax = plt.subplots(figsize=(8, 6))
    markers = {"Newton/scalable": "*", "Newton/MUMPS": "o", "Newton/GMRES+ILU(0)": "s"}
    colours = {"1.015": "C0", "3.015": "C1"}
    for r in rows:
        if r["converged"]:
            ax.scatter(r["wall_time_s"], r["error"], marker=markers[r["solver"]], color=colours[r["horizon"]], s=60)
            ax.annotate(str(r["dofs"]), (r["wall_time_s"], r["error"]), fontsize=6, xytext=(3, 3), textcoords="offset points")
    for name, m in markers.items():
        ax.scatter([], [], marker=m, color="k", label=name)
    for h, c in colours.items():
        ax.scatter([], [], marker="o", color=c, label=f"delta = {h} dx")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time of the run [s] (labels: unknowns)")
    ax.set_ylabel("displacement error e_u against the affine solution")
    ax.set_title("Stabilised tension block (G = 0.5): accuracy against cost")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "accuracy_cost_block.png"), dpi=110)
    print("wrote", os.path.join(a.out, "accuracy_cost_block.csv"), "and accuracy_cost_block.png")


if __name__ == "__main__":
    main()
