#!/usr/bin/env python3
"""Weak scaling of the linear-solver presets on a damaged state (issue 19): the plate with a hole
(xml/plate_hole_damage.xml, G = 0.5, delta = 3.015 dx) after bonds broke, at lattices x4 a row.

Per size: (1) MUMPS runs the damage scene from the start for --steps-before steps and writes a
checkpoint there (past the first breaks and, at every size tried, a stall break: the table says
how many bonds were broken by then); (2) each preset resumes that checkpoint and runs
--steps-after more steps (softening bonds, more breaks, stall events: the tangents the issue
calls damaged). Per row: Newton iterations, Krylov iterations per linear solve, solve wall time
per Newton iteration, the cost of a Newton iteration in residual evaluations (the run's own
summary.json "timing", measured in the same run), peak memory, and the bonds broken in the
measured steps. Prints a table, appends CSV; asserts nothing. Single runs on a shared machine.

    tools/bench_damaged.py [--sizes 60x20 120x40 240x80] [--presets mumps scalable gmres-ilu0]
                           [--steps-before 20] [--steps-after 5] [--timeout 1800] --out out/bench_damaged
"""
import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_solvers import csv_appender, run_polled  # noqa: E402

ENV = dict(os.environ, PERINOX_PLOT_SCRIPT="", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def run(cmd, timeout):
    """(exit code or "timeout", wall seconds, peak RSS MiB, last stderr line)."""
    return run_polled(cmd, timeout, ENV)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default=os.path.join(ROOT, "xml", "plate_hole_damage.xml"))
    ap.add_argument("--sizes", nargs="+", default=["60x20", "120x40", "240x80"])
    ap.add_argument("--presets", nargs="+", default=["mumps", "scalable", "gmres-ilu0"])
    ap.add_argument("--steps-before", type=int, default=20)
    ap.add_argument("--steps-after", type=int, default=5)
    ap.add_argument("--set", dest="sets", action="append", default=[])
    ap.add_argument("--timeout", type=float, default=1800)
    ap.add_argument("--perinox", default=os.path.join(ROOT, "build", "drivers", "perinox"))
    ap.add_argument("--out", default="out/bench_damaged")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    keys = ["lattice", "particles", "preset", "status", "bonds_broken_before", "steps", "newton", "krylov_per_solve",
            "solve_s", "s_per_newton", "newton_iteration_in_residuals", "peak_rss_mib", "bonds_broken_measured"]
    path = os.path.join(a.out, "bench_damaged.csv")
    w, f = csv_appender(path, keys)
    print(f"# {os.path.relpath(a.scene, ROOT)}: checkpoint after {a.steps_before} steps (MUMPS), then "
          f"{a.steps_after} steps per preset; {' '.join(a.sets)}")
    print(f"{'lattice':>8} {'particles':>9} {'preset':>11} {'status':>10} {'broken<':>7} {'Newton':>6} {'Krylov/solve':>12}"
          f" {'solve s':>8} {'s/Newton':>8} {'Newton/residual':>15} {'peak MiB':>8} {'broken':>6}", flush=True)
    for size in a.sizes:
        n = [int(v) for v in size.split("x")]
        sets = [f"Discretization/Particles={{{','.join(map(str, n))}}}", "Output/Plots=false", "Output/VTK=false"] + a.sets
        setArgs = [x for s in sets for x in ("--set", s)]
        # (1) the damaged state: MUMPS from the start, a checkpoint at the last step.
        first = os.path.join(a.out, f"{size}_before")
        ckpt = first + ".checkpoint"
        code, wall, rss, err = run([a.perinox, "run", a.scene, "--output", first, "--quiet", "--checkpoint-steps",
                                    str(a.steps_before), "--checkpoint-dir", ckpt] + setArgs +
                                   ["--set", "Solver/Linear Solver Preset=mumps",
                                    "--set", f"Solver/Max Total Steps={a.steps_before}"], a.timeout)
        if not os.path.exists(os.path.join(ckpt, "state.json")):
            print(f"{size:>8} no checkpoint after {wall:.0f} s (exit {code}: {err})", flush=True)
            continue
        with open(os.path.join(first, "summary.json")) as g:
            before = json.load(g)
        brokenBefore = before.get("broken_bonds_total", 0)
        particles = before.get("particles", 0)
        with open(os.path.join(ckpt, "state.json")) as g:
            step0 = json.load(g)["step"]
        # (2) each preset from the checkpoint.
        for preset in a.presets:
            out = os.path.join(a.out, f"{size}_{preset}")
            code, wall, rss, err = run([a.perinox, "run", a.scene, "--output", out, "--quiet", "--restart", ckpt] + setArgs +
                                       ["--set", f"Solver/Linear Solver Preset={preset}",
                                        "--set", f"Solver/Max Total Steps={step0 + a.steps_after}"], a.timeout)
            row = {"lattice": size, "particles": particles, "preset": preset, "bonds_broken_before": brokenBefore,
                   "peak_rss_mib": round(rss, 1)}
            try:
                with open(os.path.join(out, "summary.json")) as g:
                    j = json.load(g)
            except OSError:
                row["status"] = "timeout" if code == "timeout" else f"failed ({err[:60]})"
                print(f"{size:>8} {particles:>9} {preset:>11} {row['status']} after {wall:.0f} s", flush=True)
                w.writerow(row)
                f.flush()
                continue
            steps = [s for s in j["steps"] if s.get("step", 0) > step0] or j["steps"][-a.steps_after:]
            newton = sum(s["newton_iterations_all_attempts"] for s in steps)
            solves = max(sum(s["linear_solves"] for s in steps), 1)
            krylov = sum(s["krylov_iterations"] for s in steps)
            t = j.get("timing", {})
            solve = t.get("solve_s", float("nan"))
            row.update({"status": "ran" if code in (0, 3) else f"exit {code}", "steps": len(steps), "newton": newton,
                        "krylov_per_solve": round(krylov / solves, 2), "solve_s": round(solve, 2),
                        "s_per_newton": round(solve / newton, 3) if newton else float("nan"),
                        "newton_iteration_in_residuals": round(t.get("newton_iteration_in_residuals") or float("nan"), 1),
                        "peak_rss_mib": round(max(rss, j.get("peak_rss_mib_max_rank", 0)), 1),
                        "bonds_broken_measured": sum(s["broken_bonds"] for s in steps)})
            print(f"{size:>8} {particles:>9} {preset:>11} {row['status']:>10} {brokenBefore:>7} {newton:>6}"
                  f" {row['krylov_per_solve']:>12.1f} {row['solve_s']:>8.1f} {row['s_per_newton']:>8.3f}"
                  f" {row['newton_iteration_in_residuals']:>15.1f} {row['peak_rss_mib']:>8.0f} {row['bonds_broken_measured']:>6}",
                  flush=True)
            w.writerow(row)
            f.flush()
    f.close()
    print(f"# rows appended to {path}")


if __name__ == "__main__":
    main()
