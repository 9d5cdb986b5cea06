#!/usr/bin/env python3
"""The Two-Stage preconditioner keeps its multigrid hierarchy while the auxiliary operator does
not change (summary.json "preconditioner").

    check_preconditioner.py --hierarchies N RUN_DIR    exactly N hierarchies built (lattice FEM: 1 a run)
    check_preconditioner.py --damage RUN_DIR           short horizon: at most one more hierarchy per
                                                       damage event (a break round, a step whose
                                                       bonds broke, a stall break) than the first

    check_preconditioner.py --eigenvalue-products FIRST WARM RUN_DIR
                                                       matrix-free smoother: FIRST power iterations at
                                                       the first set-up, WARM at each later one
    check_preconditioner.py --own-diagonal RUN_DIR     the matrix-free smoother scaled by the operator's
                                                       own diagonal at every set-up
    check_preconditioner.py --fine-smoothed all|none RUN_DIR
                                                       a hierarchy of more than one level was built,
                                                       and MueLu smooths its finest level in every
                                                       one (all) or in none (none): "Auxiliary Fine
                                                       Smoothing" = Auto smooths there only with damage
    check_preconditioner.py --krylov-within F REF_DIR RUN_DIR
                                                       Krylov iterations per linear solve of RUN_DIR at
                                                       most F times REF_DIR's

    check_preconditioner.py --kept-factors F RUN_DIR  the MUMPS preconditioner (preset gmres-mumps):
                                                       at most a fraction F of its set-ups factorised,
                                                       and at most F_max Krylov iterations per solve
                                                       (--max-per-solve, default 20); with
                                                       --self-assembled, every factorisation of a
                                                       matrix the operator assembled for it; with
                                                       --factor-precision single|double, factors of
                                                       that precision (summary.json factor_precision)

All also require one set-up per linear solve. Counts only.
"""
import argparse
import json
import os
import sys

ap = argparse.ArgumentParser()
ap.add_argument("--hierarchies", type=int)
ap.add_argument("--damage", action="store_true")
ap.add_argument("--eigenvalue-products", type=int, nargs=2, metavar=("FIRST", "WARM"))
ap.add_argument("--krylov-within", type=float)
ap.add_argument("--own-diagonal", action="store_true")
ap.add_argument("--fine-smoothed", choices=["all", "none"])
ap.add_argument("--kept-factors", type=float)
ap.add_argument("--max-per-solve", type=float, default=20.0)
ap.add_argument("--self-assembled", action="store_true")
ap.add_argument("--factor-precision", choices=["single", "double"])
ap.add_argument("runs", nargs="+")
a = ap.parse_args()
if len(a.runs) != (2 if a.krylov_within is not None else 1):
    ap.error("give one run directory, or a reference and a run with --krylov-within")
a.run = a.runs[-1]


def per_solve(run):
    with open(os.path.join(run, "summary.json")) as f:
        t = json.load(f)
    if t["linear_solves_total"] <= 0:
        print(f"FAILED: {run} made no linear solve")
        sys.exit(1)
    return t["krylov_iterations_total"] / t["linear_solves_total"]


with open(os.path.join(a.run, "summary.json")) as f:
    s = json.load(f)
p = s.get("preconditioner")
if a.kept_factors is not None:
    if not p or p.get("type") != "MUMPS":
        print("FAILED: no MUMPS preconditioner statistics in summary.json")
        sys.exit(1)
    solves = s["linear_solves_total"]
    per = s["krylov_iterations_total"] / max(solves, 1)
    print(f"set-ups {p['setups']}, factorisations {p['factorizations']}, linear solves {solves}, "
          f"Krylov iterations per solve {per:.2f}")
    if p["setups"] != solves or solves == 0:
        print("FAILED: set-ups differ from linear solves")
        sys.exit(1)
    if p["factorizations"] < 1 or p["factorizations"] > a.kept_factors * p["setups"]:
        print(f"FAILED: more than {a.kept_factors} of the set-ups factorised (or none)")
        sys.exit(1)
    if per > a.max_per_solve:
        print(f"FAILED: more than {a.max_per_solve} Krylov iterations per solve")
        sys.exit(1)
    if a.self_assembled:
        print(f"factorisations of a self-assembled matrix {p.get('self_assembled')}, matrix bytes held {s.get('matrix_bytes')}")
        if p.get("self_assembled") != p["factorizations"]:
            print("FAILED: a factorisation did not come from the matrix-free operator's own assembly")
            sys.exit(1)
    if a.factor_precision:
        print(f"factor precision {p.get('factor_precision')}, factor bytes {p.get('factor_bytes')}")
        if p.get("factor_precision") != a.factor_precision or not p.get("factor_bytes"):
            print(f"FAILED: expected {a.factor_precision}-precision factors")
            sys.exit(1)
    print("PASSED")
    sys.exit(0)
