#!/usr/bin/env python3
"""Memory and ghosts per rank against the rank count, slabs against Zoltan2 (issue 17).

Runs the perinox driver on a scene at 1, 2, 4, 8, 16 ranks (oversubscribed on this 2-core
machine: the figures of merit are memory and communicated data, not time) for each partition
method and prints, per row, the owned and ghost particles per rank (ghosts: what one halo
exchange brings to a rank), the peak resident memory of the largest and smallest rank, the
set-up time (rank 0, after barriers) and the issue's memory bound

    1.3 x (memory at 1 rank) / p + the ghost layer

where the ghost layer is ghosts_max x (memory at 1 rank) / particles. Memory is also shown above
the process floor (the peak RSS of a one-particle-row run: MPI, Kokkos and the Trilinos
libraries, paid by every rank whatever its share), because that floor, not the problem, is most of
a small scene's memory.

    tools/bench_distribution.py [--scene xml/plate_hole_damage.xml] [--set K=V]... [--ranks 1 2 4 8 16]
                                [--methods Slabs RCB] [--out out/bench_distribution] [--csv FILE]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(perinox, scene, out, sets, np, timeout):
    cmd = ["mpirun", "-np", str(np), "--oversubscribe", perinox, "run", scene, "--output", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    env = dict(os.environ, PERINOX_PLOT_SCRIPT="", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    t0 = time.time()
    try:
        p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"status": "timeout", "wall": time.time() - t0}
    try:
        with open(os.path.join(out, "summary.json")) as f:
            j = json.load(f)
    except OSError:
        err = p.stderr.decode(errors="replace").strip().splitlines()
        return {"status": "failed: " + (err[-1][:100] if err else f"exit {p.returncode}"), "wall": time.time() - t0}
    part = j.get("partition", {})
    return {"status": "converged" if j["converged"] else "not converged", "wall": j["wall_time_s"],
            "setup": j.get("timing", {}).get("setup_s", float("nan")), "particles": j.get("particles", 0),
            "owned_max": part.get("owned_max", 0), "ghosts_max": part.get("ghosts_max", 0),
            "ghosts_mean": part.get("ghosts_mean", 0), "rss_max": j.get("peak_rss_mib_max_rank", 0),
            "rss_min": part.get("peak_rss_mib_min_rank", 0), "method": part.get("method", "?")}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--perinox", default=os.path.join(ROOT, "build", "drivers", "perinox"))
    ap.add_argument("--scene", default=os.path.join(ROOT, "xml", "plate_hole_damage.xml"))
    ap.add_argument("--set", dest="sets", action="append", default=[])
    ap.add_argument("--ranks", nargs="+", type=int, default=[1, 2, 4, 8, 16])
    ap.add_argument("--methods", nargs="+", default=["Slabs", "RCB"])
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench_distribution"))
    ap.add_argument("--csv")
    ap.add_argument("--timeout", type=float, default=3600)
    a = ap.parse_args()
    common = ["Output/Plots=false", "Output/VTK=false"] + a.sets
    floor = run(a.perinox, os.path.join(ROOT, "xml", "bar1d_variable_modulus.xml"), os.path.join(a.out, "floor"),
                ["Output/Plots=false", "Output/VTK=false"], 1, 600)
    base = floor.get("rss_max", 0.0)
    print(f"# {os.path.relpath(a.scene, ROOT)} {' '.join(a.sets)}")
    print(f"# process floor (1D bar, one rank): {base:.0f} MiB peak RSS")
    print(f"{'method':>6} {'ranks':>5} {'owned_max':>9} {'ghosts_max':>10} {'ghosts_mean':>11} {'rss_max':>8} {'rss_min':>8}"
          f" {'bound':>8} {'max/bound':>9} {'above floor':>11} {'bound-floor':>11} {'ratio':>6} {'setup s':>8} {'wall s':>7}")
    rows = []
    one = {}
    for method in a.methods:
        for np in a.ranks:
            out = os.path.join(a.out, f"{method.lower()}_np{np}")
            r = run(a.perinox, a.scene, out, common + [f"Discretization/Partition={method}"], np, a.timeout)
            if r["status"] != "converged":
                print(f"{method:>6} {np:>5} {r['status']} after {r['wall']:.0f} s")
                continue
            if np == 1:
                one = r
            if not one:
                one = r  # no 1-rank row: bound against this row (marked)
            n = max(r["particles"], 1)
            ghost_layer = r["ghosts_max"] * one["rss_max"] / n
            bound = 1.3 * one["rss_max"] / np + ghost_layer
            above = r["rss_max"] - base
            bound_floor = 1.3 * (one["rss_max"] - base) / np + r["ghosts_max"] * (one["rss_max"] - base) / n
            row = dict(method=method, ranks=np, owned_max=int(r["owned_max"]), ghosts_max=int(r["ghosts_max"]),
                       ghosts_mean=round(r["ghosts_mean"], 1), rss_max_mib=round(r["rss_max"], 1),
                       rss_min_mib=round(r["rss_min"], 1), bound_mib=round(bound, 1),
                       ratio=round(r["rss_max"] / bound, 3), above_floor_mib=round(above, 1),
                       bound_above_floor_mib=round(bound_floor, 1),
                       ratio_above_floor=round(above / bound_floor, 3) if bound_floor > 0 else float("nan"),
                       setup_s=round(r["setup"], 2), wall_s=round(r["wall"], 1), floor_mib=round(base, 1))
            rows.append(row)
            print(f"{method:>6} {np:>5} {row['owned_max']:>9} {row['ghosts_max']:>10} {row['ghosts_mean']:>11}"
                  f" {row['rss_max_mib']:>8.0f} {row['rss_min_mib']:>8.0f} {row['bound_mib']:>8.0f} {row['ratio']:>9.2f}"
                  f" {row['above_floor_mib']:>11.0f} {row['bound_above_floor_mib']:>11.0f} {row['ratio_above_floor']:>6.2f}"
                  f" {row['setup_s']:>8.2f} {row['wall_s']:>7.1f}", flush=True)
        one = {}
    if a.csv and rows:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
