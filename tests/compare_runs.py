#!/usr/bin/env python3
"""Compares the probes of several perinox runs (e.g. on 1, 2 and 3 MPI ranks).

    compare_runs.py --rtol R DIR_REF DIR...

Every probe value at every load step must agree with the reference run to R relative (to the
largest magnitude of that probe), and the runs must have the same load factors. --scale S
multiplies the other runs' probes by S first (e.g. 1000 to compare metres with millimetres).
"""
import argparse
import csv
import json
import os
import sys


def load(d):
    with open(os.path.join(d, "summary.json")) as f:
        return json.load(f)


def damage_index(d):
    """Particle id -> damage index of the final state (fields.csv)."""
    with open(os.path.join(d, "fields.csv")) as f:
        rows = list(csv.DictReader(f))
    return {int(r["id"]): float(r["damage"]) for r in rows}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rtol", type=float, required=True)
    ap.add_argument("--scale", type=float, default=1.0,
                    help="multiply the probes of every run but the first by this (unit changes)")
    ap.add_argument("--final-only", action="store_true",
                    help="compare only the final state (runs may take different load steps)")
    ap.add_argument("--same-iterations", action="store_true",
                    help="also require the same load steps and Newton iterations per step")
    ap.add_argument("--load-factor-tol", type=float, default=1e-14,
                    help="load factors must agree to this (absolute); arc-length runs solve for them")
    ap.add_argument("--same-damage", action="store_true",
                    help="also require the same bonds broken in every step and the same damage index "
                         "of every particle (fields.csv, to 1e-12)")
    ap.add_argument("--fewer-krylov", action="store_true",
                    help="each run after the first took fewer Krylov iterations in all than the first")
    ap.add_argument("dirs", nargs="+")
    a = ap.parse_args()
    ref = load(a.dirs[0])
    worst = 0.0
    for d in a.dirs[1:]:
        s = load(d)
        for name, hist in ref["probes"].items():
            other = s["probes"].get(name)
            if a.final_only and other:
                hist, other = hist[-1:], other[-1:]
            if other is None or len(other) != len(hist):
                print(f"FAILED: probe {name} differs in length in {d}")
                sys.exit(1)
            key = next(k for k in hist[0] if k != "load_factor")
            scale = max(max(abs(v) for v in h[key]) for h in hist) or 1.0
            for h, o in zip(hist, other):
                if abs(h["load_factor"] - o["load_factor"]) > a.load_factor_tol:
                    print(f"FAILED: load factors differ in {d}")
                    sys.exit(1)
                for x, y in zip(h[key], o[key]):
                    worst = max(worst, abs(x - a.scale * y) / scale)
        if a.same_iterations:
            its = [st["newton_iterations"] for st in ref["steps"]]
            other_its = [st["newton_iterations"] for st in s["steps"]]
            print(f"Newton iterations per step: {its} and {other_its}")
            # A step that both runs converged at the round-off floor (|R| at the level of the
            # residual's rounding, after the body came apart) may take one iteration more or
            # less: whether the floor is met before or after one more iteration is decided by
            # the last digits of the linear solves.
            floor = [st.get("converged_at_roundoff_floor", False) and ot.get("converged_at_roundoff_floor", False)
                     for st, ot in zip(ref["steps"], s["steps"])]
            differ = [k for k, (i, j) in enumerate(zip(its, other_its))
                      if i != j and not (floor[k] and abs(i - j) <= 1)]
            if len(its) != len(other_its) or differ:
                print(f"FAILED: Newton iterations differ in {d}" + (f" (step {differ[0] + 1})" if differ else ""))
                sys.exit(1)
            loose = sum(1 for k, (i, j) in enumerate(zip(its, other_its)) if i != j)
            if loose:
                print(f"{loose} step(s) at the round-off floor differ by one iteration")
        if a.same_damage:
            broken = [st["broken_bonds"] for st in ref["steps"]]
            other_broken = [st["broken_bonds"] for st in s["steps"]]
            if broken != other_broken:
                print(f"FAILED: bonds broken per step differ in {d}: {broken} and {other_broken}")
                sys.exit(1)
            mine, theirs = damage_index(a.dirs[0]), damage_index(d)
            if mine.keys() != theirs.keys() or any(abs(mine[k] - theirs[k]) > 1e-12 for k in mine):
                print(f"FAILED: the damage index of some particle differs in {d}")
                sys.exit(1)
            print(f"{d}: {sum(broken)} bonds broken in the same steps, damage index equal at {len(mine)} particles")
        if a.fewer_krylov:
            k0, k1 = ref.get("krylov_iterations_total", 0), s.get("krylov_iterations_total", 0)
            print(f"Krylov iterations: {k0} and {k1}")
            if not k1 < k0:
                print(f"FAILED: {d} did not take fewer Krylov iterations than {a.dirs[0]}")
                sys.exit(1)
        print(f"{d}: ranks {s['ranks']}, partition {s.get('partition', {}).get('method')}")
    print(f"largest relative difference {worst:.3e} (tolerance {a.rtol})")
    if worst > a.rtol:
        print("FAILED")
        sys.exit(1)
    print("PASSED")


if __name__ == "__main__":
    main()
