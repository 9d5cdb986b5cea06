#!/usr/bin/env python3
"""Linear solvers compared on the same stretch of a load path: each (preset, ranks) case resumes
the same checkpoint and runs the same steps; the table gives wall time, Newton iterations of every
attempt, and the median seconds per Newton iteration over the steps (each step's time includes its
failed attempts, so this is the cost of one iteration where the work is). Ratios are to the first
case, measured in this run. Single runs on a shared machine; asserts nothing.

    tools/bench_restart_solvers.py SCENE --restart CHECKPOINT --steps K
        [--set KEY=VALUE ...] [--cases mumps:1 mumps:2 gmres-ilu0:2 direct:1] --out out/bench_restart

Without --restart the cases run the scene from its start (for K steps).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--restart", default=None)
    ap.add_argument("--steps", type=int, required=True, help="steps to run after the checkpoint")
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--cases", nargs="+", default=["mumps:1", "mumps:2", "gmres-ilu0:2", "direct:1"])
    ap.add_argument("--perinox", default=os.path.join(ROOT, "build", "drivers", "perinox"))
    ap.add_argument("--out", required=True)
    a = ap.parse_args()

    first = 0
    if a.restart:
        with open(os.path.join(a.restart, "state.json")) as f:
            first = json.load(f)["step"]
    env = dict(os.environ, PERINOX_PLOT_SCRIPT="", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    rows = []
    for case in a.cases:
        preset, np = case.split(":")
        out = os.path.join(a.out, f"{preset}_np{np}")
        cmd = ["mpirun", "--oversubscribe", "-np", np, a.perinox, "run", a.scene, "--output", out, "--quiet",
               "--set", f"Solver/Linear Solver Preset={preset}", "--set", f"Solver/Max Total Steps={first + a.steps}"]
        for s in a.set:
            cmd += ["--set", s]
        if a.restart:
            cmd += ["--restart", a.restart]
        t0 = time.time()
        subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
        wall = time.time() - t0
        try:
            with open(os.path.join(out, "summary.json")) as f:
                j = json.load(f)
        except OSError:
            rows.append((case, wall, None, None, None, "no summary"))
            continue
        steps = [s for s in j["steps"] if s["step"] > first]
        iters = sum(s["newton_iterations_all_attempts"] for s in steps)
        per = [s["time_s"] / s["newton_iterations_all_attempts"] for s in steps if s["newton_iterations_all_attempts"] > 0]
        last = steps[-1]["load_factor"] if steps else float("nan")
        rows.append((case, sum(s["time_s"] for s in steps), iters, statistics.median(per) if per else None, last,
                     f"{len(steps)} steps, {sum(s['broken_bonds'] for s in steps)} bonds broken"))
    print(f"scene {a.scene}, {'checkpoint ' + a.restart + ' (after step %d), ' % first if a.restart else ''}"
          f"{a.steps} steps, sets {a.set}")
    print(f"{'case':16s} {'steps s':>9s} {'ratio':>6s} {'Newton':>7s} {'s/Newton':>9s} {'ratio':>6s} {'load':>9s}  notes")
    base = rows[0]
    for case, t, it, per, lam, note in rows:
        if it is None:
            print(f"{case:16s} {t:9.1f}  {note}")
            continue
        r1 = t / base[1] if base[1] else float("nan")
        r2 = per / base[3] if per and base[3] else float("nan")
        print(f"{case:16s} {t:9.1f} {r1:6.2f} {it:7d} {per:9.3f} {r2:6.2f} {lam:9.6f}  {note}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