if not p:
    print("FAILED: no Two-Stage preconditioner statistics in summary.json")
    sys.exit(1)
print(f"set-ups {p['setups']}, hierarchies built {p['hierarchies_built']}, levels {p['levels']}, "
      f"linear solves {s['linear_solves_total']}")
if p["setups"] != s["linear_solves_total"]:
    print("FAILED: set-ups differ from linear solves")
    sys.exit(1)
if a.hierarchies is not None and p["hierarchies_built"] != a.hierarchies:
    print(f"FAILED: expected {a.hierarchies} hierarchies")
    sys.exit(1)
if a.damage:
    events = sum(st["break_rounds"] for st in s["steps"]) + sum(
        1 for st in s["steps"] if st["broken_bonds"] > 0 or st["stall_broken_bonds"] > 0) + s.get("stall_breaks", 0)
    if s.get("broken_bonds_total", 0) == 0:
        print("FAILED: no bond broke, so the damage path was not exercised")
        sys.exit(1)
    if p["hierarchies_built"] > 1 + events:
        print(f"FAILED: {p['hierarchies_built']} hierarchies for {events} damage events")
        sys.exit(1)
if a.eigenvalue_products is not None:
    first, warm = a.eigenvalue_products
    want = first + warm * (p["setups"] - 1)
    got = p.get("eigenvalue_products")
    print(f"eigenvalue products {got}, expected {want}")
    if got != want:
        print("FAILED: the matrix-free smoother's power iterations are not warm-started as configured")
        sys.exit(1)
if a.own_diagonal:
    got = p.get("operator_diagonals")
    print(f"set-ups scaled by the operator's own diagonal {got} of {p['setups']}")
    if got != p["setups"]:
        print("FAILED: the smoother fell back to another diagonal")
        sys.exit(1)
if a.fine_smoothed is not None:
    got = p.get("fine_smoothed_hierarchies")
    want = p["hierarchies_built"] if a.fine_smoothed == "all" else 0
    print(f"hierarchies with a smoothed finest level {got} of {p['hierarchies_built']}, expected {want}")
    if p["levels"] < 2:
        print("FAILED: a one-level hierarchy (the coarse solve alone) cannot show the finest level's smoother")
        sys.exit(1)
    if got != want:
        print("FAILED: the auxiliary hierarchy's finest level is not smoothed as 'Auxiliary Fine Smoothing' = Auto says")
        sys.exit(1)
    # An unsmoothed finest level is skipped by the cycle (entered at level 1); a smoothed one never is.
    entered = p.get("coarse_entry_hierarchies")
    want = 0 if a.fine_smoothed == "all" else p["hierarchies_built"]
    print(f"hierarchies whose cycle starts at level 1: {entered}, expected {want}")
    if entered != want:
        print("FAILED: the V-cycle does not skip the unsmoothed finest level's residual" if want else
              "FAILED: the V-cycle skipped a smoothed finest level")
        sys.exit(1)
if a.krylov_within is not None:
    ref, run = per_solve(a.runs[0]), per_solve(a.run)
    print(f"Krylov iterations per solve {run:.2f} against {ref:.2f} ({run / ref:.2f}x, at most {a.krylov_within}x)")
    if run > a.krylov_within * ref:
        print("FAILED: too many Krylov iterations per solve")
        sys.exit(1)
print("PASSED")
