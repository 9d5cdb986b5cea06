#!/usr/bin/env python3
"""Weak scaling of the linear-solver presets, end to end through the perinox driver (issue 19).

The stabilised tension block (xml/tension_block.xml, Silling G, delta = 3.015 dx, one load step to
the scene's tolerance) from 3 200 particles, x4 a row, in 2D, and from 8 000 in 3D. Per row and
preset: Newton iterations, Krylov iterations per linear solve, set-up and solve wall time, solve
time per particle, peak memory, matrix bytes, and the cost of a Newton iteration in units of one
residual evaluation measured in the same run (summary.json "timing": Newton's own time, its
Jacobians, linear solves and residuals, per iteration; and the whole solve's time per iteration,
which also carries the tangent predictor's solve and the first assembly, which builds the graph).
Prints a table and writes CSV; asserts nothing.

A preset is not run at a size when it cannot finish there: when at the previous size it took more
than a quarter of --timeout (every preset grows at least linearly), or when 4x its previous peak
memory exceeds --max-mib.

    tools/bench_scalable.py [--dims 2 3] [--sizes2 80x40 ...] [--sizes3 40x20x10 ...]
                            [--presets scalable gmres-ilu0 mumps] [--set Model/G=0.01]
                            [--timeout 900] [--max-mib 12000] --out out/bench_scalable
"""
import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_solvers import csv_appender, run_polled  # noqa: E402

# The 3D block: 1 x 0.5 x 0.25, pinned as in docs/performance.md's preconditioner study.
SETS_3D = [
    "Discretization/Dimension=3", "Discretization/Lower Corner={0,0,0}", "Discretization/Upper Corner={1,0.5,0.25}",
    "Regions/pin/Lower={-1,0,0}", "Regions/pin/Upper={0,0.1,0.1}",
    "Regions/pin2/Type=Box", "Regions/pin2/Population=Fictitious", "Regions/pin2/Lower={-1,0.4,0}", "Regions/pin2/Upper={0,0.5,0.1}",
    "Boundary Conditions/pin z/Region=pin", "Boundary Conditions/pin z/Component=z",
    "Boundary Conditions/pin2 z/Region=pin2", "Boundary Conditions/pin2 z/Component=z",
    "Boundary Conditions/pull/Gradient={0.1,0,0}",
    "Reference/Gradient={0.1,0,0,0,-0.02819,0,0,0,-0.02819}", "Reference/Center={0,0.0125,0.0125}",
]


