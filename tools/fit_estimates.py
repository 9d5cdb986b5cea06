#!/usr/bin/env python3
"""Fits the power laws of perinox check's estimate (estimateRun in packages/solver/src/
AutoLinearSolver.cpp) to the runs of tools/bench_auto.py, and prints them with their spread.

For each run: w = particles x (bonds + 1), with the bonds of a lattice ball of the run's horizon
factor (as estimateRun counts them); the peak resident memory above 75 MiB and the wall time of
one Newton iteration (the run's wall time over its Newton iterations). Per kind of choice (direct:
direct and mumps; kept: gmres-mumps; free: scalable matrix-free; assembled: scalable assembled)
and dimension (1D and 2D together, 3D), a least-squares line in log-log over the runs that measure
the solver rather than the start-up (30 MiB above the base, 1 s in all); in 3D, whose runs span a
narrow range, 2D's exponents with coefficients through the 3D runs. Prints the fits as C++
initialisers and, per run, estimate over measurement; asserts nothing.

    tools/fit_estimates.py [--bench out/bench_auto] [--perinox build/drivers/perinox]
"""
import argparse
import csv
import json
import math
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_auto  # noqa: E402

KIND = {"direct": "direct", "mumps": "direct", "gmres-mumps": "kept", "gmres-mumps+mf": "kept",
        "scalable+mf+ew": "free", "scalable-weak+mf+ew": "free", "scalable+mf": "free", "scalable": "assembled"}


def bonds(dim, h):
    return 2 * h if dim == 1 else math.pi * h * h if dim == 2 else 4.0 / 3.0 * math.pi * h ** 3


def geometry(perinox, scene, sets):
    """(dimension, particles, horizon factor) from perinox check."""
    cmd = [perinox, "check", scene]
    for s in sets:
        cmd += ["--set", s]
    out = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, PERINOX_PLOT_SCRIPT="")).stdout
    m = re.search(r"(\d)D, (\d+) particles .*horizon ([0-9.eE+-]+), spacing ([0-9.eE+-]+)", out)
    if not m:
        return None
    return int(m.group(1)), int(m.group(2)), float(m.group(3)) / float(m.group(4))


def line(points):
    """Least squares of log y = log a + b log x: (a, b)."""
    xs = [math.log(x) for x, _ in points]
    ys = [math.log(y) for _, y in points]
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else 1.0
    return math.exp(my - b * mx), b


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bench", default=os.path.join(ROOT, "out", "bench_auto"))
    ap.add_argument("--perinox", default=os.path.join(ROOT, "build", "drivers", "perinox"))
    a = ap.parse_args()
    rows = bench_auto.rows(os.path.join(a.bench, "scenes"))
    geo = {}
    data = {}
    with open(os.path.join(a.bench, "bench_auto.csv")) as f:
        for r in csv.DictReader(f):
            kind = KIND.get(r["config"])
            if not kind or r["status"] not in ("converged", "not converged") or not r["newton"] or int(r["newton"]) == 0:
                continue
            if r["row"] not in rows:
                continue
            if r["row"] not in geo:
                geo[r["row"]] = geometry(a.perinox, rows[r["row"]][0], rows[r["row"]][1])
            g = geo[r["row"]]
            if not g:
                continue
            dim, particles, h = g
            w = particles * (bonds(dim, h) + 1)
            key = (kind, 3 if dim == 3 else 2)
            data.setdefault(key, []).append((r["row"], r["config"], w, float(r["peak_mib"]) - 75.0,
                                             float(r["wall_s"]) / int(r["newton"]), float(r["wall_s"])))
    print("constexpr Fit kFits[2][4] = {  // {a, b, c, d}: peak = 75 + a w^b MiB, Newton iteration = c w^d s")
    fits2 = []
    for dim in (2, 3):
        fits = []
        for kind in ("direct", "kept", "free", "assembled"):
            pts = data.get((kind, dim), [])
            # Runs that measure the solver, not the start-up: 30 MiB above the base, 1 s in all.
            mem = [(w, m) for _, _, w, m, _, _ in pts if m > 30]
            tim = [(w, t) for _, _, w, _, t, wall in pts if wall > 1.0]
            # 2D: a line in log-log. 3D (a narrow range of w, few runs): 2D's exponent, the
            # coefficient through the 3D runs; so also where 2D has fewer than three runs.
            am, bm = line(mem) if len(mem) >= 3 and dim == 2 else (None, None)
            at, bt = line(tim) if len(tim) >= 3 and dim == 2 else (None, None)
            fits.append([kind, am, bm, at, bt, pts, mem, tim])
        for f in fits:  # no line fitted: the 2D fit's exponent through the runs there are
            kind, am, bm, at, bt, pts, mem, tim = f
            ref = next((g for g in fits2 if g[0] == kind), None) if dim == 3 else None
            if am is None:
                bm = ref[2] if ref else 1.0
                am = math.exp(sum(math.log(m) - bm * math.log(w) for w, m in mem) / len(mem)) if mem else (ref[1] if ref else 1e-3)
            if at is None:
                bt = ref[4] if ref else 1.0
                at = math.exp(sum(math.log(t) - bt * math.log(w) for w, t in tim) / len(tim)) if tim else (ref[3] if ref else 1e-6)
            f[1:5] = [am, bm, at, bt]
        if dim == 2:
            fits2 = fits
        print(f"    // {dim}D: " + ", ".join(k for k, *_ in fits))
        print("    {" + ", ".join(f"{{{am:.3g}, {bm:.3g}, {at:.3g}, {bt:.3g}}}" for _, am, bm, at, bt, *_ in fits) + "},")
        for kind, am, bm, at, bt, pts, *_ in fits:
            for row, config, w, m, t, _ in pts:
                em, et = am * w ** bm, at * w ** bt
                print(f"      {dim}D {kind:9} {row:34} {config:16} w {w:10.3g}  memory est/meas {em + 75:8.0f}/{m + 75:6.0f} MiB"
                      f" ({(em + 75) / (m + 75):5.2f})  Newton est/meas {et:8.3g}/{t:8.3g} s ({et / t:5.2f})")
    print("};")


if __name__ == "__main__":
    main()