def run(perinox, scene, out, sets, timeout, np):
    cmd = ([] if np == 1 else ["mpirun", "-np", str(np), "--oversubscribe"]) + [perinox, "run", scene, "--output", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    env = dict(os.environ, PERINOX_PLOT_SCRIPT="", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    code, wall, rss, last = run_polled(cmd, timeout, env)
    if code == "timeout":
        return {"status": "timeout", "wall": wall, "rss_mib": rss}
    err = [last] if last else []
    try:
        with open(os.path.join(out, "summary.json")) as f:
            j = json.load(f)
    except OSError:
        return {"status": "failed: " + (err[-1][:120] if err else f"exit {code}"), "wall": wall, "rss_mib": rss}
    t = j.get("timing", {})
    solves = max(j.get("linear_solves_total", 0), 1)
    return {
        "status": "converged" if j["converged"] else "not converged",
        "wall": j["wall_time_s"], "setup": t.get("setup_s", float("nan")), "solve": t.get("solve_s", float("nan")),
        "residual": t.get("residual_evaluation_s", float("nan")),
        "newton_in_residuals": t.get("newton_iteration_in_residuals") or float("nan"),
        "solve_per_newton_in_residuals": t.get("solve_per_newton_iteration_in_residuals", float("nan")),
        "newton": j.get("newton_iterations_total", 0), "krylov_per_solve": j.get("krylov_iterations_total", 0) / solves,
        "rss_mib": max(j.get("peak_rss_mib_max_rank", 0), rss), "matrix_mib": j.get("matrix_bytes", 0) / 2**20,
        "particles": j.get("particles", 0),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default=os.path.join(ROOT, "xml", "tension_block.xml"))
    ap.add_argument("--dims", nargs="+", type=int, default=[2, 3])
    ap.add_argument("--sizes2", nargs="+", default=["80x40", "160x80", "320x160", "640x320", "1280x640"])
    ap.add_argument("--sizes3", nargs="+", default=["40x20x10", "60x30x15"])
    ap.add_argument("--presets", nargs="+", default=["scalable", "gmres-ilu0", "mumps"])
    ap.add_argument("--G", default="0.5")
    ap.add_argument("--horizon", default="3.015")
    ap.add_argument("--set", dest="sets", action="append", default=[])
    ap.add_argument("--np", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=900)
    ap.add_argument("--max-mib", type=float, default=12000)
    ap.add_argument("--tag", default="")
    ap.add_argument("--out", default="out/bench_scalable")
    ap.add_argument("--perinox", default=os.path.join(ROOT, "build", "drivers", "perinox"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    keys = ["tag", "dim", "lattice", "real_particles", "ranks", "preset", "status", "newton", "krylov_per_solve", "setup_s",
            "solve_s", "solve_us_per_particle", "residual_s", "newton_iteration_in_residuals",
            "solve_per_newton_iteration_in_residuals", "peak_rss_mib", "matrix_mib"]
    path = os.path.join(a.out, "bench_scalable.csv")
    w, f = csv_appender(path, keys)
    print(f"# {os.path.relpath(a.scene, ROOT)}, Silling G = {a.G}, delta = {a.horizon} dx, one load step, {a.np} rank(s) "
          f"{' '.join(a.sets)}")
    print(f"{'dim':>3} {'particles':>9} {'preset':>11} {'status':>10} {'Newton':>6} {'Krylov/solve':>12} {'set-up s':>8}"
          f" {'solve s':>8} {'us/particle':>11} {'Newton it / residual':>20} {'solve / Newton it / residual':>28}"
          f" {'peak MiB':>8} {'matrix MiB':>10}", flush=True)
    for dim in a.dims:
        sizes = a.sizes2 if dim == 2 else a.sizes3
        last = {}
        for size in sizes:
            n = [int(v) for v in size.split("x")]
            real = 1
            for v in n:
                real *= v
            for preset in a.presets:
                prev = last.get(preset)
                if prev and (prev["status"] != "converged" or prev["wall"] > a.timeout / 4 or 4 * prev["rss_mib"] > a.max_mib):
                    print(f"{dim:>3} {real:>9} {preset:>11} {'skipped':>10} (at {prev['particles_real']}: {prev['status']}, "
                          f"{prev['wall']:.0f} s, {prev['rss_mib']:.0f} MiB)", flush=True)
                    last[preset] = dict(prev, status="skipped")
                    continue
                sets = [f"Discretization/Particles={{{','.join(map(str, n))}}}", f"Discretization/Horizon Factor={a.horizon}",
                        "Model/Stabilization=Silling", f"Model/G={a.G}", "Solver/Load Steps=1",
                        f"Solver/Linear Solver Preset={preset}", "Output/Plots=false", "Output/VTK=false"]
                if dim == 3:
                    sets += SETS_3D
                out = os.path.join(a.out, f"{a.tag}{dim}d_{size}_{preset}_np{a.np}")
                r = run(a.perinox, a.scene, out, sets + a.sets, a.timeout, a.np)
                r["particles_real"] = real
                last[preset] = r
                row = {"tag": a.tag, "dim": dim, "lattice": size, "real_particles": real, "ranks": a.np, "preset": preset,
                       "status": r["status"], "peak_rss_mib": round(r["rss_mib"], 1)}
                if r["status"] in ("converged", "not converged"):
                    row.update({"newton": r["newton"], "krylov_per_solve": round(r["krylov_per_solve"], 2),
                                "setup_s": round(r["setup"], 3), "solve_s": round(r["solve"], 3),
                                "solve_us_per_particle": round(1e6 * r["solve"] / real, 2), "residual_s": r["residual"],
                                "newton_iteration_in_residuals": round(r["newton_in_residuals"], 1),
                                "solve_per_newton_iteration_in_residuals": round(r["solve_per_newton_in_residuals"], 1),
                                "matrix_mib": round(r["matrix_mib"], 1)})
                    print(f"{dim:>3} {real:>9} {preset:>11} {r['status']:>10} {r['newton']:>6} {r['krylov_per_solve']:>12.1f}"
                          f" {r['setup']:>8.2f} {r['solve']:>8.2f} {row['solve_us_per_particle']:>11.1f}"
                          f" {r['newton_in_residuals']:>20.1f} {r['solve_per_newton_in_residuals']:>28.1f}"
                          f" {r['rss_mib']:>8.0f} {r['matrix_mib']:>10.1f}", flush=True)
                else:
                    print(f"{dim:>3} {real:>9} {preset:>11} {r['status'][:40]:>10} after {r['wall']:.0f} s, {r['rss_mib']:.0f} MiB",
                          flush=True)
                w.writerow(row)
                f.flush()
    f.close()
    print(f"# rows appended to {path}")


if __name__ == "__main__":
    main()
